// Bench case sets: the bundled nominal set loads as the spec describes it, and every malformed file
// in tests/data/bad/ (see its README.md) is rejected with a message naming file, line and column.
#include "io/bench_data.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>

#include "tests/testing/expect_error.h"

namespace pz::io {
namespace {

using pz::testing::InputErrorOf;

const std::filesystem::path kBad = std::filesystem::path(PIEZOID_TEST_DATA_DIR) / "bad";
const std::filesystem::path kNominal =
    std::filesystem::path(PIEZOID_DATA_DIR) / "bimorph-fin" / "nominal";

std::string CaseFileError(const std::string& name, double frequency_hz = 25) {
  return InputErrorOf(
      [&] { (void)LoadCaseFile(kBad / name, 1, 10, frequency_hz, CaseRole::kTrain); });
}
std::string SetError(const std::string& folder) {
  return InputErrorOf([&] { (void)LoadCaseSet(kBad / folder); });
}

TEST(NominalCaseSet, HasNineCasesWithThePapersSplitAndLengths) {
  const CaseSet set = LoadCaseSet(kNominal);
  ASSERT_EQ(set.cases.size(), 9u);
  const double amplitudes[] = {375, 500, 750}, frequencies[] = {0.25, 0.5, 1.0};
  const size_t samples[] = {1200, 600, 300};
  for (int i = 0; i < 9; ++i) {
    const BenchCase& c = set.cases[i];
    EXPECT_EQ(c.number, i + 1);
    EXPECT_EQ(c.amplitude_v, amplitudes[i / 3]);
    EXPECT_EQ(c.frequency_hz, frequencies[i % 3]);
    EXPECT_EQ(c.t.size(), samples[i % 3]) << "case " << c.number;
    EXPECT_EQ(c.u.size(), c.t.size());
    EXPECT_EQ(c.angle_deg.size(), c.t.size());
    EXPECT_NEAR(c.sample_rate_hz, 100.0, 1e-9);
    EXPECT_EQ(c.file.filename(), "case" + std::to_string(i + 1) + ".csv");
  }
  std::vector<int> train;
  for (const BenchCase* c : set.Training()) train.push_back(c->number);
  EXPECT_EQ(train, (std::vector<int>{1, 5, 6, 7}));
  std::vector<int> validate;
  for (const BenchCase* c : set.Validation()) validate.push_back(c->number);
  EXPECT_EQ(validate, (std::vector<int>{2, 3, 4, 8, 9}));
  EXPECT_TRUE(set.Test().empty());
  ASSERT_NE(set.Find(6), nullptr);
  EXPECT_EQ(set.Find(6)->role, CaseRole::kTrain);
  EXPECT_EQ(set.Find(10), nullptr);
}

TEST(NominalCaseSet, DriveReproducesTheRecordedGridAndVoltage) {
  const CaseSet set = LoadCaseSet(kNominal);
  for (const BenchCase& c : set.cases) {
    const model::DriveSignal d = c.Drive();
    const std::vector<double> t = model::SampleTimes(d), u = model::SampleValues(d);
    ASSERT_EQ(t.size(), c.t.size()) << "case " << c.number;
    for (size_t k = 0; k < t.size(); ++k) {
      ASSERT_NEAR(t[k], c.t[k], 1e-9);
      ASSERT_NEAR(u[k], c.u[k], 1e-8 * c.amplitude_v);
    }
  }
  // Spot values of case 1 (first and last rows of case1.csv).
  const BenchCase& c1 = set.cases[0];
  EXPECT_EQ(c1.t[1], 0.01);
  EXPECT_EQ(c1.u[1], 5.89024399193);
  EXPECT_EQ(c1.t.back(), 11.99);
  EXPECT_EQ(c1.angle_deg.back(), -0.6591796875);
}

TEST(AllBundledCaseSets, Load) {
  for (const char* name : {"nominal", "driver-lowpass", "creep", "hinge-friction", "delay"}) {
    const CaseSet set = LoadCaseSet(std::filesystem::path(PIEZOID_DATA_DIR) / "bimorph-fin" / name);
    EXPECT_EQ(set.cases.size(), 9u) << name;
  }
}

TEST(CaseSetFormat, CrlfBomAndBlankTrailingLinesAreAccepted) {
  const CaseSet set = LoadCaseSet(kBad / "set_ok");
  ASSERT_EQ(set.cases.size(), 3u);
  EXPECT_EQ(set.cases[1].role, CaseRole::kValidate);
  EXPECT_EQ(set.cases[2].role, CaseRole::kTest);
  EXPECT_EQ(set.cases[1].t.size(), 12u);
  EXPECT_EQ(set.cases[0].angle_deg, set.cases[1].angle_deg);  // same data, LF vs CRLF+BOM
  EXPECT_NEAR(set.cases[0].sample_rate_hz, 100, 1e-9);
}

TEST(ManifestErrors, NameFileLineAndColumn) {
  PZ_EXPECT_HAS(SetError("set_missing_column"),
                "set_missing_column/cases.csv:1: missing column 'frequency_Hz'");
  PZ_EXPECT_HAS(SetError("set_unknown_role"),
                "cases.csv:3: column 'role' (5): unknown role 'training'");
  PZ_EXPECT_HAS(SetError("set_duplicate_case"),
                "cases.csv:3: column 'case' (1): duplicate case 1 (first on line 2)");
  PZ_EXPECT_HAS(SetError("set_missing_file"),
                "cases.csv:3: column 'file' (4): case file 'case2.csv' not found");
  PZ_EXPECT_HAS(SetError("set_not_number"),
                "cases.csv:2: column 'frequency_Hz' (3): '2S' is not a number");
  PZ_EXPECT_HAS(SetError("set_case_not_integer"),
                "cases.csv:2: column 'case' (1): '1.5' is not an integer");
  PZ_EXPECT_HAS(SetError("set_ragged"), "cases.csv:2: 4 fields, expected 5");
  PZ_EXPECT_HAS(SetError("set_no_cases"), "cases.csv: no data rows");
  PZ_EXPECT_HAS(SetError("set_empty_manifest"), "cases.csv: empty file");
  PZ_EXPECT_HAS(SetError("no_such_set"), "no_such_set: not a directory");
  PZ_EXPECT_HAS(SetError("case_empty.csv"), "not a directory");
}

TEST(ManifestErrors, CaseFileErrorsNameTheCaseFileAndTheManifestLine) {
  const std::string e = SetError("set_bad_case_file");
  PZ_EXPECT_HAS(
      e,
      "case_voltage_mismatch.csv:7: column 'voltage_V' (2): 7.5 V is not V sin(2 pi f t) = 10 V");
  PZ_EXPECT_HAS(e, "case 2 of");
  PZ_EXPECT_HAS(e, "cases.csv line 3");
  PZ_EXPECT_HAS(SetError("set_wrong_frequency"),
                "12 samples, expected round(3 cycles * 100 Hz / 50 Hz) = 6");
}

TEST(CaseFileErrors, NameFileLineAndColumn) {
  PZ_EXPECT_HAS(CaseFileError("case_missing_column.csv"),
                "case_missing_column.csv:1: missing column 'angle_deg' (columns: t_s, voltage_V)");
  PZ_EXPECT_HAS(CaseFileError("case_not_number.csv"),
                "case_not_number.csv:6: column 'angle_deg' (3): 'abc' is not a number");
  PZ_EXPECT_HAS(CaseFileError("case_nan.csv"),
                "case_nan.csv:8: column 'angle_deg' (3): 'nan' is not finite");
  PZ_EXPECT_HAS(CaseFileError("case_inf.csv"),
                "case_inf.csv:4: column 'voltage_V' (2): 'inf' is not finite");
  PZ_EXPECT_HAS(CaseFileError("case_empty_field.csv"),
                "case_empty_field.csv:5: column 'angle_deg' (3): empty field");
  PZ_EXPECT_HAS(CaseFileError("case_time_not_increasing.csv"),
                "case_time_not_increasing.csv:7: column 't_s' (1): time 0.04 s is not after the "
                "previous sample's 0.04 s");
  PZ_EXPECT_HAS(CaseFileError("case_time_off_rate.csv"),
                "case_time_off_rate.csv:9: column 't_s' (1): step 0.015");
  PZ_EXPECT_HAS(CaseFileError("case_time_off_rate.csv"),
                "differs from the first step 0.01 s (sample rate 100 Hz");
  PZ_EXPECT_HAS(CaseFileError("case_not_from_zero.csv"),
                "case_not_from_zero.csv:2: column 't_s' (1): the first sample time is 0.01 s");
  PZ_EXPECT_HAS(CaseFileError("case_voltage_mismatch.csv"),
                "case_voltage_mismatch.csv:7: column 'voltage_V' (2): 7.5 V is not V sin(2 pi f t) "
                "= 10 V (V = 10 V, f = 25 Hz, t = 0.05 s");
  PZ_EXPECT_HAS(
      CaseFileError("case_sample_count.csv"),
      "case_sample_count.csv: 11 samples, expected round(3 cycles * 100 Hz / 25 Hz) = 12");
  PZ_EXPECT_HAS(CaseFileError("case_ragged.csv"),
                "case_ragged.csv:10: 4 fields, expected 3 (t_s, voltage_V, angle_deg)");
  PZ_EXPECT_HAS(CaseFileError("case_blank_middle.csv"),
                "case_blank_middle.csv:8: blank line inside the data");
  PZ_EXPECT_HAS(CaseFileError("case_empty.csv"), "case_empty.csv: empty file");
  PZ_EXPECT_HAS(CaseFileError("case_header_only.csv"), "case_header_only.csv: 0 data rows");
  PZ_EXPECT_HAS(CaseFileError("case_quoted.csv"),
                "case_quoted.csv:4: quoted fields are not supported");
  PZ_EXPECT_HAS(CaseFileError("no_such_file.csv"), "no_such_file.csv: no such file");
}

TEST(CaseFileOptions, ChecksCanBeRelaxed) {
  BenchReadOptions lax;
  lax.cycles = 0;
  lax.check_voltage = false;
  EXPECT_EQ(LoadCaseFile(kBad / "case_sample_count.csv", 1, 10, 25, CaseRole::kTrain, lax).t.size(),
            11u);
  EXPECT_NO_THROW(
      (void)LoadCaseFile(kBad / "case_voltage_mismatch.csv", 1, 10, 25, CaseRole::kTrain, lax));
  BenchReadOptions bad;
  bad.time_rel_tol = 0;
  PZ_EXPECT_HAS(InputErrorOf([&] {
                  (void)LoadCaseFile(kBad / "tiny_case.csv", 1, 10, 25, CaseRole::kTrain, bad);
                }),
                "time_rel_tol = 0");
}

// The one builder of a bench case (the file reader's, and the hgann and diagnose job kinds' from a
// spec): a case given without its drive gets the stated V sin(2 pi f k / fs) on t = k / fs; the
// stated cycles make its drive and are checked against the sample count; every error names the
// spec's field and sample.
TEST(MakeBenchCase, BuildsTheStatedDriveAndNamesTheSpecsFields) {
  BenchReadOptions o;
  o.cycles = 0;
  o.check_voltage = false;
  BenchCaseSamples s;
  s.number = 3;
  s.amplitude_v = 375;
  s.frequency_hz = 7;
  s.sample_rate_hz = 1000;
  s.role = CaseRole::kTest;
  s.angle_deg.assign(429, 0.5);
  const BenchCase c = MakeBenchCase(s, o, SpecCaseWhere("hgann.cases[0]"));
  ASSERT_EQ(c.t.size(), 429u);
  ASSERT_EQ(c.u.size(), 429u);
  for (size_t k = 0; k < c.t.size(); ++k) {
    EXPECT_EQ(c.t[k], static_cast<double>(k) / 1000);
    EXPECT_EQ(c.u[k], 375 * std::sin(2 * std::numbers::pi * 7 * c.t[k]));
  }
  EXPECT_EQ(c.role, CaseRole::kTest);
  EXPECT_EQ(c.Drive().cycles, 429 * 7 / 1000.0);  // N f / fs unless stated
  BenchCaseSamples stated = s;
  stated.cycles = 3;  // round(3 * 1000 / 7) = 429
  EXPECT_EQ(MakeBenchCase(stated, o, SpecCaseWhere("diagnose.cases[1]")).Drive().cycles, 3.0);
  stated.cycles = 2;
  PZ_EXPECT_HAS(InputErrorOf([&] { MakeBenchCase(stated, o, SpecCaseWhere("diagnose.cases[1]")); }),
                "diagnose.cases[1]: 429 samples, expected round(2 cycles * 1000 Hz / 7 Hz) = 286");
  BenchCaseSamples bad = s;
  bad.angle_deg[5] = NAN;
  PZ_EXPECT_HAS(InputErrorOf([&] { MakeBenchCase(bad, o, SpecCaseWhere("hgann.cases[2]")); }),
                "hgann.cases[2].angle_deg[5]: nan deg must be finite");
  bad = s;
  bad.u.assign(428, 0.0);
  PZ_EXPECT_HAS(InputErrorOf([&] { MakeBenchCase(bad, o, SpecCaseWhere("hgann.cases[2]")); }),
                "hgann.cases[2].voltage_v: 428 drive samples for 429 angle samples");
  bad.u.assign(429, 0.0);
  bad.u[7] = INFINITY;
  PZ_EXPECT_HAS(InputErrorOf([&] { MakeBenchCase(bad, o, SpecCaseWhere("hgann.cases[2]")); }),
                "hgann.cases[2].voltage_v[7]: inf V must be finite");
  bad = s;
  bad.sample_rate_hz = 0;
  PZ_EXPECT_HAS(InputErrorOf([&] { MakeBenchCase(bad, o, SpecCaseWhere("hgann.cases[2]")); }),
                "hgann.cases[2].sample_rate_hz: sample rate 0 Hz must be finite and > 0");
  // The recorded drive, when given, is kept and (with the check on) compared with the stated one.
  bad = s;
  bad.u.assign(429, 0.0);
  o.check_voltage = true;
  PZ_EXPECT_HAS(InputErrorOf([&] { MakeBenchCase(bad, o, SpecCaseWhere("hgann.cases[2]")); }),
                "hgann.cases[2].voltage_v[1]: 0 V is not V sin(2 pi f t)");
}

TEST(CaseRoles, RoundTripNames) {
  for (CaseRole r : {CaseRole::kTrain, CaseRole::kValidate, CaseRole::kTest})
    EXPECT_EQ(ParseCaseRole(CaseRoleName(r)), r);
  EXPECT_FALSE(ParseCaseRole("Train").has_value());
}

}  // namespace
}  // namespace pz::io
