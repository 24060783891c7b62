// The lists the documents and scripts keep by hand, checked against the registries they copy
// (issue 46 part 5): the family table of docs/records.md, its `--effects` list, the effect table
// of docs/diagnosis.md (the fin bench's effects), bench/real_recording.sh's default families, the
// README's families, proto/job.proto's comments on record_family and effects, and the header
// table of records/families.h.
// A family or effect added to a registry fails here until every list names it.
#include <gtest/gtest.h>

#include <algorithm>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include "model/effect_library.h"
#include "records/fin_effects.h"
#include "records/registry.h"

namespace pz {
namespace {

std::string Slurp(const std::string& rel) {
  std::ifstream in(std::string(PIEZOID_SOURCE_DIR) + "/" + rel);
  EXPECT_TRUE(in) << rel;
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// The first backquoted name of each row of the markdown table whose header row starts with
// `header` (up to the first line that is not a table row).
std::vector<std::string> TableNames(const std::string& text, const std::string& header) {
  std::istringstream in(text);
  std::string line;
  std::vector<std::string> names;
  bool inside = false;
  static const std::regex first(R"(^\| `([a-z0-9-]+)`)");
  while (std::getline(in, line)) {
    if (!inside) {
      inside = line.rfind(header, 0) == 0;
      continue;
    }
    if (line.rfind("|", 0) != 0) break;
    std::smatch m;
    if (std::regex_search(line, m, first)) names.push_back(m[1]);
  }
  return names;
}

std::vector<std::string> Split(const std::string& text, const std::string& sep) {
  std::vector<std::string> out;
  size_t at = 0;
  while (true) {
    const size_t next = text.find(sep, at);
    std::string part = text.substr(at, next == std::string::npos ? std::string::npos : next - at);
    part.erase(0, part.find_first_not_of(" \n"));
    part.erase(part.find_last_not_of(" \n") + 1);
    if (!part.empty()) out.push_back(part);
    if (next == std::string::npos) return out;
    at = next + sep.size();
  }
}

std::vector<std::string> FamilyNames() {
  std::vector<std::string> names;
  for (const records::FamilyDef* f : records::Families()) names.push_back(f->name);
  return names;
}

TEST(DocLists, RecordsMdHasARowForEveryFamily) {
  EXPECT_EQ(TableNames(Slurp("docs/records.md"), "| family | model | parameters |"),
            FamilyNames());
}

TEST(DocLists, RecordsMdNamesEveryEffectARecordsFamilyTakes) {
  // The effects with a step kernel are the ones a records family chains (beam effects have none).
  std::vector<std::string> expected;
  for (const model::EffectDef* e : model::Effects())
    if (e->kernel() != 0) expected.push_back(e->name());
  const std::string text = Slurp("docs/records.md");
  static const std::regex list(R"(`--effects a,b` adds unmodelled effects of the diagnosis )"
                               R"(library to any family \(([^;]*);)");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(text, m, list)) << "docs/records.md: the `--effects a,b` sentence";
  std::vector<std::string> listed = Split(m[1], ",");
  std::sort(listed.begin(), listed.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(listed, expected);
}

TEST(DocLists, DiagnosisMdHasARowForEveryFinEffect) {
  std::vector<std::string> expected;
  for (const records::FinEffectInfo& e : records::FinEffects())
    if (!e.kind.none()) expected.push_back(e.name);
  // The table is in stage order, the library in chain order: the same names are what counts.
  std::vector<std::string> rows =
      TableNames(Slurp("docs/diagnosis.md"), "| effect | stage / path | equation |");
  std::sort(rows.begin(), rows.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(rows, expected);
}

TEST(DocLists, RealRecordingScriptRunsEveryFamily) {
  const std::string script = Slurp("bench/real_recording.sh");
  static const std::regex families(R"re(FAMILIES=\$\{FAMILIES:-([a-z -]+)\})re");
  std::smatch m;
  ASSERT_TRUE(std::regex_search(script, m, families)) << "bench/real_recording.sh: FAMILIES=";
  std::vector<std::string> listed = Split(m[1], " ");
  std::vector<std::string> expected = FamilyNames();
  std::sort(listed.begin(), listed.end());
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(listed, expected);
}

std::vector<std::string> Sorted(std::vector<std::string> v) {
  std::sort(v.begin(), v.end());
  return v;
}

std::vector<std::string> RecordsEffectNames() {
  std::vector<std::string> names;
  for (const model::EffectDef* e : model::Effects())
    if (e->kernel() != 0) names.push_back(e->name());
  return names;
}

// The names matching `name` (its first group) in `text` between the first `to` and the last
// `from` before it.
std::vector<std::string> NamesBetween(const std::string& text, const std::string& from,
                                      const std::string& to, const std::regex& name) {
  const size_t b = text.find(to);
  EXPECT_NE(b, std::string::npos) << to;
  const size_t a = b == std::string::npos ? b : text.rfind(from, b);
  EXPECT_NE(a, std::string::npos) << from;
  if (a == std::string::npos || b == std::string::npos) return {};
  // `to`'s first character kept: it ends the last name.
  const std::string part = text.substr(a + from.size(), b + 1 - a - from.size());
  std::vector<std::string> out;
  for (std::sregex_iterator it(part.begin(), part.end(), name), end; it != end; ++it)
    out.push_back((*it)[1]);
  return out;
}

TEST(DocLists, ReadmeNamesEveryFamily) {
  EXPECT_EQ(Sorted(NamesBetween(Slurp("README.md"), "Families: ", "Every fit flags",
                                std::regex("`([a-z-]+)`"))),
            Sorted(FamilyNames()));
}

TEST(DocLists, JobProtoCommentsNameEveryFamilyAndEffect) {
  const std::string proto = Slurp("proto/job.proto");
  const std::regex word(R"(([a-z]+(?:-[a-z]+)*)(?:,| \())");
  std::vector<std::string> families =
      NamesBetween(proto, "// RECORDS family only: ", "(records/registry.h)", word);
  EXPECT_EQ(Sorted(families), Sorted(FamilyNames()));
  std::vector<std::string> effects =
      NamesBetween(proto, "string record_family = 11;", "(model/effect_library.h)", word);
  EXPECT_EQ(Sorted(effects), Sorted(RecordsEffectNames()));
}

TEST(DocLists, FamiliesHeaderTableHasARowForEveryFamily) {
  // The header comment's rows: "//   name   text", the name two spaces or more from its text.
  const std::string header = Slurp("records/families.h");
  const std::string table = header.substr(0, header.find("#pragma once"));
  std::vector<std::string> rows;
  static const std::regex row(R"(//   ([a-z-]+) {2,}\S)");
  for (std::sregex_iterator it(table.begin(), table.end(), row), end; it != end; ++it)
    rows.push_back((*it)[1]);
  EXPECT_EQ(Sorted(rows), Sorted(FamilyNames()));
}

}  // namespace
}  // namespace pz
