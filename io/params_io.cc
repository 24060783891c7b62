#include "io/params_io.h"

#include "io/csv.h"

namespace pz::io {
namespace {

// The nine parameter columns, in file order, with their fields.
struct ParamColumn {
  const char* name;
  double model::BimorphParams::*field;
};
constexpr ParamColumn kColumns[] = {
    {"mu", &model::BimorphParams::mu},       {"delta", &model::BimorphParams::delta},
    {"alpha", &model::BimorphParams::alpha}, {"beta", &model::BimorphParams::beta},
    {"gamma", &model::BimorphParams::gamma}, {"a1", &model::BimorphParams::a1},
    {"a2", &model::BimorphParams::a2},       {"b1", &model::BimorphParams::b1},
    {"b2", &model::BimorphParams::b2}};
constexpr int kRequired = 7;  // b1, b2 optional

}  // namespace

const CaseParams* ParamsFile::Find(int case_number) const {
  for (const auto& r : rows)
    if (r.case_number == case_number) return &r;
  return nullptr;
}

ParamsFile ParseParamsCsv(std::string_view text, std::string source) {
  const CsvTable csv = ParseCsv(text, std::move(source));
  std::vector<std::string_view> required = {"case"};
  for (int i = 0; i < kRequired; ++i) required.push_back(kColumns[i].name);
  csv.RequireColumns(required);
  const auto cb1 = csv.FindColumn("b1"), cb2 = csv.FindColumn("b2");
  if (cb1.has_value() != cb2.has_value())
    throw InputError(csv.source + ":" + std::to_string(csv.header_line) + ": column '" +
                     (cb1 ? "b1" : "b2") + "' without '" + (cb1 ? "b2" : "b1") +
                     "': give both saturations or neither");
  csv.RequireRows();
  const int ccase = *csv.FindColumn("case");

  ParamsFile file;
  file.source = csv.source;
  for (size_t r = 0; r < csv.rows.size(); ++r) {
    CaseParams p;
    p.line = csv.rows[r].line;
    const long number = csv.Integer(r, ccase);
    if (number <= 0 || number > 1000000)
      throw InputError(csv.Where(r, ccase) + ": case number " + csv.Field(r, ccase) +
                       " must be a positive integer");
    p.case_number = static_cast<int>(number);
    if (const CaseParams* prev = file.Find(p.case_number))
      throw InputError(csv.Where(r, ccase) + ": duplicate case " + std::to_string(number) +
                       " (first on line " + std::to_string(prev->line) + ")");
    for (int i = 0; i < kRequired; ++i)
      p.params.*kColumns[i].field = csv.Number(r, *csv.FindColumn(kColumns[i].name));
    if (cb1) {
      const bool e1 = csv.Field(r, *cb1).empty(), e2 = csv.Field(r, *cb2).empty();
      if (e1 != e2) {
        const int col = e1 ? *cb1 : *cb2;
        throw InputError(csv.Where(r, col) + ": empty while '" + (e1 ? "b2" : "b1") +
                         "' is given: give both saturations or neither");
      }
      if (!e1) {
        p.params.b1 = csv.Number(r, *cb1);
        p.params.b2 = csv.Number(r, *cb2);
        p.has_saturation = true;
      }
    }
    if (const Status s = p.params.Validate(); !s.ok()) {
      // Validate() messages start with the field name ("mu = -1: must be >= 0 [1/s]").
      const std::string field = s.message().substr(0, s.message().find(' '));
      const auto col = csv.FindColumn(field);
      throw InputError((col ? csv.Where(r, *col) : csv.source + ":" + std::to_string(p.line)) +
                       ": " + s.message());
    }
    file.rows.push_back(p);
  }
  return file;
}

ParamsFile ReadParamsCsv(const std::filesystem::path& path) {
  return ParseParamsCsv(ReadTextFile(path), path.string());
}

void WriteParamsCsv(std::ostream& out, std::span<const CaseParams> rows) {
  bool any_sat = false;
  for (const auto& r : rows) any_sat = any_sat || r.has_saturation;
  const int ncol = any_sat ? 9 : kRequired;
  out << "case";
  for (int i = 0; i < ncol; ++i) out << ',' << kColumns[i].name;
  out << '\n';
  for (const auto& r : rows) {
    out << r.case_number;
    for (int i = 0; i < ncol; ++i) {
      out << ',';
      if (i < kRequired || r.has_saturation) out << FormatNumber(r.params.*kColumns[i].field);
    }
    out << '\n';
  }
}

void WriteParamsCsvFile(const std::filesystem::path& path, std::span<const CaseParams> rows) {
  WriteFileWith(path, [&](std::ostream& out) { WriteParamsCsv(out, rows); });
}

}  // namespace pz::io
