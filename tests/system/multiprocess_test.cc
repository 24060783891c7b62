// The service over real processes on 127.0.0.1: determinism across worker counts and in-process,
// worker and master kills, concurrent jobs, cancel. Each test is bounded (< 60 s).
#include <gtest/gtest.h>

#include <atomic>

#include <random>

#include "tests/system/service_harness.h"

namespace pz::testing {
namespace {

using namespace std::chrono_literals;

struct Outcome {
  service::JobInfo info;
  std::vector<service::ScoredGenome> best;
  std::vector<service::GenerationRecord> log;
};

Outcome RunOnCluster(Cluster& c, const job::JobSpec& spec, std::chrono::seconds timeout) {
  auto client = c.Client();
  svcclient::SubmitResult r;
  Outcome o;
  Status s = client.Submit(spec, &r);
  EXPECT_TRUE(s.ok()) << s.ToString();
  if (!s.ok()) return o;
  s = client.WaitFinal(r.job_id, timeout, &o.info);
  EXPECT_TRUE(s.ok()) << s.ToString();
  EXPECT_EQ(o.info.state, service::JobState::kSucceeded) << o.info.message;
  s = client.Fetch(r.job_id, 5, &o.best, &o.log);
  EXPECT_TRUE(s.ok()) << s.ToString();
  return o;
}

TEST(Service, SameJobIsBitIdenticalWith124WorkersAndInProcess) {
  const job::JobSpec spec = SyntheticSpec(7, 40, 15);
  const service::JobCheckpoint ref = Reference(spec);
  for (int workers : {1, 2, 4}) {
    SCOPED_TRACE(std::to_string(workers) + " workers");
    Cluster c("det" + std::to_string(workers));
    for (int i = 0; i < workers; ++i) c.AddWorker(2);
    Outcome o = RunOnCluster(c, spec, 40s);
    ExpectSameRun(ref, o.best, o.log);
  }
}

TEST(Service, WorkersKilledRepeatedlyJobCompletesBitIdentical) {
  // Long enough (≥ 50 × 20 × 4 ms / 6 threads ≈ 0.7 s of evaluation, more with the kills) for
  // several kills.
  job::JobSpec spec = SyntheticSpec(11, 40, 50, /*sleep_ms=*/4);
  spec.limits.quarantine_after = 100;  // kills by the test must not quarantine innocents
  const service::JobCheckpoint ref = Reference(spec);
  Cluster c("killw");
  for (int i = 0; i < 3; ++i) c.AddWorker(2);
  auto client = c.Client();
  svcclient::SubmitResult r;
  ASSERT_TRUE(client.Submit(spec, &r).ok());
  std::mt19937 rng(3);
  service::JobInfo info;
  int kills = 0;
  const auto deadline = std::chrono::steady_clock::now() + 50s;
  while (std::chrono::steady_clock::now() < deadline) {
    ASSERT_TRUE(client.GetStatus(r.job_id, &info).ok());
    if (service::IsFinal(info.state)) break;
    std::this_thread::sleep_for(250ms);
    auto& ws = c.workers();
    ws[rng() % ws.size()]->Kill(SIGKILL);
    ++kills;
    c.AddWorker(2);
  }
  EXPECT_GE(kills, 3);
  ASSERT_EQ(info.state, service::JobState::kSucceeded) << info.message;
  Outcome o;
  ASSERT_TRUE(client.Fetch(r.job_id, 5, &o.best, &o.log).ok());
  ExpectSameRun(ref, o.best, o.log);
}

TEST(Service, MasterKilledAndRestartedResumesBitIdentical) {
  const job::JobSpec spec = SyntheticSpec(13, 40, 30, /*sleep_ms=*/3);
  const service::JobCheckpoint ref = Reference(spec);
  // A checkpoint on disk after every generation, so that each restart really resumes mid-run.
  Cluster c("killm", {"--checkpoint-interval-s", "0"});
  c.AddWorker(2);
  c.AddWorker(2);
  std::string job_id;
  {
    auto client = c.Client();
    svcclient::SubmitResult r;
    ASSERT_TRUE(client.Submit(spec, &r).ok());
    job_id = r.job_id;
  }
  for (int restart = 0; restart < 2; ++restart) {
    auto client = c.Client();
    service::JobInfo info;
    const uint64_t target = 6 + 10 * restart;
    for (int i = 0; i < 400 && info.generation < target; ++i) {
      ASSERT_TRUE(client.GetStatus(job_id, &info).ok());
      std::this_thread::sleep_for(50ms);
    }
    ASSERT_GE(info.generation, target);
    ASSERT_EQ(info.state, service::JobState::kRunning);
    c.KillMaster(SIGKILL);
    c.StartMaster();
  }
  auto client = c.Client();
  service::JobInfo info;
  ASSERT_TRUE(client.WaitFinal(job_id, 50s, &info).ok());
  ASSERT_EQ(info.state, service::JobState::kSucceeded) << info.message;
  Outcome o;
  ASSERT_TRUE(client.Fetch(job_id, 5, &o.best, &o.log).ok());
  ExpectSameRun(ref, o.best, o.log);
}

TEST(Service, ThreeJobsAtOnceCompleteAndCancelWorks) {
  Cluster c("multi");
  c.AddWorker(2);
  c.AddWorker(2);
  auto client = c.Client();
  std::vector<std::string> ids;
  std::vector<job::JobSpec> specs;
  for (uint64_t seed : {21, 22, 23}) {
    specs.push_back(SyntheticSpec(seed, 30, 10, 1));
    svcclient::SubmitResult r;
    ASSERT_TRUE(client.Submit(specs.back(), &r).ok());
    ids.push_back(r.job_id);
  }
  svcclient::SubmitResult doomed;
  ASSERT_TRUE(client.Submit(SyntheticSpec(99, 30, 100000, 1), &doomed).ok());
  // A watcher sees generation events of the doomed job, then its cancellation.
  std::atomic<int> events{0};
  std::atomic<service::JobState> last{service::JobState::kUnspecified};
  std::thread watcher([&] {
    auto w = c.Client();
    (void)w.Watch(
        doomed.job_id,
        [&](const service::JobEvent& e) {
          ++events;
          last = e.state;
          return true;
        },
        40s);
  });
  // Cancel once the watcher has seen generations go by (bounded wait: the machine may be loaded).
  for (int i = 0; i < 300 && events.load() < 2; ++i) std::this_thread::sleep_for(100ms);
  ASSERT_TRUE(client.Cancel(doomed.job_id).ok());
  watcher.join();
  EXPECT_GT(events.load(), 1);
  EXPECT_EQ(last.load(), service::JobState::kCancelled);
  service::JobInfo info;
  ASSERT_TRUE(client.GetStatus(doomed.job_id, &info).ok());
  EXPECT_EQ(info.state, service::JobState::kCancelled);
  EXPECT_EQ(client.Cancel(doomed.job_id).code(), StatusCode::kFailedPrecondition);

  for (size_t i = 0; i < ids.size(); ++i) {
    ASSERT_TRUE(client.WaitFinal(ids[i], 40s, &info).ok());
    EXPECT_EQ(info.state, service::JobState::kSucceeded) << info.message;
  }
  Outcome o;
  ASSERT_TRUE(client.Fetch(ids[1], 5, &o.best, &o.log).ok());
  ExpectSameRun(Reference(specs[1]), o.best, o.log);
  std::vector<service::JobInfo> jobs;
  int workers = 0;
  ASSERT_TRUE(client.List(&jobs, &workers).ok());
  EXPECT_EQ(jobs.size(), 4u);
  EXPECT_EQ(workers, 2);
}

}  // namespace
}  // namespace pz::testing
