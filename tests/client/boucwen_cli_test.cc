// `piezoid boucwen` run in-process on the bundled benchmark data with a tiny search: the true model
// reproduces the benchmark's floor (the integrator matches the generator), the search improves on
// its first swarm, the result does not depend on the thread count, and bad input is refused.
// report.json is proto::BoucwenReport (proto/boucwen.proto): it reads back into its message and
// prints to the same bytes, as does the file of a piezoid before it (tests/data/boucwen-json).
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "boucwen.pb.h"
#include "client/commands.h"
#include "io/csv.h"
#include "io/proto_json.h"
#include "tests/testing/expect_error.h"

namespace pz::client {
namespace {

namespace fs = std::filesystem;
const fs::path kData = fs::path(PIEZOID_DATA_DIR) / "boucwen-benchmark";

int RunBoucwen(const std::vector<std::string>& args) {
  CLI::App app{"piezoid"};
  app.require_subcommand(1);
  int exit_code = 0;
  RegisterBoucwen(app, exit_code);
  std::vector<const char*> argv = {"piezoid", "boucwen"};
  for (const auto& a : args) argv.push_back(a.c_str());
  app.parse(static_cast<int>(argv.size()), argv.data());
  return exit_code;
}

/// report.json read into its message (an unknown or mistyped field fails), which prints back to the
/// file's bytes.
proto::BoucwenReport ReadReport(const fs::path& dir) {
  const std::string text = io::ReadTextFile(dir / "report.json");
  proto::BoucwenReport r;
  io::ReadJsonMessage("report.json", text, &r);
  EXPECT_EQ(io::PrintJson(r, "report.json"), text);
  return r;
}

std::vector<std::string> Tiny(const fs::path& out, int threads) {
  return {"--algorithm",
          "pso",
          "--iterations",
          "6",
          "--population",
          "8",
          "--repetitions",
          "1",
          "--train-periods",
          "1",
          "--threads",
          std::to_string(threads),
          "--data-dir",
          kData.string(),
          "--out",
          out.string(),
          "--no-plots",
          "--progress",
          "0"};
}

TEST(BoucwenCli, TinyRunWritesAReportAndDoesNotDependOnThreads) {
  const fs::path root = fs::path(::testing::TempDir()) / "boucwen_cli";
  fs::remove_all(root);
  ASSERT_EQ(RunBoucwen(Tiny(root / "t1", 1)), 0);
  ASSERT_EQ(RunBoucwen(Tiny(root / "t2", 2)), 0);
  const auto a = ReadReport(root / "t1");
  const auto b = ReadReport(root / "t2");
  // The true parameters reproduce the benchmark's own floor (README: about 2.3e-7 m on the
  // multisine).
  EXPECT_LT(a.true_model_multisine_rms_m(), 3e-7);
  EXPECT_LT(a.true_model_sinesweep_rms_m(), 4e-6);
  EXPECT_EQ(a.evaluations(), b.evaluations());
  EXPECT_EQ(a.training_rms_m(), b.training_rms_m());  // bit for bit
  EXPECT_EQ(a.test_multisine_rms_m(), b.test_multisine_rms_m());
  EXPECT_EQ(a.threads(), 1);
  EXPECT_EQ(b.threads(), 2);
  ASSERT_EQ(a.parameters_size(), 6);
  for (const auto& [name, p] : a.parameters()) {
    ASSERT_TRUE(b.parameters().contains(name)) << name;
    EXPECT_EQ(p.identified(), b.parameters().at(name).identified()) << name;
    EXPECT_EQ(p.relative_error(), p.identified() / p.true_() - 1) << name;
    EXPECT_TRUE(p.lower() <= p.identified() && p.identified() <= p.upper()) << name;
  }
  ASSERT_EQ(a.repetition_training_rms_m_size(), 1);
  EXPECT_EQ(a.repetition_training_rms_m(0), a.training_rms_m());
  // The search improves on its first swarm (convergence.csv: evaluations, best RMS, time).
  std::ifstream conv(root / "t1" / "convergence.csv");
  std::string line;
  std::getline(conv, line);
  std::vector<double> best;
  while (std::getline(conv, line)) best.push_back(std::stod(line.substr(line.find(',') + 1)));
  ASSERT_GE(best.size(), 2u);
  EXPECT_LT(best.back(), best.front());
  EXPECT_DOUBLE_EQ(best.back(), a.training_rms_m());
}

TEST(BoucwenReportJson, TheFileOfAPiezoidBeforeItsMessageReadsAndPrintsBackToTheSameBytes) {
  const fs::path file = fs::path(PIEZOID_TEST_DATA_DIR) / "boucwen-json" / "report.json";
  const std::string text = io::ReadTextFile(file);
  proto::BoucwenReport r;
  io::ReadJsonMessage(file.string(), text, &r);
  EXPECT_EQ(io::PrintJson(r, "report.json"), text);
  EXPECT_EQ(r.algorithm(), "pso");
  EXPECT_EQ(r.seed(), 1u);
  EXPECT_EQ(r.evaluations(), 112);
  EXPECT_EQ(r.repetition_training_rms_m_size(), 2);
  ASSERT_TRUE(r.parameters().contains("beta_delta"));
  EXPECT_EQ(r.parameters().at("beta_delta").true_(), -1100);
  // A key the message does not have is named.
  std::string bad = text;
  bad.replace(bad.find("\"stop_reason\""), 13, "\"stop_raeson\"");
  const std::string e =
      pz::testing::InputErrorOf([&] { io::ReadJsonMessage("x/report.json", bad, &r); });
  PZ_EXPECT_HAS(e, "x/report.json");
  PZ_EXPECT_HAS(e, "stop_raeson");
}

TEST(BoucwenCli, BadInputIsRefused) {
  const fs::path root = fs::path(::testing::TempDir()) / "boucwen_cli_bad";
  EXPECT_THROW(RunBoucwen({"--algorithm", "simplex", "--out", root.string()}), CLI::ParseError);
  EXPECT_ANY_THROW(RunBoucwen({"--data-dir", (root / "missing").string(), "--iterations", "2",
                               "--out", root.string(), "--no-plots"}));
}

}  // namespace
}  // namespace pz::client
