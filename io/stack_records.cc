#include "io/stack_records.h"

#include <cmath>
#include <numbers>

#include "io/csv.h"

namespace pz::io {
namespace fs = std::filesystem;

std::optional<CaseRole> ParseRecordRole(std::string_view name) {
  for (CaseRole r : {CaseRole::kTrain, CaseRole::kTest})
    if (name == CaseRoleName(r)) return r;
  return std::nullopt;
}

std::string StackRecord::Label() const {
  return "record " + std::to_string(number) + " (" + FormatNumber(frequency_hz) + " Hz, A = " +
         FormatNumber(amplitude_v) + " V, " + CaseRoleName(role) + ")";
}

Status StackReadOptions::Validate() const {
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

const StackRecord* StackRecordSet::Find(int number) const {
  for (const auto& r : records)
    if (r.number == number) return &r;
  return nullptr;
}

std::vector<const StackRecord*> StackRecordSet::WithRole(CaseRole role) const {
  std::vector<const StackRecord*> out;
  for (const auto& r : records)
    if (r.role == role) out.push_back(&r);
  return out;
}

StackRecord LoadStackRecordFile(const fs::path& file, int number, double frequency_hz,
                                double offset_v, double amplitude_v, CaseRole role,
                                const StackReadOptions& options, const std::string& context) {
  ThrowIfError(options.Validate());
  const std::string ctx = context.empty() ? "" : " (" + context + ")";
  const CsvTable csv = ReadCsvFile(file);
  SampledColumns cols = ReadSampledColumns(csv, "displacement_um", "record", options.time_rel_tol,
                                           "a record starts at t = 0 (from rest at the offset)", ctx);
  const int cu = cols.u_column;
  const size_t n = cols.t.size();
  StackRecord r;
  r.number = number;
  r.frequency_hz = frequency_hz;
  r.offset_v = offset_v;
  r.amplitude_v = amplitude_v;
  r.role = role;
  r.file = file;
  r.t = std::move(cols.t);
  r.u = std::move(cols.u);
  r.y = std::move(cols.y);
  r.sample_rate_hz = cols.sample_rate_hz;
  if (options.check_voltage) {
    const double vtol =
        options.voltage_rel_tol * (std::abs(offset_v) + amplitude_v) + options.voltage_abs_tol_v;
    for (size_t k = 0; k < n; ++k) {
      const double want =
          offset_v + amplitude_v * std::sin(2 * std::numbers::pi * frequency_hz * r.t[k]);
      if (!(std::abs(r.u[k] - want) <= vtol))
        throw InputError(csv.Where(k, cu) + ": " + FormatNumber(r.u[k]) +
                         " V is not offset + A sin(2 pi f t) = " + FormatNumber(want) +
                         " V (offset = " + FormatNumber(offset_v) + " V, A = " +
                         FormatNumber(amplitude_v) + " V, f = " + FormatNumber(frequency_hz) +
                         " Hz, t = " + FormatNumber(r.t[k]) + " s; tolerance " +
                         FormatNumber(vtol) + " V)" + ctx);
    }
  }
  return r;
}

StackRecordSet LoadStackRecordSet(const fs::path& dir, const StackReadOptions& options) {
  ThrowIfError(options.Validate());
  std::error_code ec;
  if (!fs::is_directory(dir, ec))
    throw InputError(dir.string() +
                     ": not a directory (expected a record set folder with records.csv)");
  const fs::path manifest = dir / "records.csv";
  const CsvTable csv = ReadCsvFile(manifest);
  csv.RequireColumns({"record", "frequency_Hz", "offset_V", "amplitude_V", "file", "role"});
  csv.RequireRows();
  const int cr = *csv.FindColumn("record"), cf = *csv.FindColumn("frequency_Hz"),
            co = *csv.FindColumn("offset_V"), ca = *csv.FindColumn("amplitude_V"),
            cfile = *csv.FindColumn("file"), crole = *csv.FindColumn("role");
  StackRecordSet set;
  set.dir = dir;
  std::vector<int> seen_line;
  for (size_t row = 0; row < csv.rows.size(); ++row) {
    const long number = csv.Integer(row, cr);
    if (number <= 0 || number > 1000000)
      throw InputError(csv.Where(row, cr) + ": record number " + csv.Field(row, cr) +
                       " must be a positive integer");
    for (size_t p = 0; p < set.records.size(); ++p)
      if (set.records[p].number == number)
        throw InputError(csv.Where(row, cr) + ": duplicate record " + std::to_string(number) +
                         " (first on line " + std::to_string(seen_line[p]) + ")");
    const double f = csv.Number(row, cf);
    if (!(f > 0))
      throw InputError(csv.Where(row, cf) + ": frequency " + csv.Field(row, cf) +
                       " Hz must be > 0");
    const double offset = csv.Number(row, co);
    const double a = csv.Number(row, ca);
    if (a < 0)
      throw InputError(csv.Where(row, ca) + ": amplitude " + csv.Field(row, ca) +
                       " V must be >= 0");
    const auto role = ParseRecordRole(csv.Field(row, crole));
    if (!role)
      throw InputError(csv.Where(row, crole) + ": unknown role '" + csv.Field(row, crole) +
                       "' (expected train or test)");
    const std::string& name = csv.Field(row, cfile);
    if (name.empty()) throw InputError(csv.Where(row, cfile) + ": empty file name");
    const fs::path file = dir / name;
    if (!fs::is_regular_file(file, ec))
      throw InputError(csv.Where(row, cfile) + ": record file '" + name + "' not found (" +
                       file.string() + ")");
    set.records.push_back(LoadStackRecordFile(
        file, static_cast<int>(number), f, offset, a, *role, options,
        "record " + std::to_string(number) + " of " + manifest.string() + " line " +
            std::to_string(csv.rows[row].line)));
    seen_line.push_back(csv.rows[row].line);
  }
  return set;
}

}  // namespace pz::io
