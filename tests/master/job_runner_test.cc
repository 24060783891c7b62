// The job runner (the master's GA loop over a job kind): an hgann spec run in process is exactly
// `piezoid identify`'s local run of the same case set and GA settings.
#include <gtest/gtest.h>

#include "hgann/identify.h"
#include "kinds/kinds.h"
#include "master/job_runner.h"
#include "model/chromosome.h"
#include "tests/testing/hgann_spec.h"

namespace pz::master {
namespace {

const io::CaseSet& Nominal() { return testing::NominalCaseSet(); }
job::JobSpec NominalSpec(int population, int generations) { return testing::NominalHgannSpec(population, generations); }

TEST(JobRunner, InProcessJobRunsExactlyAsPiezoidIdentify) {
  const job::JobSpec spec = NominalSpec(16, 4);
  service::JobCheckpoint job;
  ASSERT_TRUE(RunJobInProcess("t", spec, kinds::All(), &job).ok());

  hgann::IdentifyOptions o;
  job::GenomeLayout layout{model::kChromosomeBits, 0};
  o.ga = ToGaOptions(spec, layout);
  o.threads = 2;
  const hgann::HgannFitness fitness(hgann::HgannConfigFromCaseSet(Nominal(), model::ParameterRanges{}));
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


}  // namespace
}  // namespace pz::master
