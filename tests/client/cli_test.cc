// The library behind `piezoid simulate` and `piezoid pi`: per-case parameter and saturation
// resolution, scoring with a stand-in simulator (exact PI/CF by construction), the report formats,
// and the commands run in-process (bad input surfaces as pz::InputError → exit code 2 in main.cc).
// The scores' JSON is proto::PiScores (proto/pi.proto); the file of a piezoid before it
// (tests/data/pi-json) reads into it.
#include "tests/testing/cli.h"

#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "client/case_models.h"
#include "client/commands.h"
#include "client/data_root.h"
#include "io/csv.h"
#include "io/proto_json.h"
#include "model/saturation.h"
#include "pi.pb.h"
#include "reports/pi_report.h"
#include "tests/testing/expect_error.h"

namespace pz::client {
namespace {

using pz::testing::InputErrorOf;
namespace fs = std::filesystem;

const fs::path kBad = fs::path(PIEZOID_TEST_DATA_DIR) / "bad";
const fs::path kNominal = fs::path(PIEZOID_DATA_DIR) / "bimorph-fin" / "nominal";

// Parses a command line for a fresh app holding the two commands; returns the exit code they set.
int RunCli(const std::vector<std::string>& args) {
  return pz::testing::RunCommands({RegisterSimulate, RegisterPi}, args);
}

// Flags as a command would have them after parsing args (e.g. {"--b1", "1.2", "--b2", "-1.1"}).
struct ParsedFlags {
  CLI::App app{"test"};
  ParamFlags flags;
  explicit ParsedFlags(const std::vector<std::string>& args) {
    flags.Register(app, "");
    std::vector<const char*> argv = {"test"};
    for (const auto& a : args) argv.push_back(a.c_str());
    app.parse(static_cast<int>(argv.size()), argv.data());
  }
};

// A stand-in plant: the measured angle of the case plus a constant offset, on the drive's grid.
Simulator OffsetSimulator(const io::CaseSet& set, double offset_deg, int failing_case = 0) {
  return
      [&set, offset_deg, failing_case](const model::BimorphParams& p, const model::DriveSignal& d) {
        model::BimorphTrace tr;
        tr.t = model::SampleTimes(d);
        const auto& s = std::get<model::Sinusoid>(d);
        const io::BenchCase* c = nullptr;
        for (const auto& bc : set.cases)
          if (bc.amplitude_v == s.amplitude_v && bc.frequency_hz == s.frequency_hz) c = &bc;
        if (c == nullptr || c->number == failing_case) {
          tr.summary.status = model::SimStatus::kSolverFailure;
          tr.summary.message = "stand-in failure";
          return tr;
        }
        for (double y : c->angle_deg) tr.angle_deg.push_back(y + offset_deg);
        return tr;
      };
}

TEST(ResolveBenchCases, AutoFitsSaturationsFromTheMeasuredExtremes) {
  const io::CaseSet set = io::LoadCaseSet(kNominal);
  ParsedFlags f({});
  const auto models = ResolveBenchCases(f.flags, set);
  ASSERT_EQ(models.size(), 9u);
  for (size_t i = 0; i < models.size(); ++i) {
    const auto ext = model::SaturationFromExtremes(set.cases[i].angle_deg);
    EXPECT_EQ(models[i].params.b1, ext.b1);
    EXPECT_EQ(models[i].params.b2, ext.b2);
    EXPECT_EQ(models[i].saturation_source, "fitted");
    EXPECT_EQ(models[i].params.mu, 95.0);
  }
  // Case 1 reaches its saturation b1 = 1.37 deg; the encoder reads it as 31 quanta of 360/8192 deg.
  EXPECT_EQ(models[0].params.b1, 31 * 360.0 / 8192);
}

TEST(ResolveBenchCases, GivenPaperAndRegressionModes) {
  const io::CaseSet set = io::LoadCaseSet(kNominal);
  {
    ParsedFlags f({"--b1", "1.2", "--b2", "-1.1", "--mu", "90"});
    const auto m = ResolveBenchCases(f.flags, set);
    EXPECT_EQ(m[4].params.b1, 1.2);
    EXPECT_EQ(m[4].params.b2, -1.1);
    EXPECT_EQ(m[4].params.mu, 90.0);
    EXPECT_EQ(m[4].saturation_source, "given");
  }
  {
    ParsedFlags f({"--saturation", "paper"});
    const auto m = ResolveBenchCases(f.flags, set);
    EXPECT_NEAR(m[4].params.b1, 0.00645 * 500 - 0.84771 * 0.5 - 0.63061, 1e-12);
  }
  {
    ParsedFlags f({"--saturation", "regression"});
    const auto m = ResolveBenchCases(f.flags, set);
    EXPECT_EQ(m[0].saturation_source, "regression");
    EXPECT_GT(m[8].params.b1, m[0].params.b1);
  }
  {
    ParsedFlags f({"--params", (kBad / "params_ok.csv").string(), "--saturation", "given"});
    io::CaseSet two = set;
    two.cases = {set.cases[0], set.cases[4]};  // cases 1 and 5 are in params_ok.csv
    const auto m = ResolveBenchCases(f.flags, two);
    EXPECT_EQ(m[0].params.b1, 1.37);
    EXPECT_EQ(m[0].saturation_source, "params file");
    EXPECT_EQ(m[1].params.delta, 0.2);
    EXPECT_EQ(m[1].saturation_source, "default");  // row without b1, b2: the --b1/--b2 defaults
    PZ_EXPECT_HAS(InputErrorOf([&] { (void)ResolveBenchCases(f.flags, set); }),
                  "params_ok.csv: no row for case 2");
  }
  {
    ParsedFlags f({"--b1", "1.2"});
    PZ_EXPECT_HAS(InputErrorOf([&] { (void)ResolveBenchCases(f.flags, set); }),
                  "--b1 given without --b2");
  }
}

TEST(ResolveSinusoidCases, GridIsAmplitudeMajorWithThePapersNumbering) {
  ParsedFlags f({});
  const auto m = ResolveSinusoidCases(f.flags, {375, 500, 750}, {0.25, 0.5, 1.0}, 3, 100);
  ASSERT_EQ(m.size(), 9u);
  EXPECT_EQ(m[4].case_number, 5);
  EXPECT_EQ(m[4].amplitude_v, 500);
  EXPECT_EQ(m[4].frequency_hz, 0.5);
  EXPECT_EQ(m[4].saturation_source, "paper");
  EXPECT_EQ(std::get<model::Sinusoid>(m[0].drive).NumSamples(), 1200);
  PZ_EXPECT_HAS(InputErrorOf([&] { (void)ResolveSinusoidCases(f.flags, {100}, {0.25}, 3, 100); }),
                "case 1 (b1, b2 paper): b1 = ");
  ParsedFlags fitted({"--saturation", "fitted"});
  PZ_EXPECT_HAS(
      InputErrorOf([&] { (void)ResolveSinusoidCases(fitted.flags, {375}, {0.25}, 3, 100); }),
      "needs measured data");
}

TEST(ScoreCaseSet, ExactPiAndCfWithAStandInSimulator) {
  const io::CaseSet set = io::LoadCaseSet(kNominal);
  ParsedFlags f({});
  const auto models = ResolveBenchCases(f.flags, set);
  const reports::PiReport r = ScoreCaseSet(set, models, OffsetSimulator(set, 0.1));
  ASSERT_EQ(r.cases.size(), 9u);
  for (const auto& c : r.cases) {
    ASSERT_TRUE(c.scored);
    EXPECT_NEAR(c.metrics.pi, 0.01 * static_cast<double>(set.Find(c.case_number)->t.size()), 1e-9);
    EXPECT_NEAR(c.metrics.rmse, 0.1, 1e-12);
    EXPECT_NEAR(c.metrics.max_abs, 0.1, 1e-12);
  }
  EXPECT_NEAR(r.cf_train, 0.01 * (1200 + 600 + 300 + 1200), 1e-9);           // cases 1, 5, 6, 7
  EXPECT_NEAR(r.sum_validate, 0.01 * (600 + 300 + 1200 + 600 + 300), 1e-9);  // cases 2, 3, 4, 8, 9
  EXPECT_EQ(r.failed, 0);

  std::ostringstream text;
  reports::PrintPiReport(text, r);
  PZ_EXPECT_HAS(text.str(), "CF = sum of PI over the training cases (1, 5, 6, 7): 33 deg^2");
  PZ_EXPECT_HAS(text.str(), "     500 V      12.0000      6.0000*      3.0000*");
}

TEST(ScoreCaseSet, FailedCasesAreRowsLeftOutOfTheSums) {
  const io::CaseSet set = io::LoadCaseSet(kNominal);
  ParsedFlags f({});
  const reports::PiReport r =
      ScoreCaseSet(set, ResolveBenchCases(f.flags, set), OffsetSimulator(set, 0.1, 5));
  EXPECT_EQ(r.failed, 1);
  EXPECT_FALSE(r.cases[4].scored);
  EXPECT_NEAR(r.cf_train, 0.01 * (1200 + 300 + 1200), 1e-9);
  std::ostringstream text, json, csv;
  reports::PrintPiReport(text, r);
  PZ_EXPECT_HAS(text.str(), "(incomplete: 1 case(s) failed)");
  PZ_EXPECT_HAS(text.str(), "solver_failure: stand-in failure");
  reports::PiReport named = r;  // a folder name that JSON must escape
  named.case_set = "a\"b\\c\nd\x01";
  reports::WritePiJson(json, named);
  PZ_EXPECT_HAS(json.str(), "\"case_set\": \"a\\\"b\\\\c\\nd\\u0001\"");
  PZ_EXPECT_HAS(json.str(), "\"pi_deg2\": null");
  proto::PiScores back;  // reads into its message and prints back to the same bytes
  io::ReadJsonMessage("pi.json", json.str(), &back);
  EXPECT_EQ(io::PrintJson(back, "pi.json"), json.str());
  EXPECT_EQ(back.case_set(), named.case_set);
  EXPECT_EQ(back.failed(), 1);
  ASSERT_EQ(back.cases_size(), 9);
  const proto::PiCaseScore& c5 = back.cases(4);
  EXPECT_EQ(c5.case_(), 5);
  EXPECT_EQ(c5.amplitude_v(), 500);
  EXPECT_EQ(c5.frequency_hz(), 0.5);
  EXPECT_EQ(c5.role(), "train");
  EXPECT_EQ(c5.status(), "solver_failure");
  EXPECT_EQ(c5.message(), "stand-in failure");
  EXPECT_TRUE(std::isnan(c5.pi_deg2()) && std::isnan(c5.rmse_deg()) && std::isnan(c5.r2()));
  EXPECT_EQ(back.cases(3).pi_deg2(), r.cases[3].metrics.pi);
  EXPECT_EQ(back.cf_train_deg2(), r.cf_train);
  reports::WritePiCsv(csv, r);
  PZ_EXPECT_HAS(csv.str(), "\n5,500,0.5,train,");
  PZ_EXPECT_HAS(csv.str(), ",fitted,solver_failure,,,,\n");
}

TEST(ScoreCaseSet, ModelTraceOffTheCaseGridIsNamed) {
  const io::CaseSet set = io::LoadCaseSet(kNominal);
  ParsedFlags f({});
  const auto shifted = [&](const model::BimorphParams& p, const model::DriveSignal& d) {
    model::BimorphTrace tr = OffsetSimulator(set, 0)(p, d);
    for (double& t : tr.t) t += 0.005;
    return tr;
  };
  PZ_EXPECT_HAS(
      InputErrorOf([&] { (void)ScoreCaseSet(set, ResolveBenchCases(f.flags, set), shifted); }),
      "case1.csv vs model trace: time grids differ first at sample 0");
}

TEST(PiJson, TheFileOfAPiezoidBeforeItsMessageReadsIntoIt) {
  // Written by string concatenation, in another key order and layout: every key is the message's,
  // with its value.
  const fs::path file = fs::path(PIEZOID_TEST_DATA_DIR) / "pi-json" / "pi.json";
  proto::PiScores s;
  io::ReadJsonMessage(file.string(), io::ReadTextFile(file), &s);
  EXPECT_EQ(s.case_set(), "data/bimorph-fin/nominal");
  EXPECT_EQ(s.solver(), "modal");
  EXPECT_EQ(s.saturation(), "auto");
  ASSERT_EQ(s.cases_size(), 9);
  EXPECT_EQ(s.cases(0).case_(), 1);
  EXPECT_EQ(s.cases(0).steps(), 1205);
  EXPECT_EQ(s.cases(0).b1_deg(), 1.3623046875);
  EXPECT_EQ(s.cases(0).pi_deg2(), 0.11821669260323361);
  EXPECT_EQ(s.cf_train_deg2(), 0.6377400236487345);
  EXPECT_EQ(s.failed(), 0);
}

TEST(DefaultCaseSet, EnvironmentOverridesTheBundledData) {
  ::unsetenv("PIEZOID_DATA");
  // Found above the test program (build/tests/client/): the source tree's data/, not compiled in.
  EXPECT_TRUE(fs::equivalent(DefaultCaseSetDir(), kNominal)) << DefaultCaseSetDir();
  ::setenv("PIEZOID_DATA", "/elsewhere", 1);
  EXPECT_EQ(DefaultCaseSetDir(), fs::path("/elsewhere/bimorph-fin/nominal"));
  ::unsetenv("PIEZOID_DATA");
}

TEST(DefaultCaseSet, MissingBundledDataSaysWhereItLookedAndWhatToGive) {
  ::setenv("PIEZOID_DATA", "/nonexistent-piezoid-data", 1);
  const std::string e = InputErrorOf(
      [] { CheckBundledData(DefaultCaseSetDir(), "bimorph-fin/nominal", "--cases DIR"); });
  ::unsetenv("PIEZOID_DATA");
  PZ_EXPECT_HAS(e, "the bundled data (/nonexistent-piezoid-data/bimorph-fin/nominal) is not here");
  PZ_EXPECT_HAS(e, "give --cases DIR, or set PIEZOID_DATA");
  // A folder the user gave is left to the reader's own error.
  CheckBundledData("/elsewhere/cases", "bimorph-fin/nominal", "--cases DIR");
  CheckBundledData(DefaultCaseSetDir(), "bimorph-fin/nominal", "--cases DIR");  // it exists
}

TEST(Commands, BadInputThrowsInputErrorNamingTheFile) {
  PZ_EXPECT_HAS(InputErrorOf([] {
                  RunCli({"pi", "--cases", (kBad / "set_unknown_role").string()});
                }),
                "cases.csv:3: column 'role' (5): unknown role 'training'");
  PZ_EXPECT_HAS(InputErrorOf([] {
                  RunCli({"pi", "--cases", kNominal.string(), "--params",
                          (kBad / "params_nan.csv").string()});
                }),
                "params_nan.csv:2: column 'delta' (3)");
  PZ_EXPECT_HAS(InputErrorOf([] {
                  RunCli({"simulate", "--amplitude", "375,500"});
                }),
                "2 cases from sinusoids: give --out DIR");
  PZ_EXPECT_HAS(InputErrorOf([] {
                  RunCli({"simulate", "--input", (kBad / "input_time_back.csv").string()});
                }),
                "input_time_back.csv:4: column 't_s' (1)");
  PZ_EXPECT_HAS(
      InputErrorOf([] {
        RunCli({"simulate", "--input", (kBad / "input_ok.csv").string(), "--saturation", "paper"});
      }),
      "not available for an --input file");
  EXPECT_THROW(RunCli({"simulate", "--cases", kNominal.string(), "--amplitude", "375"}),
               CLI::ParseError);
  EXPECT_THROW(RunCli({"pi", "--params", "p.csv", "--mu", "3"}), CLI::ParseError);
}

TEST(Commands, PiPrintsTheTableAndWritesJson) {
  const fs::path json = fs::path(::testing::TempDir()) / "pi_cli_test.json";
  fs::remove(json);
  ::testing::internal::CaptureStdout();
  const int code = RunCli({"pi", "--json", json.string()});
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(code, 0) << out;
  PZ_EXPECT_HAS(out, "(9 cases), solver modal, saturation auto");
  PZ_EXPECT_HAS(out, "CF = sum of PI over the training cases (1, 5, 6, 7)");
  proto::PiScores s;
  io::ReadJsonMessage(json.string(), io::ReadTextFile(json), &s);
  EXPECT_EQ(s.cases_size(), 9);
  EXPECT_EQ(s.solver(), "modal");
  EXPECT_EQ(s.failed(), 0);
  EXPECT_GT(s.cf_train_deg2(), 0);
}

TEST(Commands, SimulateWritesOneCsvPerCase) {
  const fs::path out = fs::path(::testing::TempDir()) / "simulate_cli_test";
  fs::remove_all(out);
  ::testing::internal::CaptureStdout();
  const int code =
      RunCli({"simulate", "--amplitude", "375", "--frequency", "1,2", "--out", out.string()});
  const std::string log = ::testing::internal::GetCapturedStdout();
  PZ_EXPECT_HAS(log, "case 1: sinusoid 375 V 1 Hz x3 @100 Hz");
  PZ_EXPECT_HAS(log, "case 2: sinusoid 375 V 2 Hz x3 @100 Hz");
  EXPECT_EQ(code, 0) << log;
  for (const char* name : {"case1.csv", "case2.csv"}) {
    std::ifstream in(out / name);
    std::string header;
    std::getline(in, header);
    EXPECT_EQ(header, "t_s,voltage_V,z_N,w_tip_m,theta_linear_deg,angle_deg") << name;
  }
}

// The nominal bench was made with the spec's plant at the nominal parameters, then read through a
// 2048-line encoder (quantum q = 360/8192 deg) with 0.003 deg jitter. The nominal model with fitted
// saturations must therefore match it to quantisation level: per sample the error is about q/√12 =
// 0.0127 deg RMS and at most about q = 0.044 deg. (Measured on the modal path: CF = 0.638 deg².)
TEST(ScoreCaseSet, NominalParametersMatchTheNominalBenchToQuantisationLevel) {
  const io::CaseSet set = io::LoadCaseSet(kNominal);
  ParsedFlags f({});
  const reports::PiReport r =
      ScoreCaseSet(set, ResolveBenchCases(f.flags, set), PlantSimulator(model::Solver::kModal));
  ASSERT_EQ(r.failed, 0);
  const double q = 360.0 / 8192;
  for (const auto& c : r.cases) {
    EXPECT_LT(c.metrics.rmse, q) << "case " << c.case_number;
    EXPECT_LT(c.metrics.max_abs, 1.5 * q) << "case " << c.case_number;
  }
  EXPECT_LT(r.cf_train, 1.0);
}

}  // namespace
}  // namespace pz::client
