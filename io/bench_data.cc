#include "io/bench_data.h"

#include <cmath>
#include <numbers>

#include "io/csv.h"
#include "model/format.h"

namespace pz::io {
namespace fs = std::filesystem;

model::Sinusoid BenchCase::Drive() const {
  model::Sinusoid s;
  s.amplitude_v = amplitude_v;
  s.frequency_hz = frequency_hz;
  s.sample_rate_hz = sample_rate_hz;
  s.cycles = cycles > 0 ? cycles : static_cast<double>(t.size()) * frequency_hz / sample_rate_hz;
  return s;
}

model::SampledSignal BenchCase::SampledDrive() const { return {t, u}; }

Status BenchReadOptions::Validate() const {
  if (!(std::isfinite(cycles) && cycles >= 0))
    return InvalidArgument(FieldError("cycles", cycles, "must be finite and >= 0"));
  if (!(time_rel_tol > 0 && time_rel_tol < 0.5))
    return InvalidArgument(FieldError("time_rel_tol", time_rel_tol, "must be in (0, 0.5)"));
  if (!(voltage_rel_tol >= 0 && std::isfinite(voltage_rel_tol)))
    return InvalidArgument(
        FieldError("voltage_rel_tol", voltage_rel_tol, "must be finite and >= 0"));
  if (!(voltage_abs_tol_v >= 0 && std::isfinite(voltage_abs_tol_v)))
    return InvalidArgument(
        FieldError("voltage_abs_tol_v", voltage_abs_tol_v, "must be finite and >= 0"));
  return Status::Ok();
}

const BenchCase* CaseSet::Find(int number) const {
  for (const auto& c : cases)
    if (c.number == number) return &c;
  return nullptr;
}

std::vector<const BenchCase*> CaseSet::WithRole(CaseRole role) const {
  std::vector<const BenchCase*> out;
  for (const auto& c : cases)
    if (c.role == role) out.push_back(&c);
  return out;
}

model::FinCase MakeFinCase(const BenchCase& c, const std::optional<model::SaturationPair>& given) {
  return model::MakeFinCase(c.number, c.Drive(), c.angle_deg, c.role == CaseRole::kTrain, given,
                            c.file.string());
}

BenchCase MakeBenchCase(BenchCaseSamples s, const BenchReadOptions& options,
                        const BenchCaseWhere& where, const std::string& context) {
  ThrowIfError(options.Validate());
  constexpr size_t kWhole = std::string::npos;
  auto fail = [&](std::string_view field, size_t index, const std::string& what) {
    throw InputError(where(field, index) + ": " + what + context);
  };
  if (!(std::isfinite(s.amplitude_v) && s.amplitude_v >= 0))
    fail("amplitude_v", kWhole,
         "amplitude " + FormatNumber(s.amplitude_v) + " V must be finite and >= 0");
  if (!(std::isfinite(s.frequency_hz) && s.frequency_hz > 0))
    fail("frequency_hz", kWhole,
         "frequency " + FormatNumber(s.frequency_hz) + " Hz must be finite and > 0");
  if (!(std::isfinite(s.sample_rate_hz) && s.sample_rate_hz > 0))
    fail("sample_rate_hz", kWhole,
         "sample rate " + FormatNumber(s.sample_rate_hz) + " Hz must be finite and > 0");
  const size_t n = s.angle_deg.size();
  if (n < 2) fail("angle_deg", kWhole, std::to_string(n) + " samples; a case needs at least 2");
  for (size_t k = 0; k < n; ++k)
    if (!std::isfinite(s.angle_deg[k]))
      fail("angle_deg", k, FormatNumber(s.angle_deg[k]) + " deg must be finite");
  if (!s.t.empty() && s.t.size() != n)
    fail("t", kWhole,
         std::to_string(s.t.size()) + " times for " + std::to_string(n) + " angle samples");
  if (!s.u.empty() && s.u.size() != n)
    fail("u", kWhole,
         std::to_string(s.u.size()) + " drive samples for " + std::to_string(n) + " angle samples");
  for (size_t k = 0; k < s.u.size(); ++k)
    if (!std::isfinite(s.u[k])) fail("u", k, FormatNumber(s.u[k]) + " V must be finite");
  const double cycles = s.cycles > 0 ? s.cycles : options.cycles;
  if (cycles > 0) {
    const long expected = std::lround(cycles * s.sample_rate_hz / s.frequency_hz);
    if (static_cast<long>(n) != expected)
      fail("", kWhole,
           std::to_string(n) + " samples, expected round(" + FormatNumber(cycles) + " cycles * " +
               FormatNumber(s.sample_rate_hz) + " Hz / " + FormatNumber(s.frequency_hz) +
               " Hz) = " + std::to_string(expected));
  }
  BenchCase c;
  c.number = s.number;
  c.amplitude_v = s.amplitude_v;
  c.frequency_hz = s.frequency_hz;
  c.role = s.role;
  c.file = std::move(s.file);
  c.sample_rate_hz = s.sample_rate_hz;
  c.cycles = s.cycles;
  c.t = std::move(s.t);
  if (c.t.empty()) {
    c.t.resize(n);
    for (size_t k = 0; k < n; ++k) c.t[k] = static_cast<double>(k) / s.sample_rate_hz;
  }
  c.u = std::move(s.u);
  if (c.u.empty()) {
    c.u.resize(n);
    for (size_t k = 0; k < n; ++k)
      c.u[k] = s.amplitude_v * std::sin(2 * std::numbers::pi * s.frequency_hz * c.t[k]);
  } else if (options.check_voltage) {
    const double vtol = options.voltage_rel_tol * c.amplitude_v + options.voltage_abs_tol_v;
    for (size_t k = 0; k < n; ++k) {
      const double want = c.amplitude_v * std::sin(2 * std::numbers::pi * c.frequency_hz * c.t[k]);
      if (!(std::abs(c.u[k] - want) <= vtol))
        fail("u", k,
             FormatNumber(c.u[k]) + " V is not V sin(2 pi f t) = " + FormatNumber(want) +
                 " V (V = " + FormatNumber(c.amplitude_v) +
                 " V, f = " + FormatNumber(c.frequency_hz) + " Hz, t = " + FormatNumber(c.t[k]) +
                 " s; tolerance " + FormatG(vtol, 3) + " V)");
    }
  }
  c.angle_deg = std::move(s.angle_deg);
  return c;
}

BenchCaseWhere SpecCaseWhere(std::string prefix) {
  return [prefix = std::move(prefix)](std::string_view field, size_t k) {
    const std::string name =
        field.empty() ? "" : "." + std::string(field == "u" ? "voltage_v" : field);
    return prefix + name + (k == std::string::npos ? "" : "[" + std::to_string(k) + "]");
  };
}

BenchCase LoadCaseFile(const fs::path& file, int number, double amplitude_v, double frequency_hz,
                       CaseRole role, const BenchReadOptions& options, const std::string& context) {
  ThrowIfError(options.Validate());
  const std::string ctx = context.empty() ? "" : " (" + context + ")";
  const CsvTable csv = ReadCsvFile(file);
  SampledColumns cols = ReadSampledColumns(csv, "angle_deg", "case", options.time_rel_tol,
                                           "a case starts at t = 0 (from rest)", ctx);
  BenchCaseSamples s;
  s.number = number;
  s.amplitude_v = amplitude_v;
  s.frequency_hz = frequency_hz;
  s.role = role;
  s.sample_rate_hz = cols.sample_rate_hz;
  s.angle_deg = std::move(cols.y);
  s.u = std::move(cols.u);
  s.t = std::move(cols.t);
  s.file = file;
  const BenchCaseWhere where = [&](std::string_view field, size_t k) {
    if (k == std::string::npos) return csv.source;
    return csv.Where(k, field == "u"   ? cols.u_column
                        : field == "t" ? cols.t_column
                                       : cols.y_column);
  };
  return MakeBenchCase(std::move(s), options, where, ctx);
}

CaseSet LoadCaseSet(const fs::path& dir, const BenchReadOptions& options) {
  ThrowIfError(options.Validate());
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw InputError(dir.string() +
                     ": not a directory (expected a case set folder with cases.csv)");
  const fs::path manifest = dir / "cases.csv";
  const CsvTable csv = ReadCsvFile(manifest);
  csv.RequireColumns({"case", "amplitude_V", "frequency_Hz", "file", "role"});
  csv.RequireRows();
  const int cc = *csv.FindColumn("case"), cv = *csv.FindColumn("amplitude_V"),
            cf = *csv.FindColumn("frequency_Hz"), cfile = *csv.FindColumn("file"),
            crole = *csv.FindColumn("role");
  CaseSet set;
  set.dir = dir;
  std::vector<int> seen_line;
  for (size_t r = 0; r < csv.rows.size(); ++r) {
    const long number = csv.Integer(r, cc);
    if (number <= 0 || number > 1000000)
      throw InputError(csv.Where(r, cc) + ": case number " + csv.Field(r, cc) +
                       " must be a positive integer");
    for (size_t p = 0; p < set.cases.size(); ++p)
      if (set.cases[p].number == number)
        throw InputError(csv.Where(r, cc) + ": duplicate case " + std::to_string(number) +
                         " (first on line " + std::to_string(seen_line[p]) + ")");
    const double v = csv.Number(r, cv);
    if (v < 0)
      throw InputError(csv.Where(r, cv) + ": amplitude " + csv.Field(r, cv) + " V must be >= 0");
    const double f = csv.Number(r, cf);
    if (!(f > 0))
      throw InputError(csv.Where(r, cf) + ": frequency " + csv.Field(r, cf) + " Hz must be > 0");
    const auto role = ParseCaseRole(csv.Field(r, crole));
    if (!role)
      throw InputError(csv.Where(r, crole) + ": unknown role '" + csv.Field(r, crole) +
                       "' (expected train, validate or test)");
    const std::string& name = csv.Field(r, cfile);
    if (name.empty()) throw InputError(csv.Where(r, cfile) + ": empty file name");
    const fs::path file = dir / name;
    if (!fs::is_regular_file(file, ec))
      throw InputError(csv.Where(r, cfile) + ": case file '" + name + "' not found (" +
                       file.string() + ")");
    set.cases.push_back(LoadCaseFile(file, static_cast<int>(number), v, f, *role, options,
                                     "case " + std::to_string(number) + " of " + manifest.string() +
                                         " line " + std::to_string(csv.rows[r].line)));
    seen_line.push_back(csv.rows[r].line);
  }
  return set;
}

}  // namespace pz::io
