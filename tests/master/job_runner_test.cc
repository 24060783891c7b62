// The job runner (the master's GA loop over a job kind): an hgann spec run in process is exactly
// `piezoid identify`'s local run of the same case set and GA settings.
#include <gtest/gtest.h>

#include "hgann/identify.h"
#include "kinds/kinds.h"
#include "master/job_runner.h"
#include "model/chromosome.h"
#include "opt/inline_evaluator.h"
#include "service/wire_codec.h"
#include "tests/testing/hgann_spec.h"

namespace pz::master {
namespace {

const io::CaseSet& Nominal() { return testing::NominalCaseSet(); }
job::JobSpec NominalSpec(int population, int generations) {
  return testing::NominalHgannSpec(population, generations);
}

TEST(JobRunner, InProcessJobRunsExactlyAsPiezoidIdentify) {
  const job::JobSpec spec = NominalSpec(16, 4);
  service::JobCheckpoint job;
  ASSERT_TRUE(RunJobInProcess("t", spec, kinds::All(), &job).ok());

  hgann::IdentifyOptions o;
  job::GenomeLayout layout{model::kChromosomeBits, 0};
  o.ga = ToGaOptions(spec, layout);
  o.threads = 2;
  const hgann::HgannFitness fitness(
      hgann::HgannConfigFromCaseSet(Nominal(), model::ParameterRanges{}));
  const hgann::IdentifyResult id = hgann::RunIdentify(o, Nominal(), fitness, nullptr);

  ASSERT_EQ(job.log.size(), id.log.size());
  for (size_t g = 0; g < job.log.size(); ++g) {
    EXPECT_EQ(job.log[g].best_cost, id.log[g].best_cost) << g;
    EXPECT_EQ(job.log[g].mean_cost, id.log[g].mean_cost) << g;
    EXPECT_EQ(job.log[g].worst_cost, id.log[g].worst_cost) << g;
    EXPECT_EQ(job.log[g].best_description, id.log[g].best_description) << g;
  }
  EXPECT_EQ(job.best.front().genome.bits, id.best.chromosome);
  EXPECT_EQ(job.best.front().fitness.cost, id.summary.best_fitness.cost);
}

// The job kind's repair (hgann/loop_repair.h) follows the spec's preset: the default repairs every
// child whose loop is unbounded, so none is refused for it; the paper's GA refuses them.
TEST(JobRunner, TheDefaultPresetRepairsUnboundedLoopsThePaperPresetRefusesThem) {
  const auto unbounded = [](const service::JobCheckpoint& job) {
    int n = 0;
    for (const auto& g : job.log)
      for (const auto& [reason, count] : g.failure_reasons)
        if (reason.find("unbounded") != std::string::npos) n += count;
    return n;
  };
  job::JobSpec spec = NominalSpec(16, 4);
  service::JobCheckpoint repaired, paper;
  ASSERT_TRUE(RunJobInProcess("t", spec, kinds::All(), &repaired).ok());
  std::get<job::HgannProblem>(spec.problem).preset = "paper";
  ASSERT_TRUE(RunJobInProcess("t", spec, kinds::All(), &paper).ok());
  EXPECT_EQ(unbounded(repaired), 0);
  EXPECT_GT(unbounded(paper), 0) << "a uniform genome's loop is unbounded about half the time";
}

/// Four islands of the nominal hgann problem: migration every 3 generations, fully connected, an
/// island restarted after 4 generations of its own stall, each island at its own mutation rate.
job::JobSpec IslandSpec() {
  job::JobSpec spec = NominalSpec(16, 10);
  spec.ga->islands = 4;
  spec.ga->migration_interval = 3;
  spec.ga->migrants = 2;
  spec.ga->topology = opt::MigrationTopology::kFullyConnected;
  spec.ga->island_stall_generations = 4;
  spec.ga->island_mutation = {0.01, 0.02, 0.03, 0.05};
  return spec;
}

/// IslandSpec with a gated broadcast every 2 generations between its migrations (opt/ga.h, 6b.).
job::JobSpec BroadcastSpec() {
  job::JobSpec spec = IslandSpec();
  spec.ga->topology = opt::MigrationTopology::kRing;
  spec.ga->broadcast_interval = 2;
  spec.ga->broadcast_margin = 1e-6;
  return spec;
}

/// Whether generation g of the spec ends with a migration or a broadcast.
bool Migrates(const job::JobSpec& spec, int g) {
  return g > 0 && (g % spec.ga->migration_interval == 0 ||
                   (spec.ga->broadcast_interval > 0 && g % spec.ga->broadcast_interval == 0));
}

TEST(JobRunner, FourIslandsInProcessAreExactlyPiezoidIdentify) {
  for (const job::JobSpec& spec : {IslandSpec(), BroadcastSpec()}) {
    SCOPED_TRACE("broadcast interval " + std::to_string(spec.ga->broadcast_interval));
    service::JobCheckpoint job;
    ASSERT_TRUE(RunJobInProcess("t", spec, kinds::All(), &job).ok());

    hgann::IdentifyOptions o;
    o.ga = ToGaOptions(spec, job::GenomeLayout{model::kChromosomeBits, 0});
    EXPECT_EQ(o.ga.islands, 4);
    EXPECT_EQ(o.ga.island_mutation, (std::vector<double>{0.01, 0.02, 0.03, 0.05}));
    o.threads = 2;
    const hgann::HgannFitness fitness(
        hgann::HgannConfigFromCaseSet(Nominal(), model::ParameterRanges{}));
    const hgann::IdentifyResult id = hgann::RunIdentify(o, Nominal(), fitness, nullptr);

    ASSERT_EQ(job.log.size(), id.log.size());
    int migrations = 0;
    for (size_t g = 0; g < job.log.size(); ++g) {
      EXPECT_EQ(job.log[g], id.log[g]) << g;  // every field, the islands' records included
      EXPECT_EQ(job.log[g].islands.size(), 4u);
      migrations += job.log[g].migrated;
    }
    EXPECT_EQ(migrations, spec.ga->broadcast_interval > 0 ? 7 : 3);  // 3, 6, 9 (and 2, 4, 8, 10)
    EXPECT_EQ(job.best.front().genome.bits, id.best.chromosome);
    EXPECT_EQ(job.best.front().fitness.cost, id.summary.best_fitness.cost);
    EXPECT_EQ(job.optimizer.best_island, id.summary.best_island);
    EXPECT_EQ(job.termination, opt::GaTermination::kMaxGenerations);
    // The kept best are over all islands, best first, indexed island · population + rank.
    ASSERT_EQ(job.best.size(), static_cast<size_t>(kBestKept));
    for (size_t i = 1; i < job.best.size(); ++i)
      EXPECT_LE(job.best[i - 1].fitness.cost, job.best[i].fitness.cost);
    const auto& top_island = job.optimizer.islands[job.optimizer.best_island];
    EXPECT_EQ(job.best.front().genome, top_island.population[0]);
  }
}

TEST(JobRunner, ResumeFromAStoredCheckpointAtAMigrationIsBitIdentical) {
  for (const job::JobSpec& spec : {IslandSpec(), BroadcastSpec()}) {
    SCOPED_TRACE("broadcast interval " + std::to_string(spec.ga->broadcast_interval));
    service::JobCheckpoint whole;
    ASSERT_TRUE(RunJobInProcess("t", spec, kinds::All(), &whole).ok());
    std::unique_ptr<opt::FitnessFunction> f;
    ASSERT_TRUE(kinds::All().MakeFitness(spec, &f).ok());
    opt::InlineEvaluator eval(*f, spec.limits.penalty_cost);
    for (int stop :
         {2, 3,
          4}) {  // 3 migrates; 4 restarts islands that stalled; 2 and 4 broadcast (BroadcastSpec)
      SCOPED_TRACE("stopped after generation " + std::to_string(stop));
      JobRunner first("t", spec);
      ASSERT_TRUE(first.Init(kinds::All()).ok());
      for (int g = 0; g <= stop; ++g) first.Step(eval);
      ASSERT_EQ(first.checkpoint().log.back().migrated, Migrates(spec, stop));
      // Through the stored bytes, as a master restart reads them.
      service::JobCheckpoint stored;
      ASSERT_TRUE(
          service::DecodeCheckpoint(service::EncodeCheckpoint(first.checkpoint()), &stored).ok());
      ASSERT_EQ(stored.optimizer.islands.size(), 4u);
      JobRunner second("t", spec);
      ASSERT_TRUE(second.Init(kinds::All(), &stored).ok());
      while (!second.Done()) second.Step(eval);
      const service::JobCheckpoint& resumed = second.checkpoint();
      EXPECT_TRUE(service::EncodeCheckpoint([&] {
                    auto c = resumed;
                    c.elapsed_s = whole.elapsed_s;
                    for (size_t g = 0; g < c.log.size() && g < whole.log.size(); ++g)
                      c.log[g].wall_time_s = whole.log[g].wall_time_s;
                    return c;
                  }()) == service::EncodeCheckpoint(whole))
          << "the resumed job's checkpoint differs from the uninterrupted one";
    }
  }
}

}  // namespace
}  // namespace pz::master
