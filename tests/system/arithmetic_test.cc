// A master serves one arithmetic profile (model::ArithmeticProfile(): build, instruction-set level,
// C library): workers of two kinds of machine would give a job results that differ in their last
// bits depending on which computed what. The first worker fixes the profile; a worker announcing
// another is refused with the reason, exits instead of retrying, and shows among the departures.
// --allow-mixed-arithmetic accepts both. A job records the profile that computed it, and a master
// restarted on its state directory serves that profile while the job runs.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <set>
#include <sstream>

#include "master/checkpoint.h"
#include "model/arithmetic.h"
#include "tests/system/service_harness.h"

namespace pz::testing {
namespace {

using namespace std::chrono_literals;

// Polls the master's worker table until `done` holds (10 s at most).
bool WaitForWorkers(client::ServiceClient& client, service::WorkersSnapshot* w,
                    const std::function<bool(const service::WorkersSnapshot&)>& done) {
  for (int i = 0; i < 200; ++i) {
    if (client.Workers(w).ok() && done(*w)) return true;
    std::this_thread::sleep_for(50ms);
  }
  return false;
}

const std::string kOther = "piezoid 0.0.1; x86-64; glibc 2.19";  // a profile no machine here has

TEST(Arithmetic, AWorkerOfAnotherProfileIsRefusedWithTheReasonAndDoesNotRetry) {
  Cluster c("arith");
  auto client = c.Client(4000, 5);
  c.AddWorker(1);
  service::WorkersSnapshot w;
  ASSERT_TRUE(WaitForWorkers(client, &w, [](const auto& s) { return s.workers.size() == 1; }));
  EXPECT_EQ(w.workers[0].arithmetic, model::ArithmeticProfile());

  Process& other = c.AddWorker(1, {"--arithmetic", kOther});
  bool exited = false;
  for (int i = 0; i < 200 && !exited; ++i) {
    exited = !other.running();
    if (!exited) std::this_thread::sleep_for(50ms);
  }
  EXPECT_TRUE(exited) << "a refused worker must stop, not reconnect for ever";
  const std::string log = Slurp(c.dir() / "workers.log");
  EXPECT_NE(log.find("refused"), std::string::npos) << log;
  EXPECT_NE(log.find(kOther), std::string::npos) << "the worker is told its own profile:\n" << log;
  EXPECT_NE(log.find("--allow-mixed-arithmetic"), std::string::npos)
      << "and what would accept it:\n"
      << log;

  ASSERT_TRUE(client.Workers(&w).ok());
  ASSERT_EQ(w.workers.size(), 1u) << "the refused worker was never added";
  EXPECT_EQ(w.workers[0].arithmetic, model::ArithmeticProfile());
  ASSERT_FALSE(w.departed.empty());
  EXPECT_NE(w.departed.back().reason.find("refused: another arithmetic (" + kOther + ")"),
            std::string::npos)
      << w.departed.back().reason;
}

TEST(Arithmetic, TheFirstWorkerFixesTheProfileServed) {
  Cluster c("arith-first");
  auto client = c.Client(4000, 5);
  c.AddWorker(1, {"--arithmetic", kOther});
  service::WorkersSnapshot w;
  ASSERT_TRUE(WaitForWorkers(client, &w, [](const auto& s) { return s.workers.size() == 1; }));
  Process& native = c.AddWorker(1);  // this machine's own profile is now the other one
  ASSERT_TRUE(WaitForWorkers(client, &w, [](const auto& s) { return !s.departed.empty(); }));
  EXPECT_NE(w.departed.back().reason.find(model::ArithmeticProfile()), std::string::npos)
      << w.departed.back().reason;
  EXPECT_EQ(w.workers.size(), 1u);
  for (int i = 0; i < 200 && native.running(); ++i) std::this_thread::sleep_for(50ms);
  EXPECT_FALSE(native.running());
}

TEST(Arithmetic, AJobResumedByARestartedMasterContinuesOnTheProfileItWasComputedOn) {
  Cluster c("arith-resume");
  c.AddWorker(1, {"--arithmetic", kOther});
  client::SubmitResult r;
  {
    auto client = c.Client(4000, 5);
    ASSERT_TRUE(client.Submit(SyntheticSpec(31, 20, 400, 2), &r).ok());
    service::JobInfo info;
    for (int i = 0; i < 400 && info.generation < 3; ++i) {
      ASSERT_TRUE(client.GetStatus(r.job_id, &info).ok());
      std::this_thread::sleep_for(25ms);
    }
    ASSERT_GE(info.generation, 3u);
  }
  c.KillMaster(SIGKILL);
  service::JobCheckpoint stored;
  std::string notice;
  ASSERT_TRUE(
      master::JobDirectory(c.dir() / "state").LoadCheckpoint(r.job_id, &stored, &notice).ok())
      << notice;
  EXPECT_EQ(stored.arithmetic, kOther)
      << "the checkpoint records the profile that computed the job";

  // The restarted master serves the job's profile before any worker arrives: a worker of this
  // machine's profile is refused even if it is the first to reconnect.
  ASSERT_TRUE(c.StartMaster());
  Process& native = c.AddWorker(1);
  auto client = c.Client(4000, 5);
  service::WorkersSnapshot w;
  ASSERT_TRUE(WaitForWorkers(
      client, &w, [](const auto& s) { return !s.departed.empty() && s.workers.size() == 1; }));
  EXPECT_NE(w.departed.back().reason.find(model::ArithmeticProfile()), std::string::npos)
      << w.departed.back().reason;
  EXPECT_EQ(w.workers[0].arithmetic, kOther);
  for (int i = 0; i < 200 && native.running(); ++i) std::this_thread::sleep_for(50ms);
  EXPECT_FALSE(native.running());
  const std::string log = Slurp(c.dir() / "workers.log");
  EXPECT_NE(log.find("fixed by job " + r.job_id), std::string::npos)
      << "the refusal names the job:\n"
      << log;

  service::JobInfo info;
  ASSERT_TRUE(client.WaitFinal(r.job_id, 60s, &info).ok());
  EXPECT_EQ(info.state, service::JobState::kSucceeded) << info.message;
  EXPECT_EQ(info.notice.find("resumed on"), std::string::npos) << info.notice;
}

TEST(Arithmetic, AllowMixedArithmeticServesBothProfiles) {
  Cluster c("arith-mixed", {"--allow-mixed-arithmetic"});
  auto client = c.Client(4000, 5);
  c.AddWorker(1);
  c.AddWorker(1, {"--arithmetic", kOther});
  service::WorkersSnapshot w;
  ASSERT_TRUE(WaitForWorkers(client, &w, [](const auto& s) { return s.workers.size() == 2; }))
      << Slurp(c.dir() / "workers.log");
  std::set<std::string> profiles;
  for (const auto& v : w.workers) profiles.insert(v.arithmetic);
  EXPECT_EQ(profiles, (std::set<std::string>{model::ArithmeticProfile(), kOther}));
  EXPECT_TRUE(w.departed.empty());
}

}  // namespace
}  // namespace pz::testing
