// piezoid identify's result folder (reports/identify_report.h): every file written, the network
// reloads exactly and predicts as the fitness's decoding does.
#include "reports/identify_report.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>

#include "client/commands.h"
#include "hgann/hgann_fitness.h"
#include "hgann/trend_seeds.h"
#include "io/bench_data.h"
#include "io/network_io.h"
#include "model/chromosome.h"

namespace pz::client {
namespace {

const io::CaseSet& Nominal() {
  static const io::CaseSet set =
      io::LoadCaseSet(std::string(PIEZOID_DATA_DIR) + "/bimorph-fin/nominal");
  return set;
}

/// A small run of the nominal set into a temporary folder named after `name`.
reports::IdentifyOptions SmallRun(const std::string& name, int population, int generations) {
  reports::IdentifyOptions o;
  o.cases_dir = Nominal().dir;
  o.out_dir = std::filesystem::temp_directory_path() /
              ("piezoid-" + name + "-" + std::to_string(::getpid()));
  o.ga.population_size = population;
  o.ga.max_generations = generations;
  o.ga.seed = 4;
  o.threads = 2;
  o.plots = false;
  return o;
}

TEST(IdentifyReport, WritesResultFolderWhoseNetworkReloadsExactly) {
  const io::CaseSet& set = Nominal();
  const hgann::HgannFitness fitness(hgann::HgannConfigFromCaseSet(set, {}));
  reports::IdentifyOptions o = SmallRun("identify-test", 20, 3);
  int generations = 0;
  const auto result =
      hgann::RunIdentify(o, set, fitness, [&](const opt::GenerationSummary&) { ++generations; });
  EXPECT_EQ(generations, 4);
  std::ostringstream term;
  const auto files = reports::WriteIdentifyReport(o, set, fitness, result, term);
  for (const char* f :
       {"network.pb", "network.json", "progress.csv", "validation.csv", "parameters.csv",
        "report.md", "fitness.gp", "case9_loop.gp", "traces/case9.csv"})
    EXPECT_TRUE(std::filesystem::exists(o.out_dir / f)) << f;
  EXPECT_NE(term.str().find("paper's Table 8"), std::string::npos);
  // The parameters held at a bound on every training case are named in report.md and on the
  // terminal, each with its side; a run with none has no such line.
  {
    std::ifstream in(o.out_dir / "report.md");
    const std::string md((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    const auto side = fitness.ParametersAtBound(result.best.network);
    const char* symbols[] = {"μ", "δ", "α", "β", "γ", "a1", "a2"};
    const bool any = std::any_of(side.begin(), side.end(), [](int s) { return s != 0; });
    EXPECT_EQ(md.find("Held at a bound:") != std::string::npos, any);
    EXPECT_EQ(term.str().find("held at a bound on every training case") != std::string::npos, any);
    for (int k = 0; k < 7; ++k) {
      if (side[k] == 0) continue;
      EXPECT_NE(md.find(std::string(symbols[k]) +
                        (side[k] > 0 ? " at its upper bound" : " at its lower bound")),
                std::string::npos)
          << symbols[k];
    }
    // Where the network extrapolates: the withheld cases outside the training cases' hull (2, 3,
    // 8, 9 on the paper's split), not case 4 (on its edge), in report.md and on the terminal.
    EXPECT_NE(md.find("## Where the network extrapolates"), std::string::npos);
    for (const char* row : {"| 2 | 375 | 0.5 | yes |", "| 3 | 375 | 1 | yes |",
                            "| 8 | 750 | 0.5 | yes |", "| 9 | 750 | 1 | yes |"})
      EXPECT_NE(md.find(row), std::string::npos) << row;
    EXPECT_EQ(md.find("| 4 | 500 | 0.25 |"), std::string::npos);
    EXPECT_NE(term.str().find("case 9 (750 V, 1 Hz, outside the hull)"), std::string::npos);
  }
  for (const char* f : {"network.pb", "network.json"}) {
    io::SavedNetwork loaded;
    ASSERT_TRUE(io::LoadNetwork((o.out_dir / f).string(), &loaded).ok()) << f;
    EXPECT_EQ(loaded.network, result.best.network) << f;
    EXPECT_EQ(loaded.provenance.fitness, result.summary.best_fitness.cost);
    const auto a = loaded.network.Predict(600, 0.7),
               b = fitness.Decode(result.summary.best).Predict(600, 0.7);
    EXPECT_EQ(a, b) << f;
  }
  std::filesystem::remove_all(o.out_dir);
}

/// report.md of a result whose network is `net` (a small run's result with its network replaced).
std::string ReportOf(const std::string& name, const hgann::HgannFitness& fitness,
                     const model::Network& net, std::string* terminal) {
  reports::IdentifyOptions o = SmallRun(name, 10, 0);
  auto result = hgann::RunIdentify(o, Nominal(), fitness, nullptr);
  result.best.chromosome = model::EncodeChromosome(net);
  result.best.network = fitness.Decode(opt::Genome{result.best.chromosome, {}});
  result.cases = fitness.EvaluateCases(result.best.network);
  std::ostringstream term;
  reports::WriteIdentifyReport(o, Nominal(), fitness, result, term);
  std::ifstream in(o.out_dir / "report.md");
  const std::string md((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::filesystem::remove_all(o.out_dir);
  *terminal = term.str();
  return md;
}

TEST(IdentifyReport, ThePerCaseCheckFlagsAPlantedMissAndNotTheTruth) {
  // The nominal bench's truth as a constant network (μ 95 1/s, δ 0.1 s, α 2.5e-3 N/V, β 6e-3,
  // γ 4e-3 1/V, a1 0.1, a2 0.15 deg; data/bimorph-fin/README.md), and the same with a2 planted at
  // 0.3 deg. The truth is flagged nowhere (the linear 2 σ alone flagged α and a1 where the
  // per-case estimates sit elsewhere in the α–β–γ–backlash valley); the planted a2 is.
  const hgann::HgannFitness fitness(hgann::HgannConfigFromCaseSet(Nominal(), {}));
  const auto& cfg = fitness.config();
  const auto constant = [&](std::array<double, 7> p) {
    std::vector<double> c2;
    for (int k = 0; k < 7; ++k)
      c2.push_back((p[k] - cfg.ranges[k].lower) / (cfg.ranges[k].upper - cfg.ranges[k].lower));
    return hgann::TrendNetwork(-1, -1, c2, {}, cfg.normalization, cfg.ranges);
  };
  std::string term;
  const std::string truth =
      ReportOf("check-truth", fitness, constant({95, 0.1, 2.5e-3, 6e-3, 4e-3, 0.1, 0.15}), &term);
  EXPECT_NE(truth.find("The network agrees with every per-case estimate"), std::string::npos)
      << truth.substr(truth.find("## The network against per-case fits"), 3000);
  EXPECT_EQ(term.find("departs from a per-case fit"), std::string::npos) << term;
  const std::string planted =
      ReportOf("check-planted", fitness, constant({95, 0.1, 2.5e-3, 6e-3, 4e-3, 0.1, 0.3}), &term);
  EXPECT_NE(planted.find("a2 in cases"), std::string::npos)
      << planted.substr(planted.find("## The network against per-case fits"), 3000);
  EXPECT_NE(term.find("a2 network 0.3"), std::string::npos) << term;
}

TEST(IdentifyReport, IslandsGetTheirColumnsTheirLinesAndTheirReportLine) {
  const io::CaseSet& set = Nominal();
  const hgann::HgannFitness fitness(hgann::HgannConfigFromCaseSet(set, {}));
  reports::IdentifyOptions o = SmallRun("identify-islands", 12, 4);
  o.ga.islands = 3;
  o.ga.migration_interval = 2;
  o.ga.migrants = 1;
  o.ga.topology = opt::MigrationTopology::kRing;  // not the defaults: the report names what it ran
  o.ga.migration_margin = 0;
  const auto result = hgann::RunIdentify(o, set, fitness, nullptr);
  std::ostringstream term;
  reports::WriteIdentifyReport(o, set, fitness, result, term);
  std::ifstream csv(o.out_dir / "progress.csv");
  std::string header, row;
  std::getline(csv, header);
  EXPECT_NE(
      header.find(
          ",best_network,best_island,migrated,immigrants,restarted,island_0_best,island_1_best,"
          "island_2_best"),
      std::string::npos)
      << header;
  int rows = 0;
  while (std::getline(csv, row)) {
    ++rows;
    // The columns after the quoted network description (which holds commas) match the header's.
    const std::string tail = row.substr(row.rfind('"')),
                      head = header.substr(header.find("best_network"));
    EXPECT_EQ(std::count(tail.begin(), tail.end(), ','), std::count(head.begin(), head.end(), ','))
        << row;
  }
  EXPECT_EQ(rows, 5);
  EXPECT_EQ(reports::IslandCsvCells(result.log[2]).substr(0, 3),
            "," + std::to_string(result.log[2].best_island) + ",");
  EXPECT_NE(reports::IslandsBrief(result.log.back()).find("/3 (islands "), std::string::npos);
  std::ifstream gp(o.out_dir / "fitness.gp");
  const std::string plot((std::istreambuf_iterator<char>(gp)), {});
  EXPECT_NE(plot.find("island 2"), std::string::npos) << plot;
  std::ifstream md(o.out_dir / "report.md");
  const std::string report((std::istreambuf_iterator<char>(md)), {});
  EXPECT_NE(report.find("× 3 islands (1 migrants every 2 generations, ring; mutation by island "
                        "0.01 0.02 0.03; 2 migrations"),
            std::string::npos)
      << report;
  // The margin's gate and the islands' rates (the default ladder above, or given) are named in the
  // report's line.
  const auto report_line = [&] {
    reports::WriteIdentifyReport(o, set, fitness, hgann::RunIdentify(o, set, fitness, nullptr),
                                 term);
    std::ifstream in(o.out_dir / "report.md");
    return std::string((std::istreambuf_iterator<char>(in)), {});
  };
  o.ga.migration_margin = 0.2;
  const std::string gated = report_line();
  EXPECT_NE(gated.find("1 migrants every 2 generations, ring, from sources better by more than 20 "
                       "%; mutation by island 0.01 0.02 0.03; 2 migrations"),
            std::string::npos)
      << gated;
  o.ga.island_mutation = {0.01, 0.02, 0.05};
  const std::string mixed = report_line();
  EXPECT_NE(
      mixed.find(
          "from sources better by more than 20 %; mutation by island 0.01 0.02 0.05; 2 migrations"),
      std::string::npos)
      << mixed;
  o.ga.island_mutation.clear();
  o.ga.migration_margin = 0;
  o.ga.broadcast_interval = 3;
  o.ga.broadcast_margin = 0.25;
  const std::string broadcast = report_line();
  EXPECT_NE(
      broadcast.find(
          "1 migrants every 2 generations, ring; a broadcast every 3 generations from islands "
          "better by more than 25 %;"),
      std::string::npos)
      << broadcast;
  // One island: the file is as before islands.
  EXPECT_EQ(reports::IslandCsvHeader({opt::GenerationSummary{}}), "");
  EXPECT_EQ(reports::IslandsBrief(opt::GenerationSummary{}), "");
  std::filesystem::remove_all(o.out_dir);
}

/// The message `piezoid identify <args>` refuses its input with. --cases names no folder, so input
/// that passes the GA's checks is refused for the case set.
std::string IdentifyRefusal(std::vector<std::string> args) {
  CLI::App app{"piezoid"};
  int exit_code = 0;
  RegisterIdentify(app, exit_code);
  args.insert(args.begin(), {"piezoid", "identify", "--cases", "/nonexistent-case-set"});
  std::vector<const char*> argv;
  for (const auto& a : args) argv.push_back(a.c_str());
  try {
    app.parse(static_cast<int>(argv.size()), argv.data());
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(IdentifyCli, ABadNextCandidateIsRefusedNamingTheFlagAndThePoint) {
  const std::string rule =
      ": must be V:f, the amplitude [V] and the frequency [Hz] of a feasible operating point, each "
      "a finite number > 0 (e.g. 750:1)";
  EXPECT_EQ(IdentifyRefusal({"--next-candidates", "750:1,600"}),
            "--next-candidates = \"600\"" + rule);
  EXPECT_EQ(IdentifyRefusal({"--next-candidates", "750:0"}),
            "--next-candidates = \"750:0\"" + rule);
  EXPECT_EQ(IdentifyRefusal({"--next-candidates", "7x0:1"}),
            "--next-candidates = \"7x0:1\"" + rule);
  EXPECT_EQ(IdentifyRefusal({"--next-candidates", "nan:1"}),
            "--next-candidates = \"nan:1\"" + rule);
  // Good points pass on to the case set, which does not exist here.
  EXPECT_EQ(IdentifyRefusal({"--next-candidates", "750:1,600:0.4"})
                .find("--next-candidates"),
            std::string::npos);
}

TEST(IdentifyCli, BadGaSettingsAreRefusedUnderTheirFlagWithTheAllowedRange) {
  EXPECT_EQ(IdentifyRefusal({"--islands", "0"}), "--islands = 0: must be in [1, 1024]");
  EXPECT_EQ(
      IdentifyRefusal({"--preset", "fast"}),
      "--preset = fast: must be \"robust\" (the default: islands, spread penalty, trend seeds) or "
      "\"paper\" (the paper's Table 2)");
  EXPECT_EQ(IdentifyRefusal({"--migration-margin", "1"}),
            "--migration-margin = 1: must be in [0, 1) (0 = every source)");
  EXPECT_EQ(IdentifyRefusal({"--islands", "1025"}), "--islands = 1025: must be in [1, 1024]");
  EXPECT_EQ(IdentifyRefusal({"--broadcast-interval", "-3"}),
            "--broadcast-interval = -3: must be >= 0 (0 = no broadcast)");
  EXPECT_EQ(IdentifyRefusal({"--broadcast-margin", "0"}),
            "--broadcast-margin = 0: must be in (0, 1)");
  EXPECT_EQ(IdentifyRefusal(
                {"--migration-interval", "0", "--migrants", "0", "--broadcast-interval", "25"}),
            "--migrants = 0: must be >= 1 when --broadcast-interval = 25 > 0");
  EXPECT_EQ(IdentifyRefusal({"--islands", "3", "--island-mutation", "0.01,0.02"}),
            "--island-mutation.size() = 2: must be 0 (the ladder: --mutation × 1, 2, 3, 5) or "
            "--islands = 3");
  EXPECT_EQ(IdentifyRefusal({"--islands", "2", "--island-mutation", "0.01,2"}),
            "--island-mutation[1] = 2: must be in [0, 1]");
  EXPECT_EQ(IdentifyRefusal({"--migrants", "400"}),
            "--migrants = 400: must be in [0, --population - 1 = 399]");
  EXPECT_EQ(IdentifyRefusal({"--migrants", "0"}),
            "--migrants = 0: must be >= 1 when --migration-interval = 25 > 0 (--migration-interval "
            "0 runs the "
            "islands independently)");
  EXPECT_EQ(IdentifyRefusal({"--migration-interval", "-1"}),
            "--migration-interval = -1: must be >= 0 (0 = no migration)");
  EXPECT_EQ(IdentifyRefusal({"--topology", "star"}),
            "--topology = star: must be \"ring\", \"fully_connected\" or \"random\"");
  EXPECT_EQ(IdentifyRefusal({"--island-stall", "-2"}),
            "--island-stall = -2: must be >= 0 (0 = never)");
  EXPECT_EQ(IdentifyRefusal({"--population", "1"}), "--population = 1: must be >= 2");
  EXPECT_EQ(IdentifyRefusal({"--generations", "-1"}), "--generations = -1: must be >= 0");
  EXPECT_EQ(IdentifyRefusal({"--stall", "-1"}), "--stall = -1: must be >= 0 (0 = never)");
  EXPECT_EQ(IdentifyRefusal({"--mutation", "2"}), "--mutation = 2: must be in [0, 1]");
  EXPECT_EQ(IdentifyRefusal({"--elite", "1"}), "--elite = 1: must be in (0, 1)");
  EXPECT_NE(IdentifyRefusal({"--islands", "4", "--migration-interval", "0", "--migrants", "0"})
                .find("nonexistent-case-set"),
            std::string::npos);
}

}  // namespace
}  // namespace pz::client
