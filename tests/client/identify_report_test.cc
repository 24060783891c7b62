// piezoid identify's result folder (client/identify_report.h): every file written, the network
// reloads exactly and predicts as the fitness's decoding does.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <sstream>

#include "client/identify_report.h"
#include "hgann/hgann_fitness.h"
#include "io/bench_data.h"
#include "io/network_io.h"

namespace pz::client {
namespace {

TEST(IdentifyReport, WritesResultFolderWhoseNetworkReloadsExactly) {
  static const io::CaseSet set = io::LoadCaseSet(std::string(PIEZOID_DATA_DIR) + "/bimorph-fin/nominal");
  const hgann::HgannFitness fitness(hgann::HgannConfigFromCaseSet(set, {}));
  IdentifyOptions o;
  o.cases_dir = set.dir;
  o.out_dir = std::filesystem::temp_directory_path() / ("piezoid-identify-test-" + std::to_string(::getpid()));
  o.ga.population_size = 20;
  o.ga.max_generations = 3;
  o.ga.seed = 4;
  o.threads = 2;
  o.plots = false;
  int generations = 0;
  const auto result = hgann::RunIdentify(o, set, fitness, [&](const opt::GenerationSummary&) { ++generations; });
  EXPECT_EQ(generations, 4);
  std::ostringstream term;
  const auto files = WriteIdentifyReport(o, set, fitness, result, term);
  for (const char* f : {"network.pb", "network.json", "progress.csv", "validation.csv", "parameters.csv",
                        "report.md", "fitness.gp", "case9_loop.gp", "traces/case9.csv"})
    EXPECT_TRUE(std::filesystem::exists(o.out_dir / f)) << f;
  EXPECT_NE(term.str().find("paper's Table 8"), std::string::npos);
  for (const char* f : {"network.pb", "network.json"}) {
    io::SavedNetwork loaded;
    ASSERT_TRUE(io::LoadNetwork((o.out_dir / f).string(), &loaded).ok()) << f;
    EXPECT_EQ(loaded.network, result.best.network) << f;
    EXPECT_EQ(loaded.provenance.fitness, result.summary.best_fitness.cost);
    const auto a = loaded.network.Predict(600, 0.7), b = fitness.Decode(result.summary.best).Predict(600, 0.7);
    EXPECT_EQ(a, b) << f;
  }
  std::filesystem::remove_all(o.out_dir);
}

}  // namespace
}  // namespace pz::client
