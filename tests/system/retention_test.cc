// Ended jobs do not stay in the master's memory forever (issue 12.5): beyond --keep-in-memory the
// oldest are archived (status from a summary, fetch from the state directory, the same result),
// also after a restart; `prune` deletes ended jobs for good — named, by count or by age —, never a
// running one, and a dry run deletes nothing.
#include <gtest/gtest.h>

#include "tests/system/service_harness.h"

namespace pz::testing {
namespace {

using namespace std::chrono_literals;

std::map<std::string, service::JobInfo> ById(svcclient::ServiceClient& c) {
  std::vector<service::JobInfo> all;
  EXPECT_TRUE(c.List(&all).ok());
  std::map<std::string, service::JobInfo> m;
  for (auto& i : all) m[i.job_id] = i;
  return m;
}

TEST(Retention, OldEndedJobsAreArchivedFetchableAndPrunable) {
  Cluster c("retention", {"--keep-in-memory", "2"});
  c.AddWorker(2);
  auto client = c.Client(4000, 5);
  std::vector<std::string> ids;
  std::vector<job::JobSpec> specs;
  for (int k = 0; k < 5; ++k) {  // one after the other: job 0 ends first
    specs.push_back(SyntheticSpec(600 + k, 12, 8));
    svcclient::SubmitResult r;
    ASSERT_TRUE(client.Submit(specs.back(), &r).ok());
    service::JobInfo info;
    ASSERT_TRUE(client.WaitFinal(r.job_id, 30s, &info).ok());
    ASSERT_EQ(info.state, service::JobState::kSucceeded);
    ids.push_back(r.job_id);
    std::this_thread::sleep_for(20ms);  // distinct end times
  }
  auto check_archive = [&](svcclient::ServiceClient& client, const char* when) {
    auto jobs = ById(client);
    ASSERT_EQ(jobs.size(), 5u) << when;
    for (int k = 0; k < 5; ++k) {
      const auto& i = jobs[ids[k]];
      EXPECT_EQ(i.archived, k < 3) << when << ": job " << k;
      EXPECT_EQ(i.state, service::JobState::kSucceeded) << when;
      EXPECT_GT(i.ended_unix_s, 0) << when;
      EXPECT_EQ(i.generation, 9u) << when;  // the summary keeps the figures
    }
    // An archived job fetches from disk, bit for bit the in-process result.
    std::vector<service::ScoredGenome> best;
    std::vector<service::GenerationRecord> log;
    job::JobSpec spec;
    ASSERT_TRUE(client.Fetch(ids[0], 5, &best, &log, nullptr, &spec).ok()) << when;
    ExpectSameRun(Reference(specs[0]), best, log);
    EXPECT_EQ(service::EncodeJobSpec(spec), service::EncodeJobSpec(specs[0])) << when;
  };
  check_archive(client, "running master");
  c.KillMaster(SIGKILL);
  ASSERT_TRUE(c.StartMaster());
  auto after = c.Client(4000, 5);
  check_archive(after, "after a restart");

  // A running job is never pruned.
  svcclient::SubmitResult running;
  ASSERT_TRUE(after.Submit(SyntheticSpec(700, 8, 100000, /*sleep_ms=*/5), &running).ok());
  std::vector<std::string> pruned;
  std::vector<job::FieldViolation> refused;
  ASSERT_TRUE(after
                  .Prune({running.job_id, ids[0], "jnosuchjob000000"}, 0, 0, /*dry_run=*/true,
                         &pruned, &refused)
                  .ok());
  EXPECT_EQ(pruned, std::vector<std::string>{ids[0]});
  ASSERT_EQ(refused.size(), 2u);
  EXPECT_EQ(refused[0].field, running.job_id);
  EXPECT_NE(refused[0].description.find("running"), std::string::npos);
  EXPECT_NE(refused[1].description.find("no such job"), std::string::npos);
  EXPECT_TRUE(fs::exists(c.dir() / "state" / "jobs" / ids[0])) << "a dry run deleted";
  // All but the two most recently ended: jobs 0, 1, 2, their folders too.
  ASSERT_TRUE(after.Prune({}, 0, 2, false, &pruned, &refused).ok());
  EXPECT_EQ(std::set<std::string>(pruned.begin(), pruned.end()),
            (std::set<std::string>{ids[0], ids[1], ids[2]}));
  EXPECT_TRUE(refused.empty());
  for (int k = 0; k < 3; ++k) EXPECT_FALSE(fs::exists(c.dir() / "state" / "jobs" / ids[k]));
  auto jobs = ById(after);
  EXPECT_EQ(jobs.size(), 3u);  // jobs 3, 4 and the running one
  EXPECT_TRUE(jobs.count(running.job_id));
  std::vector<service::ScoredGenome> best;
  std::vector<service::GenerationRecord> log;
  EXPECT_EQ(after.Fetch(ids[0], 1, &best, &log).code(), StatusCode::kNotFound);
  // By age: nothing ended a day ago.
  ASSERT_TRUE(after.Prune({}, 86400, 0, false, &pruned, &refused).ok());
  EXPECT_TRUE(pruned.empty());
  // The command line: a rule is required; the running job is refused (exit 5).
  std::string out, err;
  EXPECT_EQ(RunCli({"prune", "--master", c.client_endpoint()}, &out, &err), 2) << err;
  EXPECT_NE(err.find("--older-than"), std::string::npos) << err;
  EXPECT_EQ(RunCli({"prune", running.job_id, ids[3], "--master", c.client_endpoint()}, &out, &err),
            5)
      << out << err;
  EXPECT_NE(out.find("pruned " + ids[3]), std::string::npos) << out;
  EXPECT_NE(err.find("running"), std::string::npos) << err;
  ASSERT_TRUE(after.Cancel(running.job_id).ok());
}

}  // namespace
}  // namespace pz::testing
