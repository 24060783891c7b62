// Per-case parameter CSV: reading (with and without saturations), the error for each malformed file
// in tests/data/bad/, and an exact write/read round trip.
#include "io/params_io.h"

#include <gtest/gtest.h>

#include <sstream>

#include "tests/testing/expect_error.h"

namespace pz::io {
namespace {

using pz::testing::InputErrorOf;

const std::filesystem::path kBad = std::filesystem::path(PIEZOID_TEST_DATA_DIR) / "bad";

std::string ParamsError(const std::string& name) {
  return InputErrorOf([&] { (void)ReadParamsCsv(kBad / name); });
}

TEST(ParamsCsv, ReadsRowsWithAndWithoutSaturations) {
  const ParamsFile f = ReadParamsCsv(kBad / "params_ok.csv");
  ASSERT_EQ(f.rows.size(), 2u);
  const CaseParams* c1 = f.Find(1);
  ASSERT_NE(c1, nullptr);
  EXPECT_TRUE(c1->has_saturation);
  EXPECT_EQ(c1->params.mu, 95);
  EXPECT_EQ(c1->params.alpha, 0.0025);
  EXPECT_EQ(c1->params.a2, 0.15);
  EXPECT_EQ(c1->params.b1, 1.37);
  EXPECT_EQ(c1->params.b2, -1.5);
  EXPECT_EQ(c1->line, 2);
  const CaseParams* c5 = f.Find(5);
  ASSERT_NE(c5, nullptr);
  EXPECT_FALSE(c5->has_saturation);  // empty b1, b2 cells
  EXPECT_EQ(c5->params.delta, 0.2);
  EXPECT_EQ(f.Find(2), nullptr);

  const ParamsFile g = ReadParamsCsv(kBad / "params_no_saturation.csv");
  ASSERT_EQ(g.rows.size(), 1u);
  EXPECT_EQ(g.rows[0].case_number, 7);
  EXPECT_FALSE(g.rows[0].has_saturation);
}

TEST(ParamsCsv, ErrorsNameFileLineAndColumn) {
  PZ_EXPECT_HAS(ParamsError("params_missing_column.csv"),
                "params_missing_column.csv:1: missing column 'gamma'");
  PZ_EXPECT_HAS(ParamsError("params_not_number.csv"),
                "params_not_number.csv:2: column 'beta' (5): 'six' is not a number");
  PZ_EXPECT_HAS(ParamsError("params_negative_mu.csv"),
                "params_negative_mu.csv:3: column 'mu' (2): mu = -5: must be >= 0");
  PZ_EXPECT_HAS(ParamsError("params_only_b1.csv"),
                "params_only_b1.csv:1: column 'b1' without 'b2'");
  PZ_EXPECT_HAS(ParamsError("params_half_saturation.csv"),
                "params_half_saturation.csv:2: column 'b2' (10): empty while 'b1' is given");
  PZ_EXPECT_HAS(
      ParamsError("params_duplicate_case.csv"),
      "params_duplicate_case.csv:3: column 'case' (1): duplicate case 3 (first on line 2)");
  PZ_EXPECT_HAS(ParamsError("params_nan.csv"),
                "params_nan.csv:2: column 'delta' (3): 'nan' is not finite");
  PZ_EXPECT_HAS(ParamsError("params_positive_b2.csv"),
                "params_positive_b2.csv:2: column 'b2' (10): b2 = 0.2999");
  PZ_EXPECT_HAS(ParamsError("case_empty.csv"), "case_empty.csv: empty file");
  PZ_EXPECT_HAS(ParamsError("missing.csv"), "missing.csv: no such file");
  PZ_EXPECT_HAS(InputErrorOf([] {
                  (void)ParseParamsCsv("case,mu,delta,alpha,beta,gamma,a1,a2\n", "inline");
                }),
                "inline: no data rows");
}

TEST(ParamsCsv, WriteThenReadRoundTripsExactly) {
  std::vector<CaseParams> rows(2);
  rows[0].case_number = 3;
  rows[0].params.mu = 93.534;
  rows[0].params.delta = 0.1 + 0.2;  // not a short decimal: must still round-trip
  rows[0].params.b1 = 1.16;
  rows[0].params.b2 = -1.16;
  rows[0].has_saturation = true;
  rows[1].case_number = 9;
  rows[1].params.gamma = 1.0 / 3.0;
  std::ostringstream out;
  WriteParamsCsv(out, rows);
  EXPECT_EQ(out.str().substr(0, out.str().find('\n')),
            "case,mu,delta,alpha,beta,gamma,a1,a2,b1,b2");
  const ParamsFile back = ParseParamsCsv(out.str(), "roundtrip");
  ASSERT_EQ(back.rows.size(), 2u);
  EXPECT_EQ(back.rows[0].params.delta, 0.1 + 0.2);
  EXPECT_EQ(back.rows[0].params.b1, 1.16);
  EXPECT_TRUE(back.rows[0].has_saturation);
  EXPECT_EQ(back.rows[1].params.gamma, 1.0 / 3.0);
  EXPECT_FALSE(back.rows[1].has_saturation);

  std::ostringstream no_sat;
  WriteParamsCsv(no_sat, std::span(rows).subspan(1));
  EXPECT_EQ(no_sat.str().substr(0, no_sat.str().find('\n')),
            "case,mu,delta,alpha,beta,gamma,a1,a2");
}

}  // namespace
}  // namespace pz::io
