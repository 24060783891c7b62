// A master serves one arithmetic profile (model::ArithmeticProfile(): the build and the measured
// fingerprint of its kernels): workers of two kinds of machine would give a job results that
// differ in their last bits depending on which computed what. The first worker fixes the profile;
// a worker announcing another is refused with the reason (the part that differs), exits instead of
// retrying, and shows among the departures. --allow-mixed-arithmetic accepts both. A job records
// the profile that computed it, and a master restarted on its state directory serves that profile
// while the job runs.
#include <gtest/gtest.h>

#include <cstdio>
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
bool WaitForWorkers(svcclient::ServiceClient& client, service::WorkersSnapshot* w,
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
  svcclient::SubmitResult r;
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


// Runs `spec` on the cluster's workers and fetches its best and log.
void RunJob(Cluster& c, const job::JobSpec& spec, std::vector<service::ScoredGenome>* best,
            std::vector<service::GenerationRecord>* log) {
  auto client = c.Client(4000, 5);
  svcclient::SubmitResult r;
  ASSERT_TRUE(client.Submit(spec, &r).ok());
  service::JobInfo info;
  ASSERT_TRUE(client.WaitFinal(r.job_id, 60s, &info).ok());
  ASSERT_EQ(info.state, service::JobState::kSucceeded) << info.message;
  ASSERT_TRUE(client.Fetch(r.job_id, 8, best, log).ok());
}

// The guard measures (issue 44): a worker is admitted when it computes what the served workers
// compute. PIEZOID_ARITHMETIC_SKEW=fin makes a worker compute as another machine would (the fin
// part of its measured fingerprint differs, and every cost it returns moves by one ulp): it is
// refused by the part that differs, naming the worker, and the job's result is the agreeing
// worker's, bit for bit the in-process reference. Admitted (--allow-mixed-arithmetic), the same
// worker changes the result: the refusal is what keeps it.
TEST(Arithmetic, AWorkerThatComputesOtherBitsIsRefusedByWhatItComputes) {
  const job::JobSpec spec = SyntheticSpec(44, 24, 8);
  const service::JobCheckpoint ref = Reference(spec);
  Cluster c("arith-measured");
  auto client = c.Client(4000, 5);
  c.AddWorker(1);
  service::WorkersSnapshot w;
  ASSERT_TRUE(WaitForWorkers(client, &w, [](const auto& s) { return s.workers.size() == 1; }));
  Process& skewed = c.AddWorker(1, {}, {"PIEZOID_ARITHMETIC_SKEW=fin"});
  const pid_t skewed_pid = skewed.pid();
  ASSERT_TRUE(WaitForWorkers(client, &w, [](const auto& s) { return !s.departed.empty(); }))
      << Slurp(c.dir() / "workers.log");
  const std::string& why = w.departed.back().reason;
  EXPECT_NE(why.find("differs in fin ("), std::string::npos) << why;
  EXPECT_EQ(why.find("libm ("), std::string::npos) << "only the part that differs: " << why;
  EXPECT_EQ(w.workers.size(), 1u);
  for (int i = 0; i < 200 && skewed.running(); ++i) std::this_thread::sleep_for(50ms);
  EXPECT_FALSE(skewed.running()) << "a refused worker stops";
  const std::string log = Slurp(c.dir() / "workers.log");
  EXPECT_NE(log.find("pid " + std::to_string(skewed_pid)), std::string::npos)
      << "the refusal names the worker:\n"
      << log;
  EXPECT_NE(log.find("computes differently from this master's workers in fin ("),
            std::string::npos)
      << log;

  std::vector<service::ScoredGenome> best;
  std::vector<service::GenerationRecord> glog;
  ASSERT_NO_FATAL_FAILURE(RunJob(c, spec, &best, &glog));
  ExpectSameRun(ref, best, glog);

  Cluster mixed("arith-measured-mixed", {"--allow-mixed-arithmetic"});
  mixed.AddWorker(1, {}, {"PIEZOID_ARITHMETIC_SKEW=fin"});
  std::vector<service::ScoredGenome> skewed_best;
  ASSERT_NO_FATAL_FAILURE(RunJob(mixed, spec, &skewed_best, &glog));
  ASSERT_FALSE(skewed_best.empty());
  EXPECT_NE(skewed_best[0].fitness.cost, ref.best[0].fitness.cost)
      << "the skewed worker's costs are its own";
}

// The same by a real difference of arithmetic: OpenBLAS's kernels for another CPU core
// (OPENBLAS_CORETYPE, read when the library loads) change the dense backend's bits where the build
// uses OpenBLAS. Whatever this machine is, a worker is admitted exactly when its measured profile
// (`piezoid doctor --profile` under the same environment) equals the served one.
TEST(Arithmetic, AdmissionFollowsTheMeasuredProfileUnderAnotherBlasCore) {
  const std::string env = "OPENBLAS_CORETYPE=Prescott";
  std::string theirs;
  {
    const std::string cmd =
        "env " + env + " '" + (BuildDir() / "client" / "piezoid").string() + "' doctor --profile";
    FILE* f = ::popen(cmd.c_str(), "r");
    ASSERT_NE(f, nullptr);
    char buf[512];
    while (std::fgets(buf, sizeof buf, f) != nullptr) theirs += buf;
    ASSERT_EQ(::pclose(f), 0) << theirs;
  }
  ASSERT_FALSE(theirs.empty());
  const std::string measured = theirs.substr(0, theirs.find_last_not_of('\n') + 1);
  Cluster c("arith-blas");
  auto client = c.Client(4000, 5);
  c.AddWorker(1);
  service::WorkersSnapshot w;
  ASSERT_TRUE(WaitForWorkers(client, &w, [](const auto& s) { return s.workers.size() == 1; }));
  c.AddWorker(1, {}, {env});
  if (measured == model::ArithmeticProfile()) {
    ASSERT_TRUE(WaitForWorkers(client, &w, [](const auto& s) { return s.workers.size() == 2; }))
        << "the same measured profile is admitted:\n"
        << Slurp(c.dir() / "workers.log");
    EXPECT_TRUE(w.departed.empty());
  } else {
    ASSERT_TRUE(WaitForWorkers(client, &w, [](const auto& s) { return !s.departed.empty(); }))
        << Slurp(c.dir() / "workers.log");
    EXPECT_NE(w.departed.back().reason.find(model::ArithmeticDifference(
                  model::ArithmeticProfile(), measured)),
              std::string::npos)
        << w.departed.back().reason;
    EXPECT_NE(w.departed.back().reason.find("dense ("), std::string::npos)
        << w.departed.back().reason;
    EXPECT_EQ(w.workers.size(), 1u);
  }
}

}  // namespace
}  // namespace pz::testing
