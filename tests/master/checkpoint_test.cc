// The state directory's files (master/checkpoint.h): checksummed spec and checkpoints, the
// previous checkpoint kept, and what loading does with a bad one — a flipped bit anywhere, a
// truncated or overwritten file, a missing one, both bad — and with files written before stored
// files existed.
#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "kinds/kinds.h"
#include "master/checkpoint.h"
#include "master/job_runner.h"
#include "opt/inline_evaluator.h"
#include "service/wire_codec.h"

namespace pz::master {
namespace {

namespace fs = std::filesystem;
using service::JobCheckpoint;

job::JobSpec Spec() {
  job::JobSpec s;
  s.seed = 3;
  job::SyntheticProblem p;
  p.cost = job::SyntheticProblem::Cost::kFunction;
  p.genome_bits = 48;
  s.problem = p;
  job::GaSettings ga;
  ga.population = 12;
  ga.generations = 10;
  ga.stall_generations = 0;
  s.ga = ga;
  return s;
}

class CheckpointFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    root_ = fs::temp_directory_path() /
            ("pz-ckpt-" + std::to_string(::getpid()) + "-" +
             ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(root_);
    // The checkpoints of generations 3 and 4 of a real run: the previous and the current one.
    JobRunner runner("j1", Spec());
    ASSERT_TRUE(runner.Init(kinds::All()).ok());
    std::unique_ptr<opt::FitnessFunction> f;
    ASSERT_TRUE(kinds::All().MakeFitness(Spec(), &f).ok());
    opt::InlineEvaluator eval(*f);
    for (int g = 0; g < 5; ++g) {
      runner.Step(eval);
      if (g == 3) previous_ = runner.checkpoint();
    }
    current_ = runner.checkpoint();
    ASSERT_TRUE(dir().SaveSpec("j1", service::EncodeJobSpec(Spec())).ok());
    ASSERT_TRUE(dir().SaveCheckpoint(previous_).ok());
    ASSERT_TRUE(dir().SaveCheckpoint(current_).ok());
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(root_);
  }
  JobDirectory dir() const { return JobDirectory(root_); }
  fs::path file(const char* name) const { return dir().dir("j1") / name; }
  std::string Read(const char* name) const {
    std::ifstream in(file(name), std::ios::binary);
    return {std::istreambuf_iterator<char>(in), {}};
  }
  void Write(const char* name, const std::string& bytes) const {
    std::ofstream(file(name), std::ios::binary | std::ios::trunc) << bytes;
  }
  static std::string Encoded(const JobCheckpoint& c) { return service::EncodeCheckpoint(c); }

  fs::path root_;
  JobCheckpoint previous_, current_;
};

TEST_F(CheckpointFiles, TheCurrentOneLoadsAndThePreviousIsKept) {
  JobCheckpoint c;
  std::string notice;
  ASSERT_TRUE(dir().LoadCheckpoint("j1", &c, &notice).ok());
  EXPECT_TRUE(notice.empty()) << notice;
  EXPECT_EQ(Encoded(c), Encoded(current_));
  EXPECT_TRUE(fs::exists(file(JobDirectory::kPreviousFile)));
  std::string spec;
  ASSERT_TRUE(dir().LoadSpec("j1", &spec).ok());
  EXPECT_EQ(spec, service::EncodeJobSpec(Spec()));
}

TEST_F(CheckpointFiles, AFlippedBitAnywhereFallsBackToThePreviousOne) {
  const std::string good = Read(JobDirectory::kCheckpointFile);
  ASSERT_GT(good.size(), 100u);
  int tried = 0;
  ::testing::internal::CaptureStderr();  // the fallback says why; protobuf adds nothing of its own
  for (size_t pos = 0; pos < good.size(); pos += std::max<size_t>(1, good.size() / 97)) {
    for (int bit : {0, 5}) {
      std::string bad = good;
      bad[pos] = static_cast<char>(bad[pos] ^ (1 << bit));
      Write(JobDirectory::kCheckpointFile, bad);
      JobCheckpoint c;
      std::string notice;
      ASSERT_TRUE(dir().LoadCheckpoint("j1", &c, &notice).ok()) << "byte " << pos;
      EXPECT_EQ(Encoded(c), Encoded(previous_))
          << "byte " << pos << " bit " << bit << ": " << notice;
      EXPECT_NE(notice.find(file(JobDirectory::kCheckpointFile).string()), std::string::npos)
          << notice;
      EXPECT_NE(notice.find("resumed from " + file(JobDirectory::kPreviousFile).string()),
                std::string::npos)
          << notice;
      ++tried;
    }
  }
  const std::string logged = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(logged.find("invalid UTF-8"), std::string::npos) << logged;
  EXPECT_EQ(logged.find("[libprotobuf"), std::string::npos) << logged;
  EXPECT_GT(tried, 150);
}

TEST_F(CheckpointFiles, TruncatedOverwrittenOrMissingFallsBack) {
  const std::string good = Read(JobDirectory::kCheckpointFile);
  for (const std::string& bad :
       {good.substr(0, good.size() / 2), good.substr(0, good.size() - 1),
        std::string("garbage garbage garbage"), std::string(), std::string(good.size(), '\0')}) {
    Write(JobDirectory::kCheckpointFile, bad);
    JobCheckpoint c;
    std::string notice;
    ASSERT_TRUE(dir().LoadCheckpoint("j1", &c, &notice).ok()) << bad.size() << " bytes";
    EXPECT_EQ(Encoded(c), Encoded(previous_)) << notice;
    EXPECT_FALSE(notice.empty());
  }
  fs::remove(file(JobDirectory::kCheckpointFile));
  JobCheckpoint c;
  std::string notice;
  ASSERT_TRUE(dir().LoadCheckpoint("j1", &c, &notice).ok());
  EXPECT_EQ(Encoded(c), Encoded(previous_));
  EXPECT_NE(notice.find("missing"), std::string::npos) << notice;
}

TEST_F(CheckpointFiles, AnotherJobsCheckpointIsRefused) {
  JobCheckpoint other = current_;
  other.job_id = "j2";
  ASSERT_TRUE(dir().SaveCheckpoint(other).ok());
  fs::rename(dir().dir("j2") / JobDirectory::kCheckpointFile, file(JobDirectory::kCheckpointFile));
  JobCheckpoint c;
  std::string notice;
  ASSERT_TRUE(dir().LoadCheckpoint("j1", &c, &notice).ok());
  EXPECT_NE(notice.find("the checkpoint of job j2"), std::string::npos) << notice;
}

TEST_F(CheckpointFiles, BothBadIsARestartFromTheSpecSaidSo) {
  Write(JobDirectory::kCheckpointFile, "x");
  std::string prev = Read(JobDirectory::kPreviousFile);
  prev[prev.size() / 2] ^= 1;
  Write(JobDirectory::kPreviousFile, prev);
  JobCheckpoint c;
  std::string notice;
  const Status s = dir().LoadCheckpoint("j1", &c, &notice);
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_NE(notice.find("checksum mismatch"), std::string::npos) << notice;
  EXPECT_NE(notice.find("restarted from generation 0"), std::string::npos) << notice;
  EXPECT_FALSE(c.optimizer.initialized);
}

TEST_F(CheckpointFiles, ANewJobHasNoCheckpointAndNoNotice) {
  fs::remove(file(JobDirectory::kCheckpointFile));
  fs::remove(file(JobDirectory::kPreviousFile));
  JobCheckpoint c;
  std::string notice;
  EXPECT_EQ(dir().LoadCheckpoint("j1", &c, &notice).code(), StatusCode::kNotFound);
  EXPECT_TRUE(notice.empty()) << notice;
}

TEST_F(CheckpointFiles, FilesWrittenBeforeStoredFilesStillLoad) {
  Write(JobDirectory::kCheckpointFile, Encoded(current_));  // a bare JobCheckpoint
  Write(JobDirectory::kSpecFile, service::EncodeJobSpec(Spec()));
  JobCheckpoint c;
  std::string notice, spec;
  ASSERT_TRUE(dir().LoadCheckpoint("j1", &c, &notice).ok());
  EXPECT_TRUE(notice.empty()) << notice;
  EXPECT_EQ(Encoded(c), Encoded(current_));
  ASSERT_TRUE(dir().LoadSpec("j1", &spec).ok());
  EXPECT_EQ(spec, service::EncodeJobSpec(Spec()));
}

TEST_F(CheckpointFiles, ACorruptSpecIsNamed) {
  std::string spec = Read(JobDirectory::kSpecFile);
  spec[spec.size() - 3] ^= 0x10;
  Write(JobDirectory::kSpecFile, spec);
  std::string bytes;
  const Status s = dir().LoadSpec("j1", &bytes);
  EXPECT_EQ(s.code(), StatusCode::kDataLoss);
  EXPECT_NE(s.message().find(file(JobDirectory::kSpecFile).string()), std::string::npos)
      << s.message();
}

}  // namespace
}  // namespace pz::master
