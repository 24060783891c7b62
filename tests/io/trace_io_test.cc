// CSV core (numbers, BOM/CRLF, header checks), trace writing with named columns, and input files.
#include "io/trace_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "io/csv.h"
#include "tests/testing/expect_error.h"

namespace pz::io {
namespace {

using pz::testing::InputErrorOf;

const std::filesystem::path kBad = std::filesystem::path(PIEZOID_TEST_DATA_DIR) / "bad";

TEST(CsvNumbers, ParseWholeFieldsOnly) {
  EXPECT_EQ(ParseDouble("1.5"), 1.5);
  EXPECT_EQ(ParseDouble("+2"), 2.0);
  EXPECT_EQ(ParseDouble("-0"), 0.0);
  EXPECT_EQ(ParseDouble("1e-3"), 1e-3);
  EXPECT_FALSE(ParseDouble("").has_value());
  EXPECT_FALSE(ParseDouble("1.5x").has_value());
  EXPECT_FALSE(ParseDouble("+-1").has_value());
  EXPECT_FALSE(ParseDouble("0x10").has_value());
  EXPECT_TRUE(std::isnan(*ParseDouble("nan")));  // parsed; CsvTable::Number rejects it
}

TEST(CsvNumbers, FormatRoundTrips) {
  for (double x : {0.1, 1.0 / 3.0, -1.5e-300, 6.02214076e23, 375.0})
    EXPECT_EQ(*ParseDouble(FormatNumber(x)), x);
  EXPECT_EQ(FormatNumber(375.0), "375");
}

TEST(CsvTableParse, HandlesBomCrlfSpacesAndTrailingBlankLines) {
  const CsvTable t = ParseCsv(
      "\xEF\xBB\xBF"
      "a, b\r\n1 ,2\r\n3,4\r\n\r\n  \n",
      "mem.csv");
  ASSERT_EQ(t.header, (std::vector<std::string>{"a", "b"}));
  ASSERT_EQ(t.rows.size(), 2u);
  EXPECT_EQ(t.rows[1].line, 3);
  EXPECT_EQ(t.Number(0, 0), 1.0);
  EXPECT_EQ(t.Number(1, *t.FindColumn("b")), 4.0);
  PZ_EXPECT_HAS(InputErrorOf([] { (void)ParseCsv("a,a\n1,2\n", "dup.csv"); }),
                "dup.csv:1: duplicate column 'a'");
  PZ_EXPECT_HAS(InputErrorOf([] { (void)ParseCsv("a,,c\n", "gap.csv"); }),
                "gap.csv:1: column 2 of the header has no name");
  PZ_EXPECT_HAS(InputErrorOf([] { (void)ParseCsv("\xEF\xBB\xBF\r\n\r\n", "bom.csv"); }),
                "bom.csv: empty file");
  PZ_EXPECT_HAS(InputErrorOf([] { (void)ParseCsv("a,b\n1,2\n1.5,x\n", "m.csv").Integer(1, 0); }),
                "m.csv:3: column 'a' (1): '1.5' is not an integer");
}

TEST(TraceCsv, WritesNamedColumnsInOrder) {
  model::BimorphTrace tr;
  tr.t = {0, 0.01};
  tr.u = {0, 5.5};
  tr.z = {0, 1e-3};
  tr.w_tip = {0, 2.5e-5};
  tr.theta_deg = {0, 0.1};
  tr.angle_deg = {0, 0};
  std::ostringstream out;
  WriteTraceCsv(out, tr);
  EXPECT_EQ(out.str(),
            "t_s,voltage_V,z_N,w_tip_m,theta_linear_deg,angle_deg\n"
            "0,0,0,0,0,0\n"
            "0.01,5.5,0.001,2.5e-05,0.1,0\n");
  const CsvTable back = ParseCsv(out.str(), "trace");
  EXPECT_EQ(back.Number(1, *back.FindColumn("w_tip_m")), 2.5e-5);
}

TEST(TraceCsv, RaggedColumnsAreAnError) {
  const std::vector<double> a = {1, 2, 3}, b = {1, 2};
  const std::vector<NamedColumn> cols = {{"a_s", a}, {"b_V", b}};
  std::ostringstream out;
  PZ_EXPECT_HAS(InputErrorOf([&] { WriteColumnsCsv(out, cols); }),
                "column 'b_V' has 2 values but 'a_s' has 3");
  const std::vector<NamedColumn> bad_name = {{"a,b", a}};
  PZ_EXPECT_HAS(InputErrorOf([&] { WriteColumnsCsv(out, bad_name); }), "column name 'a,b'");
}

TEST(InputSignalCsv, ReadsTimeAndVoltage) {
  const model::SampledSignal s = ReadInputSignalCsv(kBad / "input_ok.csv");
  EXPECT_EQ(s.t, (std::vector<double>{0, 0.5, 1, 2}));
  EXPECT_EQ(s.u, (std::vector<double>{0, 10, 0, -5}));
  // A bench case file is a valid input file too (extra angle column ignored).
  EXPECT_EQ(ReadInputSignalCsv(kBad / "tiny_case.csv").t.size(), 12u);
}

TEST(InputSignalCsv, ErrorsNameFileLineAndColumn) {
  PZ_EXPECT_HAS(InputErrorOf([] { (void)ReadInputSignalCsv(kBad / "input_time_back.csv"); }),
                "input_time_back.csv:4: column 't_s' (1): time 0.4 s is not after the previous "
                "sample's 0.5 s");
  PZ_EXPECT_HAS(InputErrorOf([] { (void)ReadInputSignalCsv(kBad / "params_ok.csv"); }),
                "params_ok.csv:1: missing columns 't_s', 'voltage_V'");
  PZ_EXPECT_HAS(InputErrorOf([] { (void)ReadInputSignalCsv(kBad / "case_header_only.csv"); }),
                "0 data rows");
}

// Output paths are checked before a long run: a missing or read-only folder, or a folder given as
// the file, is refused naming the flag and the path; a folder to write into is made.
TEST(OutputPaths, AreCheckedBeforeTheRun) {
  namespace fs = std::filesystem;
  const fs::path root = fs::path(::testing::TempDir()) / "pz_output_paths";
  fs::remove_all(root);
  fs::create_directories(root);
  EXPECT_NO_THROW(CheckWritableFile(root / "a.json", "--json"));
  EXPECT_NE(InputErrorOf([&] {
              CheckWritableFile(root / "missing" / "a.json", "--json");
            }).find("--json " + (root / "missing" / "a.json").string() + ": the folder '"),
            std::string::npos);
  EXPECT_NE(InputErrorOf([&] { CheckWritableFile(root, "--json"); }).find("is a folder"),
            std::string::npos);
  EXPECT_NO_THROW(PrepareOutputFolder(root / "out" / "deeper", "--out"));
  EXPECT_TRUE(fs::is_directory(root / "out" / "deeper"));
  std::ofstream(root / "plain") << "x";
  EXPECT_NE(InputErrorOf([&] {
              PrepareOutputFolder(root / "plain" / "sub", "--out");
            }).find("--out " + (root / "plain" / "sub").string() + ": cannot create the folder"),
            std::string::npos);
  fs::remove_all(root);
}

}  // namespace
}  // namespace pz::io
