// `piezoid synth-stack` and the excitation report of `piezoid fit` (issue 22, items 5 and 3): the
// set is written in the record format with its truth; the fit prints what the withheld records need
// beyond the training, writes the Excitation section, the JSON object and the proposed drive; that
// drive, played on the plant by synth-stack --train-drive, leaves no reversal the training lacks.
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>
#include <vector>

#include "client/commands.h"
#include "tests/testing/cli.h"
#include "tests/testing/expect_error.h"

namespace pz::client {
namespace {

namespace fs = std::filesystem;

int RunCli(const std::vector<std::string>& args) {
  return pz::testing::RunCommands({RegisterSynthStack, RegisterFit}, args);
}

std::string Read(const fs::path& p) {
  std::ifstream in(p);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Runs the command with stdout captured; returns what it printed.
std::string Captured(const std::vector<std::string>& args) {
  return pz::testing::CapturedCommands({RegisterSynthStack, RegisterFit}, args);
}

TEST(SynthStack, WritesTheSetWithItsTruthAndTheFitReportsItsExcitation) {
  const fs::path dir = fs::path(::testing::TempDir()) / "synth_stack_cli";
  fs::remove_all(dir);
  const std::string set = (dir / "set").string(), fit = (dir / "fit").string();
  PZ_EXPECT_HAS(
      Captured({"synth-stack", "--out", set, "--train-s", "8", "--withheld-s", "6", "--seed", "3"}),
      "written 4 records");
  PZ_EXPECT_HAS(Read(dir / "set" / "manifest.csv"), "ramp,ramp.csv,validate");
  const std::string truth = Read(dir / "set" / "truth.json");
  PZ_EXPECT_HAS(truth, "\"realised_um\"");
  PZ_EXPECT_HAS(truth, "\"lag_samples\": 1.35");
  PZ_EXPECT_HAS(Read(dir / "set" / "README.md"), "piezoid synth-stack --out");

  const std::string out = Captured({"fit", "--records", set, "--family", "prandtl-ishlinskii",
                                    "--out", fit, "--no-figures", "--quiet"});
  PZ_EXPECT_HAS(out, "excitation: ramp needs");
  PZ_EXPECT_HAS(out, "excitation: reversals needs");
  EXPECT_EQ(out.find("excitation: major-2"), std::string::npos) << out;
  const std::string report = Read(dir / "fit" / "report.md");
  PZ_EXPECT_HAS(report, "## Excitation (before fitting)");
  PZ_EXPECT_HAS(report, "| major-2 | ");
  PZ_EXPECT_HAS(report, "nothing: within the training excitation");
  const std::string json = Read(dir / "fit" / "fit.json");
  PZ_EXPECT_HAS(json, "\"excitation\"");
  PZ_EXPECT_HAS(json, "\"kind\": \"reversals\"");
  std::ifstream drive(dir / "fit" / "excitation_drive.csv");
  std::string header, line;
  std::getline(drive, header);
  EXPECT_EQ(header, "t_s,drive_V");
  size_t rows = 0;
  while (std::getline(drive, line)) ++rows;
  EXPECT_GT(rows, 200u * 20);  // tens of seconds at 200 Hz

  // The figures' data and scripts (rendered when gnuplot is there): loops less the training line,
  // error against reversal depth, the error averaged over a period (creep).
  const std::string figured = (dir / "fig").string();
  Captured({"fit", "--records", set, "--family", "preisach", "--out", figured, "--quiet"});
  for (const char* f :
       {"loop_ramp.gp", "error_vs_depth.gp", "creep.gp", "depth_ramp.csv", "depth_major.csv"})
    EXPECT_TRUE(fs::exists(dir / "fig" / "figures" / f)) << f;
  std::ifstream trace(dir / "fig" / "figures" / "trace_ramp.csv");
  std::getline(trace, header);
  PZ_EXPECT_HAS(header, ",error_mean_");
  PZ_EXPECT_HAS(header, ",measured_less_line_um,model_less_line_um");
  PZ_EXPECT_HAS(Read(dir / "fig" / "figures" / "loop_ramp.gp"),
                "\"trace_major.csv\" using 2:9");  // major loop behind
  const std::string figured_report = Read(dir / "fig" / "report.md");
  PZ_EXPECT_HAS(figured_report, "## Figures (figures/)");
  PZ_EXPECT_HAS(figured_report, "`creep.png`: the error averaged over");

  // Play the proposed drive as the training record: the withheld records need no reversals then.
  const std::string set2 = (dir / "set2").string(), fit2 = (dir / "fit2").string();
  Captured({"synth-stack", "--out", set2, "--train-s", "8", "--withheld-s", "6", "--seed", "3",
            "--train-drive", (dir / "fit" / "excitation_drive.csv").string()});
  PZ_EXPECT_HAS(Read(dir / "set2" / "manifest.csv"), "played,played.csv,train");
  EXPECT_EQ(Read(dir / "set2" / "ramp.csv"),
            Read(dir / "set" / "ramp.csv"));  // the same withheld records
  const std::string out2 = Captured({"fit", "--records", set2, "--family", "prandtl-ishlinskii",
                                     "--out", fit2, "--no-figures", "--quiet"});
  EXPECT_EQ(out2.find("of its reversal cycles turn where training has none"), std::string::npos)
      << out2;

  // The settling window: scored from 0.5 s after each rest, and the report says so.
  const std::string settled =
      Captured({"fit", "--records", set, "--family", "preisach", "--settle-s", "0.5", "--out",
                (dir / "settled").string(), "--no-figures", "--quiet"});
  PZ_EXPECT_HAS(Read(dir / "settled" / "report.md"),
                "Every record is scored from 0.5 s after the end of its rest");
  PZ_EXPECT_HAS(Read(dir / "settled" / "report.md"), "| ramp | validate | 1.5–");
  PZ_EXPECT_HAS(Read(dir / "settled" / "fit.json"), "\"settle_s\": 0.5");
  PZ_EXPECT_HAS(testing::InputErrorOf([&] {
                  RunCli({"fit", "--records", set, "--family", "preisach", "--settle-s", "100",
                          "--out", (dir / "bad-settle").string(), "--quiet"});
                }),
                "--settle-s 100: record major would keep 0 scored samples");

  // A set without withheld records says so; it does not say they lie within the training.
  const std::string only_train = (dir / "only-train").string();
  fs::create_directories(only_train);
  {
    std::istringstream full(Read(dir / "set" / "manifest.csv"));
    std::string head, first;
    std::getline(full, head);
    std::getline(full, first);  // the training record
    std::ofstream(dir / "only-train" / "manifest.csv") << head << "\n" << first << "\n";
  }
  fs::copy_file(dir / "set" / "major.csv", dir / "only-train" / "major.csv");
  const std::string lone = Captured({"fit", "--records", only_train, "--family", "preisach",
                                     "--out", (dir / "lone").string(), "--no-figures", "--quiet"});
  PZ_EXPECT_HAS(lone, "excitation: no withheld records");
  EXPECT_EQ(lone.find("every withheld record"), std::string::npos) << lone;
  PZ_EXPECT_HAS(Read(dir / "lone" / "report.md"), "No withheld records");
  // --pi-operators out of range: the flag is named.
  try {
    RunCli({"fit", "--records", set, "--family", "preisach", "--pi-operators", "0", "--out",
            (dir / "bad-ops").string()});
    ADD_FAILURE() << "--pi-operators 0 accepted";
  } catch (const CLI::ValidationError& e) {
    PZ_EXPECT_HAS(std::string(e.what()), "--pi-operators");
  }
  PZ_EXPECT_HAS(testing::InputErrorOf([&] {
                  RunCli({"fit", "--records", set, "--family", "preisach", "--pi-operators", "300",
                          "--out", (dir / "bad-ops").string(), "--quiet"});
                }),
                "--pi-operators 300: preisach.levels");
  // auto: the preisach grid's levels by validation; another family's count is its own.
  PZ_EXPECT_HAS(
      testing::InputErrorOf([&] {
        RunCli({"fit", "--records", set, "--family", "prandtl-ishlinskii", "--pi-operators", "auto",
                "--out", (dir / "bad-ops").string(), "--quiet"});
      }),
      "preisach");

  // One searched parameter (the delay; the weights are solved): the line search, said in the
  // report, fit.json and on stdout; its bad budgets are refused naming the flag, and its budget
  // where the search is not the line search.
  const std::string lined =
      Captured({"fit", "--records", set, "--family", "prandtl-ishlinskii", "--effects", "delay",
                "--line-grid", "9", "--out", (dir / "line").string(), "--no-figures", "--quiet"});
  PZ_EXPECT_HAS(
      lined,
      "search: line search: a grid of 9 points, then the lowest 2 of its local minima refined by "
      "Brent's method to 0.0001 of the range (the rule for 1 searched parameter)");
  PZ_EXPECT_HAS(Read(dir / "line" / "report.md"), "Search: line search: a grid of 9 points");
  const std::string line_json = Read(dir / "line" / "fit.json");
  PZ_EXPECT_HAS(line_json, "\"algorithm\": \"line\"");
  PZ_EXPECT_HAS(line_json, "\"grid\": 9");
  PZ_EXPECT_HAS(line_json, "\"spectrum_solved\": false");
  for (const auto& [flag, value] :
       std::vector<std::pair<std::string, std::string>>{{"--line-grid", "2"},
                                                        {"--line-brackets", "0"},
                                                        {"--line-tolerance", "0"},
                                                        {"--line-tolerance", "0.5"}}) {
    try {
      RunCli({"fit", "--records", set, "--family", "prandtl-ishlinskii", "--effects", "delay", flag,
              value, "--out", (dir / "bad-line").string(), "--quiet"});
      ADD_FAILURE() << flag << " " << value << " accepted";
    } catch (const CLI::ValidationError& e) {
      PZ_EXPECT_HAS(std::string(e.what()), flag);
    }
  }
  PZ_EXPECT_HAS(testing::InputErrorOf([&] {
                  RunCli({"fit", "--records", set, "--family", "prandtl-ishlinskii", "--effects",
                          "delay", "--particles", "12", "--line-grid", "9", "--out",
                          (dir / "bad-line").string(), "--quiet"});
                }),
                "--line-grid / --line-brackets / --line-tolerance: the line search's budget");

  PZ_EXPECT_HAS(testing::InputErrorOf([&] {
                  RunCli({"synth-stack", "--out", (dir / "bad").string(), "--fs", "100",
                          "--train-drive", (dir / "fit" / "excitation_drive.csv").string()});
                }),
                "sampled at 200 Hz; --fs is 100 Hz");
  fs::remove_all(dir);
}

}  // namespace
}  // namespace pz::client
