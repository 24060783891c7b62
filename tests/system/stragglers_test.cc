// Stragglers (issue 24): a worker that is alive but slow — stopped by SIGSTOP for 350 ms of every
// 450 ms, under the liveness timeout, like a throttled container — holds the last tasks of each
// generation. The master hands copies of its straggling leases to idle workers, takes the first
// answer and ignores the other: the job's result is the in-process run's bit for bit, and the
// Workers counters show the copies.
#include <gtest/gtest.h>

#include <csignal>

#include "tests/system/service_harness.h"

namespace pz::testing {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

struct SlowRun {
  double seconds = 0;
  service::WorkersSnapshot workers;
};

SlowRun RunWithASlowWorker(const job::JobSpec& spec, const service::JobCheckpoint& ref,
                           const std::vector<std::string>& master_flags) {
  Cluster c("straggle", master_flags);
  c.AddWorker(1);
  c.AddWorker(1);
  Process& slow = c.AddWorker(1);
  auto client = c.Client(4000, 5);
  svcclient::SubmitResult r;
  EXPECT_TRUE(client.Submit(spec, &r).ok());
  const auto start = Clock::now();
  service::JobInfo info;
  while (client.GetStatus(r.job_id, &info).ok() && !service::IsFinal(info.state) &&
         Clock::now() - start < 300s) {
    ::kill(slow.pid(), SIGSTOP);
    std::this_thread::sleep_for(350ms);
    ::kill(slow.pid(), SIGCONT);
    std::this_thread::sleep_for(100ms);
  }
  ::kill(slow.pid(), SIGCONT);
  SlowRun out;
  out.seconds = std::chrono::duration<double>(Clock::now() - start).count();
  EXPECT_EQ(info.state, service::JobState::kSucceeded) << info.message;
  std::vector<service::ScoredGenome> best;
  std::vector<service::GenerationRecord> log;
  EXPECT_TRUE(client.Fetch(r.job_id, 5, &best, &log).ok());
  ExpectSameRun(ref, best, log);
  EXPECT_TRUE(client.Workers(&out.workers).ok());
  EXPECT_EQ(out.workers.workers.size(), 3u) << "the slow worker was never declared dead";
  return out;
}

TEST(Stragglers, CopiesOfASlowWorkersLeasesGiveTheSameResultSooner) {
  const job::JobSpec spec = SyntheticSpec(41, 24, 25, 20);  // 20 ms per evaluation
  const service::JobCheckpoint ref = Reference(spec);
  const SlowRun with = RunWithASlowWorker(spec, ref, {});
  EXPECT_GT(with.workers.speculative_leases, 0u);
  EXPECT_GT(with.workers.speculative_wins, 0u);
  EXPECT_LE(with.workers.speculative_wins, with.workers.speculative_leases);
  const SlowRun without = RunWithASlowWorker(spec, ref, {"--speculate-after", "0"});
  EXPECT_EQ(without.workers.speculative_leases, 0u);
  std::printf("stragglers: %.1f s with copies (%lu sent, %lu answered first), %.1f s without\n",
              with.seconds, static_cast<unsigned long>(with.workers.speculative_leases),
              static_cast<unsigned long>(with.workers.speculative_wins), without.seconds);
}

}  // namespace
}  // namespace pz::testing
