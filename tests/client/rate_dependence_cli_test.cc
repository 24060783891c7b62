// The effect `rate-dependence` through the command line (issue 22): `piezoid synth-stack` writes a
// rate-dependent plant's records at several rates with its truth; `piezoid fit --effects
// rate-dependence` writes fit.json, which reads back (reports/fit_file.h LoadFit) with the effect
// and its fitted parameters, and `piezoid compensate --replay` runs the model's inverse with it; on
// a set trained at one rate the fit is refused.
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>

#include "client/commands.h"
#include "io/csv.h"
#include "reports/fit_file.h"
#include "tests/testing/cli.h"
#include "tests/testing/expect_error.h"

namespace pz::client {
namespace {

namespace fs = std::filesystem;

int RunCli(const std::vector<std::string>& args) {
  return pz::testing::RunCommands({RegisterSynthStack, RegisterFit, RegisterCompensate}, args);
}

std::string Captured(const std::vector<std::string>& args) {
  return pz::testing::CapturedCommands({RegisterSynthStack, RegisterFit, RegisterCompensate}, args);
}

const std::vector<std::string> kPlant = {
    "--seed", "1",          "--no-creep", "--lag-samples", "0",    "--train-s", "4", "--withheld-s",
    "4",      "--rate-lag", "4",          "--rate-time",   "0.005"};
const std::vector<std::string> kQuickFit = {
    "--family",     "preisach", "--effects",     "rate-dependence",
    "--settle-s",   "1.5",      "--repetitions", "1",
    "--particles",  "6",        "--iterations",  "6",
    "--no-figures", "--quiet"};

std::vector<std::string> Join(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

TEST(RateDependenceCli, FitJsonRoundTripsAndCompensates) {
  const fs::path dir = fs::path(::testing::TempDir()) / "rate_dependence_cli";
  fs::remove_all(dir);
  Captured(Join({"synth-stack", "--out", (dir / "set").string(), "--train-frequencies", "0.5,2,8",
                 "--withheld-frequencies", "4", "--chirp"},
                kPlant));
  const std::string truth = io::ReadTextFile(dir / "set" / "truth.json");
  EXPECT_NE(truth.find("\"rate_lag_V\": 4"), std::string::npos) << truth;
  EXPECT_TRUE(fs::exists(dir / "set" / "train-8hz.csv"));
  EXPECT_TRUE(fs::exists(dir / "set" / "chirp.csv"));
  Captured(Join({"fit", "--records", (dir / "set").string(), "--out", (dir / "fit").string()},
                kQuickFit));
  const records::ModelSpec m = reports::LoadFit((dir / "fit" / "fit.json").string());
  ASSERT_EQ(m.effects.size(), 1u);
  EXPECT_EQ(m.effects[0], model::EffectKind::Named("rate-dependence"));
  ASSERT_GE(m.params.size(), 2u);
  const double r_m = m.params[m.params.size() - 2], tau = m.params.back();
  EXPECT_GT(r_m, 0);
  EXPECT_GT(tau, 0);
  EXPECT_NE(io::ReadTextFile(dir / "fit" / "fit.json").find("\"rate-dependence.tau_r_s\""),
            std::string::npos);
  const std::string out = Captured({"compensate", "--model", (dir / "fit" / "fit.json").string(),
                                    "--replay", (dir / "set" / "sine-4hz.csv").string()});
  const size_t at = out.find("through the local gain ");
  ASSERT_NE(at, std::string::npos) << out;
  EXPECT_TRUE(std::isfinite(std::stod(out.substr(at + 23)))) << out;
  // A lag over a quarter sample: the compensator plans two samples, and says so.
  const bool plans = tau > 0.25 * m.dt;
  EXPECT_EQ(out.find("the compensator plans two samples instead") != std::string::npos, plans)
      << out;
}

TEST(RateDependenceCli, ATrainingSetAtOneRateIsRefused) {
  const fs::path dir = fs::path(::testing::TempDir()) / "rate_dependence_cli_one_rate";
  fs::remove_all(dir);
  Captured(Join({"synth-stack", "--out", (dir / "set").string()}, kPlant));
  const std::string e = testing::InputErrorOf([&] {
    RunCli(Join({"fit", "--records", (dir / "set").string(), "--out", (dir / "fit").string()},
                kQuickFit));
  });
  PZ_EXPECT_HAS(e, "effect 'rate-dependence' needs training records that cover rates");
  PZ_EXPECT_HAS(e, "(1×)");
  EXPECT_FALSE(fs::exists(dir / "fit" / "fit.json"));
}

}  // namespace
}  // namespace pz::client
