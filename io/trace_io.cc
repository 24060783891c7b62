#include "io/trace_io.h"

#include "io/csv.h"

namespace pz::io {

void WriteColumnsCsv(std::ostream& out, std::span<const NamedColumn> columns) {
  if (columns.empty()) throw InputError("trace CSV: no columns to write");
  for (const auto& c : columns) {
    if (c.name.empty() || c.name.find_first_of(",\"\r\n") != std::string::npos)
      throw InputError("trace CSV: column name '" + c.name +
                       "' must be non-empty without commas, quotes or line breaks");
    if (c.values.size() != columns[0].values.size())
      throw InputError("trace CSV: column '" + c.name + "' has " + std::to_string(c.values.size()) +
                       " values but '" + columns[0].name + "' has " +
                       std::to_string(columns[0].values.size()));
  }
  for (size_t i = 0; i < columns.size(); ++i) out << (i ? "," : "") << columns[i].name;
  out << '\n';
  std::string line;
  for (size_t k = 0; k < columns[0].values.size(); ++k) {
    line.clear();
    for (size_t i = 0; i < columns.size(); ++i) {
      if (i) line += ',';
      line += FormatNumber(columns[i].values[k]);
    }
    line += '\n';
    out << line;
  }
}

void WriteColumnsCsvFile(const std::filesystem::path& path, std::span<const NamedColumn> columns) {
  WriteFileWith(path, [&](std::ostream& out) { WriteColumnsCsv(out, columns); });
}

std::vector<NamedColumn> TraceColumns(const model::BimorphTrace& trace) {
  return {{"t_s", trace.t},
          {"voltage_V", trace.u},
          {"z_N", trace.z},
          {"w_tip_m", trace.w_tip},
          {"theta_linear_deg", trace.theta_deg},
          {"angle_deg", trace.angle_deg}};
}

void WriteTraceCsv(std::ostream& out, const model::BimorphTrace& trace) {
  const auto cols = TraceColumns(trace);
  WriteColumnsCsv(out, cols);
}

model::SampledSignal ReadInputSignalCsv(const std::filesystem::path& path) {
  const CsvTable csv = ReadCsvFile(path);
  csv.RequireColumns({"t_s", "voltage_V"});
  const int ct = *csv.FindColumn("t_s"), cu = *csv.FindColumn("voltage_V");
  if (csv.rows.size() < 2)
    throw InputError(csv.source + ": " + std::to_string(csv.rows.size()) +
                     " data rows; an input signal needs at least 2 samples");
  model::SampledSignal s;
  for (size_t k = 0; k < csv.rows.size(); ++k) {
    s.t.push_back(csv.Number(k, ct));
    s.u.push_back(csv.Number(k, cu));
    if (k > 0 && !(s.t[k] > s.t[k - 1]))
      throw InputError(csv.Where(k, ct) + ": time " + csv.Field(k, ct) +
                       " s is not after the previous sample's " + csv.Field(k - 1, ct) +
                       " s (time must be strictly increasing)");
  }
  ThrowIfError(s.Validate());
  return s;
}

}  // namespace pz::io
