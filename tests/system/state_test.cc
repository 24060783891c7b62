// The master's state directory against damage, over real processes (issue 12.2, 12.6): a killed
// master's running jobs whose checkpoints were altered (a flipped bit in several places, cut,
// overwritten, deleted, both current and previous bad) or whose spec was altered are all listed
// again on restart; the ones that can run end "succeeded" with the in-process result bit for bit,
// and status names the file and what was done; a job whose spec is bad is listed failed with the
// reason. Checkpoints that cannot be written show in status and watch until they can; a submission
// that cannot be stored leaves no folder; an empty job folder is removed at start.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "master/checkpoint.h"
#include "service/wire_codec.h"
#include "tests/system/service_harness.h"

namespace pz::testing {
namespace {

using namespace std::chrono_literals;
using master::JobDirectory;

std::string ReadFile(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}
void WriteFile(const fs::path& p, const std::string& bytes) {
  std::ofstream(p, std::ios::binary | std::ios::trunc) << bytes;
}
std::string Flip(std::string s, double where, int bit) {
  if (s.empty()) return s;
  s[static_cast<size_t>(where * static_cast<double>(s.size() - 1))] ^= static_cast<char>(1 << bit);
  return s;
}

/// One job per kind of damage; the spec sleeps so that every job is mid-run when the master dies
/// (the sleep changes no cost: the reference runs without it).
struct Damage {
  std::string name;
  std::function<void(const fs::path& dir)> apply;
  std::string notice;  ///< what status must say ("" = nothing)
  bool fails = false;  ///< the spec is gone: listed as failed
};

TEST(State, DamagedCheckpointsFallBackAndEveryJobEndsAsInProcess) {
  const std::vector<Damage> damages = {
      {"flip-10%",
       [](const fs::path& d) {
         WriteFile(d / "checkpoint.pb", Flip(ReadFile(d / "checkpoint.pb"), 0.1, 3));
       },
       "checksum mismatch"},
      {"flip-50%",
       [](const fs::path& d) {
         WriteFile(d / "checkpoint.pb", Flip(ReadFile(d / "checkpoint.pb"), 0.5, 0));
       },
       "checksum mismatch"},
      {"flip-last",
       [](const fs::path& d) {
         WriteFile(d / "checkpoint.pb", Flip(ReadFile(d / "checkpoint.pb"), 1.0, 7));
       },
       "checkpoint.pb"},
      {"truncated",
       [](const fs::path& d) {
         const auto s = ReadFile(d / "checkpoint.pb");
         WriteFile(d / "checkpoint.pb", s.substr(0, s.size() / 3));
       },
       "checkpoint.pb"},
      {"garbage",
       [](const fs::path& d) { WriteFile(d / "checkpoint.pb", std::string(4096, '\x5a')); },
       "checkpoint.pb"},
      {"deleted", [](const fs::path& d) { fs::remove(d / "checkpoint.pb"); }, "missing"},
      {"both-bad",
       [](const fs::path& d) {
         WriteFile(d / "checkpoint.pb", Flip(ReadFile(d / "checkpoint.pb"), 0.3, 1));
         fs::remove(d / "checkpoint.prev.pb");
       },
       "restarted from generation 0"},
      {"intact", [](const fs::path&) {}, ""},
      {"spec-bad",
       [](const fs::path& d) { WriteFile(d / "spec.pb", Flip(ReadFile(d / "spec.pb"), 0.5, 2)); },
       "spec.pb", true},
  };
  Cluster c("state");
  c.AddWorker(2);
  c.AddWorker(2);
  auto client = c.Client();
  std::vector<std::string> ids;
  std::vector<job::JobSpec> refs;
  for (size_t i = 0; i < damages.size(); ++i) {
    job::JobSpec s = SyntheticSpec(300 + i, 16, 60, /*sleep_ms=*/2);
    svcclient::SubmitResult r;
    ASSERT_TRUE(client.Submit(s, &r).ok());
    ids.push_back(r.job_id);
    std::get<job::SyntheticProblem>(s.problem).sleep_ms = 0;
    refs.push_back(s);
  }
  // Every job past generation 4 and running.
  for (const auto& id : ids) {
    service::JobInfo info;
    for (int i = 0; i < 600 && info.generation < 5; ++i) {
      ASSERT_TRUE(client.GetStatus(id, &info).ok());
      std::this_thread::sleep_for(20ms);
    }
    ASSERT_GE(info.generation, 5u) << id;
    ASSERT_EQ(info.state, service::JobState::kRunning) << id << ": make the jobs longer";
  }
  c.KillMaster(SIGKILL);
  const fs::path jobs = c.dir() / "state" / "jobs";
  for (size_t i = 0; i < damages.size(); ++i) {
    // Killed between the two renames of a write, a job has its previous checkpoint only (a state
    // the fallback covers, as "deleted" below shows): finish the write so the damage has a file.
    const fs::path d = jobs / ids[i];
    if (!fs::exists(d / "checkpoint.pb")) fs::rename(d / "checkpoint.prev.pb", d / "checkpoint.pb");
    damages[i].apply(d);
  }
  ASSERT_TRUE(c.StartMaster());
  auto after = c.Client(4000, 5);
  std::vector<service::JobInfo> all;
  ASSERT_TRUE(after.List(&all).ok());
  EXPECT_EQ(all.size(), damages.size()) << "a job vanished";
  for (size_t i = 0; i < damages.size(); ++i) {
    SCOPED_TRACE(damages[i].name);
    service::JobInfo info;
    ASSERT_TRUE(after.WaitFinal(ids[i], 60s, &info).ok());
    if (damages[i].notice.empty()) {
      EXPECT_TRUE(info.notice.empty()) << info.notice;
    } else {
      EXPECT_NE(info.notice.find(damages[i].notice), std::string::npos) << info.notice;
      EXPECT_NE(info.notice.find((jobs / ids[i]).string()), std::string::npos)
          << "names the file: " << info.notice;
    }
    if (damages[i].fails) {
      EXPECT_EQ(info.state, service::JobState::kFailed);
      EXPECT_NE(info.message.find("spec"), std::string::npos) << info.message;
      continue;
    }
    ASSERT_EQ(info.state, service::JobState::kSucceeded) << info.message;
    std::vector<service::ScoredGenome> best;
    std::vector<service::GenerationRecord> log;
    ASSERT_TRUE(after.Fetch(ids[i], 5, &best, &log).ok());
    ExpectSameRun(Reference(refs[i]), best, log);
  }
}

TEST(State, UnwritableCheckpointsShowInStatusUntilTheyAreWrittenAgain) {
  Cluster c("storage");
  c.AddWorker(2);
  auto client = c.Client();
  job::JobSpec s = SyntheticSpec(41, 16, 150, /*sleep_ms=*/2);
  svcclient::SubmitResult r;
  ASSERT_TRUE(client.Submit(s, &r).ok());
  service::JobInfo info;
  for (int i = 0; i < 300 && info.generation < 3; ++i) {
    ASSERT_TRUE(client.GetStatus(r.job_id, &info).ok());
    std::this_thread::sleep_for(20ms);
  }
  // The next writes fail: their temporary file's name is taken by a folder.
  const fs::path blocker = c.dir() / "state" / "jobs" / r.job_id / "checkpoint.pb.tmp";
  // The master writes and renames that file every generation: retry while it is there.
  bool blocked = false;
  for (int i = 0; i < 1000 && !blocked; ++i) {
    std::error_code ec;
    blocked = fs::create_directory(blocker, ec) && !ec;
    if (!blocked) std::this_thread::sleep_for(1ms);
  }
  ASSERT_TRUE(blocked) << "could not put a folder at " << blocker;
  bool shown = false;
  for (int i = 0; i < 300 && !shown; ++i) {
    ASSERT_TRUE(client.GetStatus(r.job_id, &info).ok());
    shown = !info.storage_error.empty();
    std::this_thread::sleep_for(20ms);
  }
  ASSERT_TRUE(shown) << "status never showed the failing writes";
  EXPECT_NE(info.storage_error.find("checkpoint.pb.tmp"), std::string::npos) << info.storage_error;
  EXPECT_GT(info.storage_error_since_unix_s, 0);
  EXPECT_EQ(info.state, service::JobState::kRunning);
  // Watch events say it too.
  bool in_event = false;
  ASSERT_TRUE(client
                  .Watch(
                      r.job_id,
                      [&](const service::JobEvent& e) {
                        in_event = in_event || !e.storage_error.empty();
                        return !in_event;
                      },
                      20s)
                  .ok());
  EXPECT_TRUE(in_event);
  fs::remove_all(blocker);
  ASSERT_TRUE(client.WaitFinal(r.job_id, 60s, &info).ok());
  EXPECT_EQ(info.state, service::JobState::kSucceeded) << info.message;
  EXPECT_TRUE(info.storage_error.empty()) << info.storage_error;
  std::vector<service::ScoredGenome> best;
  std::vector<service::GenerationRecord> log;
  ASSERT_TRUE(client.Fetch(r.job_id, 5, &best, &log).ok());
  std::get<job::SyntheticProblem>(s.problem).sleep_ms = 0;
  ExpectSameRun(Reference(s), best, log);
}

TEST(State, AnUnstorableSubmissionLeavesNoFolderAndEmptyFoldersGoAtStart) {
  Cluster c("nofolder");
  auto client = c.Client();
  // The spec file cannot be written: its temporary file's name is taken by a folder.
  const job::JobSpec s = SyntheticSpec(51, 8, 2);
  const std::string token = "fixed-token";
  const std::string id = service::JobIdOf(service::EncodeJobSpec(s), token);
  const fs::path dir = c.dir() / "state" / "jobs" / id;
  fs::create_directories(dir / "spec.pb.tmp");
  svcclient::SubmitResult r;
  const Status st = client.Submit(s, &r, nullptr, token);
  EXPECT_FALSE(st.ok());
  EXPECT_NE(st.message().find("cannot store the job"), std::string::npos) << st.message();
  EXPECT_FALSE(fs::exists(dir)) << "the failed submission left its folder";
  // Now it can be stored: the same submission goes through.
  ASSERT_TRUE(client.Submit(s, &r, nullptr, token).ok());
  EXPECT_EQ(r.job_id, id);
  // An empty folder (a submission cut short) is removed at the next start, with one log line.
  c.KillMaster(SIGKILL);
  const fs::path empty = c.dir() / "state" / "jobs" / "j0123456789abcde";
  fs::create_directories(empty);
  ASSERT_TRUE(c.StartMaster());
  std::vector<service::JobInfo> all;
  ASSERT_TRUE(c.Client().List(&all).ok());
  EXPECT_FALSE(fs::exists(empty));
  std::ifstream log(c.dir() / "master.log");
  const std::string text{std::istreambuf_iterator<char>(log), {}};
  EXPECT_NE(text.find("no spec.pb"), std::string::npos);
}

}  // namespace
}  // namespace pz::testing
