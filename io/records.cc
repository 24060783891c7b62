#include "io/records.h"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <map>
#include <numbers>
#include <sstream>
#include <tuple>

#include "io/bench_data.h"
#include "io/csv.h"
#include "io/fin_records.h"
#include "io/quantum.h"
#include "model/format.h"
#include "model/status.h"

namespace pz::io {
namespace fs = std::filesystem;
using model::CaseRole;

const char* OffsetModeName(OffsetMode m) {
  switch (m) {
    case OffsetMode::kFit:
      return "fit";
    case OffsetMode::kRest:
      return "rest";
    case OffsetMode::kFixed:
      return "fixed";
  }
  return "?";
}

std::string Record::Label() const {
  std::ostringstream s;
  s << model::CaseRoleName(role) << " record '" << name << "' (" << file.filename().string();
  if (!t.empty()) {
    s << ", " << FormatNumber(t[first_scored]) << "–" << FormatNumber(t[end_scored - 1]) << " s";
  }
  s << ")";
  return s.str();
}

std::vector<const Record*> RecordSet::WithRole(CaseRole role) const {
  std::vector<const Record*> out;
  for (const Record& r : records)
    if (r.role == role) out.push_back(&r);
  return out;
}

const Record* RecordSet::Find(std::string_view name) const {
  for (const Record& r : records)
    if (r.name == name) return &r;
  return nullptr;
}

UnitConversion ConvertUnit(std::string_view unit) {
  struct Row {
    const char* name;
    const char* canonical;
    double factor;
    const char* quantity;
  };
  static const Row kTable[] = {
      {"s", "s", 1, "time"},       {"ms", "s", 1e-3, "time"},
      {"us", "s", 1e-6, "time"},   {"µs", "s", 1e-6, "time"},
      {"V", "V", 1, "voltage"},    {"mV", "V", 1e-3, "voltage"},
      {"kV", "V", 1e3, "voltage"}, {"m", "um", 1e6, "length"},
      {"mm", "um", 1e3, "length"}, {"um", "um", 1, "length"},
      {"µm", "um", 1, "length"},   {"nm", "um", 1e-3, "length"},
      {"deg", "deg", 1, "angle"},  {"rad", "deg", 180 / std::numbers::pi, "angle"},
      {"N", "N", 1, "force"},
  };
  for (const Row& r : kTable)
    if (unit == r.name) return {r.canonical, r.factor, r.quantity};
  return {std::string(unit), 1, std::string(unit)};
}

namespace {

std::string SuffixUnit(const std::string& column) {
  const size_t p = column.rfind('_');
  if (p == std::string::npos || p + 1 >= column.size()) return "";
  return column.substr(p + 1);
}

bool ValidName(const std::string& s) {
  if (s.empty() || s.size() > 100) return false;
  for (char c : s)
    if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_' || c == '.'))
      return false;
  return true;
}

/// A loaded file, shared by the manifest rows that use it.
struct FileData {
  std::vector<double> t, u, y;
  double dt = 0;
  UnitConversion drive, response;
  size_t rest = 0;
  double quantum = 0;
};

struct ColumnSpec {
  std::string time = "t_s", drive = "voltage_V", response = "displacement_um";
  std::string time_unit, drive_unit, response_unit;  // declared in the manifest (may be empty)
};

UnitConversion ResolveUnit(const CsvTable& csv, const std::string& column,
                           const std::string& declared, const std::string& where_declared,
                           const char* what) {
  const std::string suffix = SuffixUnit(column);
  std::string unit = declared;
  const bool suffix_is_unit = !suffix.empty() && ConvertUnit(suffix).quantity != suffix;
  if (!declared.empty() && suffix_is_unit &&
      (ConvertUnit(suffix).canonical != ConvertUnit(declared).canonical ||
       ConvertUnit(suffix).factor != ConvertUnit(declared).factor)) {
    throw InputError(csv.source + ":" + std::to_string(csv.header_line) +
                     ": mismatched units: column '" + column + "' says " + suffix + " but " +
                     where_declared + " declares " + declared);
  }
  if (unit.empty()) unit = suffix;
  if (unit.empty()) {
    throw InputError(csv.source + ":" + std::to_string(csv.header_line) + ": the unit of the " +
                     what + " column '" + column +
                     "' is not declared (name it <name>_<unit>, e.g. " +
                     (std::string(what) == "time"    ? "t_s"
                      : std::string(what) == "drive" ? "voltage_V"
                                                     : "displacement_um") +
                     ", or give " + what + "_unit in the manifest)");
  }
  return ConvertUnit(unit);
}

// A record file's CSV. A file without a header line (its first line is data, e.g. a
// recorder's export) is refused with the fix: the columns' names and units are what the reader
// goes by.
CsvTable ReadRecordCsv(const fs::path& file) {
  const std::string text = ReadTextFile(file);
  const size_t start = text.compare(0, 3, "\xEF\xBB\xBF") == 0 ? 3 : 0;
  const size_t eol = text.find('\n', start);
  std::string first =
      text.substr(start, eol == std::string::npos ? std::string::npos : eol - start);
  if (!first.empty() && first.back() == '\r') first.pop_back();
  int numbers = 0, words = 0;
  for (size_t a = 0; a <= first.size();) {
    size_t b = first.find(',', a);
    if (b == std::string::npos) b = first.size();
    std::string f = first.substr(a, b - a);
    f.erase(0, f.find_first_not_of(" \t"));
    f.erase(f.find_last_not_of(" \t") + 1);
    if (!f.empty()) ++(ParseDouble(f) ? numbers : words);
    a = b + 1;
  }
  if (numbers > 0 && words == 0) {
    throw InputError(
        file.string() + ":1: no header line (the first line is data: '" + first.substr(0, 60) +
        "'): add a header that names the columns with their units, e.g. "
        "t_s,voltage_V,displacement_um "
        "(name an empty column too, e.g. unused), or name the columns in a manifest.csv "
        "(time_column, drive_column, response_column; docs/records.md)");
  }
  return ParseCsv(text, file.string());
}

// The rest segment (the leading samples whose drive equals the first one, within the tolerance)
// and the response's quantum of a file's samples.
void FinishFileData(FileData& d, const RecordReadOptions& opt) {
  double umax = 0;
  for (double v : d.u) umax = std::max(umax, std::abs(v));
  const double tol = opt.rest_tolerance * umax + 1e-12;
  d.rest = 1;
  while (d.rest < d.u.size() && std::abs(d.u[d.rest] - d.u[0]) <= tol) ++d.rest;
  d.quantum = EstimateQuantum(d.y);
}

FileData ReadRecordFile(const fs::path& file, const ColumnSpec& cols, const RecordReadOptions& opt,
                        const std::string& where_declared) {
  const CsvTable csv = ReadRecordCsv(file);
  csv.RequireColumns({cols.time, cols.drive, cols.response});
  const int ct = csv.RequireColumn(cols.time), cu = csv.RequireColumn(cols.drive),
            cy = csv.RequireColumn(cols.response);
  FileData d;
  const UnitConversion tu = ResolveUnit(csv, cols.time, cols.time_unit, where_declared, "time");
  if (tu.quantity != "time") {
    throw InputError(csv.source + ":" + std::to_string(csv.header_line) +
                     ": mismatched units: the time column '" + cols.time + "' is in " +
                     tu.canonical + ", not a time (s, ms, us)");
  }
  d.drive = ResolveUnit(csv, cols.drive, cols.drive_unit, where_declared, "drive");
  d.response = ResolveUnit(csv, cols.response, cols.response_unit, where_declared, "response");
  const size_t n = csv.rows.size();
  if (n < 2) {
    throw InputError(csv.source + ": " + std::to_string(n) +
                     " data rows; a record needs at least " +
                     std::to_string(std::max<size_t>(2, opt.min_scored)) + " samples (too short)");
  }
  d.t.resize(n);
  d.u.resize(n);
  d.y.resize(n);
  for (size_t i = 0; i < n; ++i) {
    d.t[i] = csv.Number(i, ct) * tu.factor;
    d.u[i] = csv.Number(i, cu) * d.drive.factor;
    d.y[i] = csv.Number(i, cy) * d.response.factor;
    // A finite number can leave the doubles in its unit's conversion (1e306 kV): named, not inf.
    for (const auto& [value, col, unit] :
         {std::tuple{d.t[i], ct, tu.canonical}, std::tuple{d.u[i], cu, d.drive.canonical},
          std::tuple{d.y[i], cy, d.response.canonical}}) {
      if (!std::isfinite(value))
        throw InputError(csv.Where(i, col) + ": " + csv.Field(i, col) +
                         " is beyond the range of a number in " + unit +
                         " (converted to the set's unit)");
    }
    if (i > 0 && !(d.t[i] > d.t[i - 1])) {
      throw InputError(csv.Where(i, ct) + ": time " + csv.Field(i, ct) +
                       " is not after the previous " + csv.Field(i - 1, ct) +
                       " (times must increase strictly: unsorted or repeated rows)");
    }
  }
  // Steps are checked against the median step (a gap does not shift it); dt is the mean step.
  std::vector<double> steps(n - 1);
  for (size_t i = 1; i < n; ++i) steps[i - 1] = d.t[i] - d.t[i - 1];
  std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2),
                   steps.end());
  const double median = steps[steps.size() / 2];
  d.dt = (d.t.back() - d.t.front()) / static_cast<double>(n - 1);
  for (size_t i = 1; i < n; ++i) {
    const double step = d.t[i] - d.t[i - 1];
    if (std::abs(step - median) > opt.time_jitter * median) {
      throw InputError(
          csv.Where(i, ct) + ": step " + FormatNumber(step / tu.factor) +
          " differs from the usual step " + FormatNumber(median / tu.factor) + " by more than " +
          FormatNumber(100 * opt.time_jitter) +
          " % (the samples must be uniform: resample the record, or a gap is missing)");
    }
  }
  FinishFileData(d, opt);
  return d;
}

std::string OptionalField(const CsvTable& csv, size_t row, const char* name) {
  const auto c = csv.FindColumn(name);
  if (!c) return "";
  return csv.Field(row, *c);
}

std::optional<double> OptionalNumber(const CsvTable& csv, size_t row, const char* name) {
  const auto c = csv.FindColumn(name);
  if (!c || csv.Field(row, *c).empty()) return std::nullopt;
  return csv.Number(row, *c);
}

Record MakeRecord(const FileData& d, std::string name, CaseRole role, fs::path file) {
  Record r;
  r.name = std::move(name);
  r.role = role;
  r.file = std::move(file);
  r.t = d.t;
  r.u = d.u;
  r.y = d.y;
  r.dt = d.dt;
  r.first_scored = 0;
  r.end_scored = d.t.size();
  r.rest_samples = d.rest;
  r.quantum = d.quantum;
  return r;
}

void CheckSameUnits(RecordSet& set, const std::vector<std::pair<std::string, FileData*>>& files) {
  // files: (record name, its data) in manifest order
  if (files.empty()) return;
  const auto& [n0, d0] = files.front();
  set.drive_unit = d0->drive.canonical;
  set.response_unit = d0->response.canonical;
  for (const auto& [n, d] : files) {
    if (d->drive.canonical != d0->drive.canonical) {
      throw InputError("mismatched units: record '" + n + "' has its drive in " +
                       d->drive.canonical + " but record '" + n0 + "' in " + d0->drive.canonical);
    }
    if (d->response.canonical != d0->response.canonical) {
      throw InputError("mismatched units: record '" + n + "' has its response in " +
                       d->response.canonical + " but record '" + n0 + "' in " +
                       d0->response.canonical);
    }
  }
}

void FinishRecord(Record& r, const RecordReadOptions& opt) {
  if (r.scored() < opt.min_scored) {
    throw InputError(r.file.string() + ": record '" + r.name + "' has " +
                     std::to_string(r.scored()) + " samples; at least " +
                     std::to_string(opt.min_scored) + " are needed (too short)");
  }
  if (r.offset_mode == OffsetMode::kRest) {
    if (r.rest_samples < 10) {
      throw InputError(r.file.string() + ": record '" + r.name +
                       "': offset 'rest' needs a rest segment (a constant drive) of at least 10 "
                       "samples at the start; this record has " +
                       std::to_string(r.rest_samples));
    }
    double s = 0;
    for (size_t i = 0; i < r.rest_samples; ++i) s += r.y[i];
    r.offset = s / static_cast<double>(r.rest_samples);
  }
}

RecordSet LoadManifest(const fs::path& dir, const RecordReadOptions& opt) {
  const fs::path manifest = dir / "manifest.csv";
  const CsvTable csv = ReadCsvFile(manifest);
  csv.RequireColumns({"record", "file", "role"});
  csv.RequireRows();
  static const std::vector<std::string> kKnown = {
      "record",          "file",         "role",       "t_start_s",    "t_end_s",
      "offset",          "frequency_Hz", "repeat",     "time_column",  "drive_column",
      "response_column", "time_unit",    "drive_unit", "response_unit"};
  for (size_t c = 0; c < csv.header.size(); ++c) {
    if (std::find(kKnown.begin(), kKnown.end(), csv.header[c]) == kKnown.end()) {
      throw InputError(csv.source + ":" + std::to_string(csv.header_line) + ": unknown column '" +
                       csv.header[c] +
                       "' (columns: record, file, role, t_start_s, t_end_s, offset, frequency_Hz, "
                       "repeat, time_column, drive_column, "
                       "response_column, time_unit, drive_unit, response_unit)");
    }
  }
  RecordSet set;
  set.source = dir;
  set.format = "manifest";
  std::map<std::string, FileData> files;
  std::vector<std::pair<std::string, FileData*>> used;
  const int c_rec = csv.RequireColumn("record"), c_file = csv.RequireColumn("file"),
            c_role = csv.RequireColumn("role");
  for (size_t i = 0; i < csv.rows.size(); ++i) {
    const std::string name = csv.Field(i, c_rec);
    if (!ValidName(name)) {
      throw InputError(csv.Where(i, c_rec) + ": record name '" + name +
                       "' must be 1–100 letters, digits, '-', '_' or '.'");
    }
    if (set.Find(name)) throw InputError(csv.Where(i, c_rec) + ": duplicate record '" + name + "'");
    const auto role = model::ParseCaseRole(csv.Field(i, c_role));
    if (!role) {
      throw InputError(csv.Where(i, c_role) + ": unknown role '" + csv.Field(i, c_role) +
                       "' (train, validate or test)");
    }
    const std::string file = csv.Field(i, c_file);
    if (file.empty()) throw InputError(csv.Where(i, c_file) + ": empty file name");
    ColumnSpec cols;
    if (auto s = OptionalField(csv, i, "time_column"); !s.empty()) cols.time = s;
    if (auto s = OptionalField(csv, i, "drive_column"); !s.empty()) cols.drive = s;
    if (auto s = OptionalField(csv, i, "response_column"); !s.empty()) cols.response = s;
    cols.time_unit = OptionalField(csv, i, "time_unit");
    cols.drive_unit = OptionalField(csv, i, "drive_unit");
    cols.response_unit = OptionalField(csv, i, "response_unit");
    const std::string key = file + "\n" + cols.time + "\n" + cols.drive + "\n" + cols.response +
                            "\n" + cols.time_unit + "\n" + cols.drive_unit + "\n" +
                            cols.response_unit;
    auto it = files.find(key);
    if (it == files.end()) {
      const fs::path path = dir / file;
      if (!fs::is_regular_file(path)) {
        throw InputError(csv.Where(i, c_file) + ": record file '" + file + "' not found in " +
                         dir.string());
      }
      it = files
               .emplace(key, ReadRecordFile(path, cols, opt,
                                            "manifest line " + std::to_string(csv.rows[i].line)))
               .first;
    }
    Record r = MakeRecord(it->second, name, *role, dir / file);
    r.manifest_line = csv.rows[i].line;
    const auto t0 = OptionalNumber(csv, i, "t_start_s");
    const auto t1 = OptionalNumber(csv, i, "t_end_s");
    if (t0 || t1) {
      SetWindow(
          r, t0.value_or(r.t.front()), t1.value_or(r.t.back()), opt.min_scored,
          csv.source + ":" + std::to_string(csv.rows[i].line) + ": record '" + name + "' window");
    }
    if (const auto f = OptionalNumber(csv, i, "frequency_Hz")) {
      if (!(std::isfinite(*f) && *f > 0))
        throw InputError(csv.Where(i, *csv.FindColumn("frequency_Hz")) + ": frequency " +
                         csv.Field(i, *csv.FindColumn("frequency_Hz")) +
                         " Hz must be finite and > 0");
      r.frequency_hz = *f;
    }
    r.repeat = OptionalField(csv, i, "repeat");
    if (!r.repeat.empty() && !ValidName(r.repeat))
      throw InputError(csv.Where(i, *csv.FindColumn("repeat")) + ": repeat group '" + r.repeat +
                       "' must be 1–100 letters, digits, '-', '_' or '.'");
    const std::string off = OptionalField(csv, i, "offset");
    if (off.empty() || off == "fit") {
      r.offset_mode = OffsetMode::kFit;
    } else if (off == "rest") {
      r.offset_mode = OffsetMode::kRest;
    } else {
      const auto v = ParseDouble(off);
      const auto c = csv.FindColumn("offset");
      if (!v || !std::isfinite(*v)) {
        throw InputError(csv.Where(i, *c) + ": offset '" + off +
                         "' is not fit, rest or a finite number");
      }
      r.offset_mode = OffsetMode::kFixed;
      r.offset = *v * it->second.response.factor;
      if (!std::isfinite(r.offset))
        throw InputError(csv.Where(i, *c) + ": offset '" + off +
                         "' is beyond the range of a number in " + it->second.response.canonical +
                         " (converted to the set's unit)");
    }
    FinishRecord(r, opt);
    used.emplace_back(name, &it->second);
    set.records.push_back(std::move(r));
  }
  CheckSameUnits(set, used);
  for (const Record& r : set.records) {  // a repeat group names two recordings at least
    if (r.repeat.empty()) continue;
    if (std::count_if(set.records.begin(), set.records.end(),
                      [&](const Record& o) { return o.repeat == r.repeat; }) < 2)
      throw InputError(csv.source + ":" + std::to_string(r.manifest_line) + ": repeat group '" +
                       r.repeat + "' has one record ('" + r.name +
                       "'); a repeat group names two or more recordings of the same drive");
  }
  return set;
}

// The stack bench's drive as its manifest states it, offset + A sin(2π f t): checked on request
// within 1e-4 of |offset| + A plus 1 mV.
void CheckStatedDrive(const CsvTable& csv, int cu, const Record& r, double offset, double amplitude,
                      const std::string& ctx) {
  const double vtol = 1e-4 * (std::abs(offset) + amplitude) + 1e-3;
  for (size_t k = 0; k < r.u.size(); ++k) {
    const double want =
        offset + amplitude * std::sin(2 * std::numbers::pi * r.frequency_hz * r.t[k]);
    if (!(std::abs(r.u[k] - want) <= vtol))
      throw InputError(
          csv.Where(k, cu) + ": " + FormatNumber(r.u[k]) + " V is not offset + A sin(2 pi f t) = " +
          FormatNumber(want) + " V (offset = " + FormatNumber(offset) +
          " V, A = " + FormatNumber(amplitude) + " V, f = " + FormatNumber(r.frequency_hz) +
          " Hz, t = " + FormatNumber(r.t[k]) + " s; tolerance " + FormatG(vtol, 3) + " V)" + ctx);
  }
}

// The stack bench of `piezoid committee` (data/piezo-stack-bench/): records.csv (record,
// frequency_Hz, offset_V, amplitude_V, file, role; roles train / test) and one CSV per record
// (t_s, voltage_V, displacement_um) starting at t = 0 on a uniform grid (the sample rate is
// inferred from the first step, within 1e-6); drive u = offset + A sin(2π f t) from rest at the
// offset; offset 0.
RecordSet FromStackBench(const fs::path& dir, const RecordReadOptions& opt) {
  const fs::path manifest = dir / "records.csv";
  const CsvTable csv = ReadCsvFile(manifest);
  csv.RequireColumns({"record", "frequency_Hz", "offset_V", "amplitude_V", "file", "role"});
  csv.RequireRows();
  const int cr = csv.RequireColumn("record"), cf = csv.RequireColumn("frequency_Hz"),
            co = csv.RequireColumn("offset_V"), ca = csv.RequireColumn("amplitude_V"),
            cfile = csv.RequireColumn("file"), crole = csv.RequireColumn("role");
  RecordSet set;
  set.source = dir;
  set.format = "stack-bench";
  std::vector<std::pair<long, int>> seen;  // (record number, manifest line)
  for (size_t row = 0; row < csv.rows.size(); ++row) {
    const long number = csv.Integer(row, cr);
    if (number <= 0 || number > 1000000)
      throw InputError(csv.Where(row, cr) + ": record number " + csv.Field(row, cr) +
                       " must be a positive integer");
    for (const auto& [n, line] : seen)
      if (n == number)
        throw InputError(csv.Where(row, cr) + ": duplicate record " + std::to_string(number) +
                         " (first on line " + std::to_string(line) + ")");
    const double f = csv.Number(row, cf);
    if (!(f > 0))
      throw InputError(csv.Where(row, cf) + ": frequency " + csv.Field(row, cf) +
                       " Hz must be > 0");
    const double offset = csv.Number(row, co), amplitude = csv.Number(row, ca);
    if (amplitude < 0)
      throw InputError(csv.Where(row, ca) + ": amplitude " + csv.Field(row, ca) +
                       " V must be >= 0");
    const std::string& role_name = csv.Field(row, crole);
    if (role_name != "train" && role_name != "test")
      throw InputError(csv.Where(row, crole) + ": unknown role '" + role_name +
                       "' (expected train or test)");
    const std::string& name = csv.Field(row, cfile);
    if (name.empty()) throw InputError(csv.Where(row, cfile) + ": empty file name");
    const fs::path file = dir / name;
    std::error_code ec;
    if (!fs::is_regular_file(file, ec))
      throw InputError(csv.Where(row, cfile) + ": record file '" + name + "' not found (" +
                       file.string() + ")");
    const std::string ctx = " (record " + std::to_string(number) + " of " + manifest.string() +
                            " line " + std::to_string(csv.rows[row].line) + ")";
    const CsvTable data = ReadCsvFile(file);
    SampledColumns cols =
        ReadSampledColumns(data, "displacement_um", "record", 1e-6,
                           "a record starts at t = 0 (from rest at the offset)", ctx);
    FileData d;
    d.t = std::move(cols.t);
    d.u = std::move(cols.u);
    d.y = std::move(cols.y);
    d.dt = 1.0 / cols.sample_rate_hz;
    FinishFileData(d, opt);
    Record r = MakeRecord(d, "record" + std::to_string(number),
                          role_name == "train" ? CaseRole::kTrain : CaseRole::kTest, file);
    r.offset_mode = OffsetMode::kFixed;
    r.offset = 0;
    r.frequency_hz = f;
    r.manifest_line = csv.rows[row].line;
    if (opt.check_stated_drive) CheckStatedDrive(data, cols.u_column, r, offset, amplitude, ctx);
    FinishRecord(r, opt);
    set.records.push_back(std::move(r));
    seen.emplace_back(number, csv.rows[row].line);
  }
  return set;
}

// The one reader of a fin bench folder: its cases (io/bench_data.h) as records (io/fin_records.h).
RecordSet FromFinBench(const fs::path& dir, const RecordReadOptions& opt) {
  BenchReadOptions bo;
  bo.cycles = 0;  // any length; the voltage column is checked against the stated sinusoid
  RecordSet set = RecordsFromCaseSet(LoadCaseSet(dir, bo));
  for (Record& r : set.records) FinishRecord(r, opt);
  return set;
}

RecordSet FromCsv(const fs::path& file, const RecordReadOptions& opt) {
  RecordSet set;
  set.source = file;
  set.format = "csv";
  // The columns by their units: the first time column (…_s, …_ms, …_us), the first voltage one
  // (…_V, …_mV, …_kV), the first length / angle one (…_um, …_mm, …_nm, …_m, …_deg, …_rad); else,
  // in order, the first three columns.
  const CsvTable head = ReadRecordCsv(file);
  if (head.header.size() < 3) {
    throw InputError(file.string() + ":" + std::to_string(head.header_line) +
                     ": a record needs three columns (time, drive, response), found " +
                     std::to_string(head.header.size()));
  }
  auto first_of = [&](std::initializer_list<std::string_view> quantities) -> std::string {
    for (const std::string& c : head.header) {
      const std::string q = ConvertUnit(SuffixUnit(c)).quantity;
      for (std::string_view want : quantities)
        if (!SuffixUnit(c).empty() && q == want) return c;
    }
    return "";
  };
  ColumnSpec cols;
  cols.time = first_of({"time"});
  cols.drive = first_of({"voltage"});
  cols.response = first_of({"length", "angle"});
  if (cols.time.empty() || cols.drive.empty() || cols.response.empty() || cols.time == cols.drive ||
      cols.drive == cols.response || cols.time == cols.response) {
    cols.time = head.header[0];
    cols.drive = head.header[1];
    cols.response = head.header[2];
  }
  FileData d = ReadRecordFile(file, cols, opt, "the file");
  Record r = MakeRecord(d, "record", CaseRole::kTrain, file);
  FinishRecord(r, opt);
  set.drive_unit = d.drive.canonical;
  set.response_unit = d.response.canonical;
  set.records.push_back(std::move(r));
  return set;
}

}  // namespace

void SetWindow(Record& r, double t0, double t1, size_t min_scored, const std::string& what) {
  if (!(t0 < t1)) {
    throw InputError(what + " [" + FormatNumber(t0) + ", " + FormatNumber(t1) +
                     "] s: the start must be before the end");
  }
  if (t0 < r.t.front() - 0.5 * r.dt || t1 > r.t.back() + 0.5 * r.dt) {
    throw InputError(what + " [" + FormatNumber(t0) + ", " + FormatNumber(t1) +
                     "] s is outside the record (" + FormatNumber(r.t.front()) + " … " +
                     FormatNumber(r.t.back()) + " s)");
  }
  const auto first = std::lower_bound(r.t.begin(), r.t.end(), t0 - 1e-9 * r.dt) - r.t.begin();
  const auto end = std::upper_bound(r.t.begin(), r.t.end(), t1 + 1e-9 * r.dt) - r.t.begin();
  r.first_scored = static_cast<size_t>(first);
  r.end_scored = static_cast<size_t>(end);
  if (r.end_scored <= r.first_scored || r.scored() < min_scored) {
    throw InputError(what + " [" + FormatNumber(t0) + ", " + FormatNumber(t1) + "] s holds " +
                     std::to_string(r.end_scored > r.first_scored ? r.scored() : 0) +
                     " samples; at least " + std::to_string(min_scored) +
                     " are needed (too short)");
  }
}

void SkipSettling(RecordSet& set, double settle_s, size_t min_scored, const std::string& what) {
  if (!std::isfinite(settle_s) || settle_s < 0)
    throw InputError(what + ": must be finite and ≥ 0 s");
  if (settle_s == 0) return;
  for (Record& r : set.records) {
    const size_t moved = std::min(r.rest_samples, r.size() - 1);  // the first sample off the rest
    const double t0 = r.t[moved] + settle_s;
    const auto first = static_cast<size_t>(
        std::lower_bound(r.t.begin(), r.t.end(), t0 - 1e-9 * r.dt) - r.t.begin());
    if (first <= r.first_scored) continue;
    if (first >= r.end_scored || r.end_scored - first < min_scored) {
      throw InputError(what + ": record " + r.name + " would keep " +
                       std::to_string(first < r.end_scored ? r.end_scored - first : 0) +
                       " scored samples (window " + FormatNumber(r.t[r.first_scored]) + "–" +
                       FormatNumber(r.t[r.end_scored - 1]) + " s, settled from " +
                       FormatNumber(t0) + " s); at least " + std::to_string(min_scored) +
                       " are needed");
    }
    r.first_scored = first;
  }
}

WindowSpec ParseWindow(std::string_view text, CaseRole role, const std::string& flag) {
  const size_t colon = text.find(':');
  WindowSpec w;
  w.role = role;
  const auto a =
      colon == std::string_view::npos ? std::nullopt : ParseDouble(text.substr(0, colon));
  const auto b =
      colon == std::string_view::npos ? std::nullopt : ParseDouble(text.substr(colon + 1));
  if (!a || !b || !std::isfinite(*a) || !std::isfinite(*b) || !(*a < *b)) {
    throw InputError(flag + " '" + std::string(text) +
                     "': expected START:END in seconds with START < END, e.g. 4:7");
  }
  w.t0_s = *a;
  w.t1_s = *b;
  return w;
}

void SplitIntoWindows(RecordSet& set, const std::vector<WindowSpec>& windows,
                      const RecordReadOptions& opt) {
  if (windows.empty()) return;
  if (set.records.size() != 1) {
    throw InputError("windows on the command line need a single record (a CSV file); " +
                     set.source.string() + " holds " + std::to_string(set.records.size()) +
                     ": give t_start_s / t_end_s in its manifest");
  }
  const Record whole = set.records.front();
  set.records.clear();
  std::map<CaseRole, int> count;
  for (const WindowSpec& w : windows) {
    Record r = whole;
    const int k = ++count[w.role];
    r.name = std::string(model::CaseRoleName(w.role)) + (k > 1 ? std::to_string(k) : "");
    r.role = w.role;
    SetWindow(r, w.t0_s, w.t1_s, opt.min_scored,
              std::string(model::CaseRoleName(w.role)) + " window");
    set.records.push_back(std::move(r));
  }
}

RecordSet LoadRecordSet(const fs::path& path, const RecordReadOptions& opt) {
  if (!(opt.time_jitter > 0 && opt.time_jitter < 0.5))
    throw InputError("time_jitter must be in (0, 0.5)");
  if (fs::is_regular_file(path)) return FromCsv(path, opt);
  if (!fs::is_directory(path))
    throw InputError("records '" + path.string() + "': no such file or folder");
  if (fs::exists(path / "manifest.csv")) return LoadManifest(path, opt);
  if (fs::exists(path / "records.csv")) return FromStackBench(path, opt);
  if (fs::exists(path / "cases.csv")) return FromFinBench(path, opt);
  throw InputError("records '" + path.string() +
                   "': no manifest.csv (nor a stack bench's records.csv or a fin bench's "
                   "cases.csv) in the folder");
}

void WriteRecordSet(const RecordSet& set, const fs::path& dir) {
  fs::create_directories(dir);
  WriteFileWith(dir / "manifest.csv", [&](std::ostream& m) {
    m << "record,file,role,t_start_s,t_end_s,offset,frequency_Hz,repeat,drive_column,"
         "response_column\n";
    for (const Record& r : set.records) {
      const std::string file = r.name + ".csv";
      m << r.name << "," << file << "," << model::CaseRoleName(r.role) << ","
        << FormatNumber(r.t[r.first_scored]) << "," << FormatNumber(r.t[r.end_scored - 1]) << ","
        << (r.offset_mode == OffsetMode::kFixed ? FormatNumber(r.offset)
                                                : OffsetModeName(r.offset_mode))
        << "," << (r.frequency_hz > 0 ? FormatNumber(r.frequency_hz) : std::string()) << ","
        << r.repeat << ",drive_" << set.drive_unit << ",response_" << set.response_unit << "\n";
      WriteFileWith(dir / file, [&](std::ostream& f) {
        f << "t_s,drive_" << set.drive_unit << ",response_" << set.response_unit << "\n";
        for (size_t i = 0; i < r.size(); ++i)
          f << FormatNumber(r.t[i]) << "," << FormatNumber(r.u[i]) << "," << FormatNumber(r.y[i])
            << "\n";
      });
    }
  });
}

}  // namespace pz::io
