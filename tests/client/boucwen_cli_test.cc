// `piezoid boucwen` run in-process on the bundled benchmark data with a tiny search: the true model
// reproduces the benchmark's floor (the integrator matches the generator), the search improves on
// its first swarm, the result does not depend on the thread count, and bad input is refused.
#include <gtest/gtest.h>
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "client/commands.h"

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

google::protobuf::Struct ReadReport(const fs::path& dir) {
  std::ifstream in(dir / "report.json");
  std::stringstream ss;
  ss << in.rdbuf();
  google::protobuf::Struct s;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(ss.str(), &s).ok()) << ss.str();
  return s;
}

double Num(const google::protobuf::Struct& s, const std::string& key) {
  const auto it = s.fields().find(key);
  EXPECT_NE(it, s.fields().end()) << key;
  return it == s.fields().end() ? 0.0 : it->second.number_value();
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
  EXPECT_LT(Num(a, "true_model_multisine_rms_m"), 3e-7);
  EXPECT_LT(Num(a, "true_model_sinesweep_rms_m"), 4e-6);
  EXPECT_EQ(Num(a, "evaluations"), Num(b, "evaluations"));
  EXPECT_EQ(Num(a, "training_rms_m"), Num(b, "training_rms_m"));  // bit for bit
  EXPECT_EQ(Num(a, "test_multisine_rms_m"), Num(b, "test_multisine_rms_m"));
  const auto& pa = a.fields().at("parameters").struct_value().fields();
  const auto& pb = b.fields().at("parameters").struct_value().fields();
  ASSERT_EQ(pa.size(), 6u);
  for (const auto& [name, v] : pa)
    EXPECT_EQ(v.struct_value().fields().at("identified").number_value(),
              pb.at(name).struct_value().fields().at("identified").number_value())
        << name;
  // The search improves on its first swarm (convergence.csv: evaluations, best RMS, time).
  std::ifstream conv(root / "t1" / "convergence.csv");
  std::string line;
  std::getline(conv, line);
  std::vector<double> best;
  while (std::getline(conv, line)) best.push_back(std::stod(line.substr(line.find(',') + 1)));
  ASSERT_GE(best.size(), 2u);
  EXPECT_LT(best.back(), best.front());
  EXPECT_DOUBLE_EQ(best.back(), Num(a, "training_rms_m"));
}

TEST(BoucwenCli, BadInputIsRefused) {
  const fs::path root = fs::path(::testing::TempDir()) / "boucwen_cli_bad";
  EXPECT_THROW(RunBoucwen({"--algorithm", "simplex", "--out", root.string()}), CLI::ParseError);
  EXPECT_ANY_THROW(RunBoucwen({"--data-dir", (root / "missing").string(), "--iterations", "2",
                               "--out", root.string(), "--no-plots"}));
}

}  // namespace
}  // namespace pz::client
