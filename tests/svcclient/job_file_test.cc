// Job files (svcclient/job_file.h): an hgann spec's case_set_dir is read relative to the job file
// and embedded; a folder and cases at once, or a folder that is not a case set, are named.
#include "svcclient/job_file.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "hgann/identify.h"
#include "kinds/kinds.h"
#include "tests/testing/hgann_spec.h"

namespace pz::client {
namespace {

using testing::Descriptions;
using testing::HasViolation;
const io::CaseSet& Nominal() { return testing::NominalCaseSet(); }
bool HasField(const std::vector<job::FieldViolation>& v, const std::string& field,
              const std::string& text = "") {
  return HasViolation(v, field, text);
}
std::string All(const std::vector<job::FieldViolation>& v) { return Descriptions(v); }

namespace fs = std::filesystem;
const fs::path kExamples = fs::path(PIEZOID_DATA_DIR) / ".." / "examples";
using job::CaseRole;
using job::FieldViolation;
using job::HgannProblem;
using job::JobSpec;

TEST(HgannJobFile, CaseSetDirIsReadRelativeToTheJobFile) {
  JobSpec s;
  std::vector<FieldViolation> v;
  ASSERT_TRUE(svcclient::LoadJobSpecFile(kExamples / "hgann_quick.json", &s, &v).ok()) << All(v);
  const auto& h = std::get<HgannProblem>(s.problem);
  EXPECT_TRUE(h.case_set_dir.empty());
  ASSERT_EQ(h.cases.size(), Nominal().cases.size());
  EXPECT_EQ(h.cases[4].angle_deg, Nominal().cases[4].angle_deg);
  EXPECT_EQ(h.cases[4].voltage_v, Nominal().cases[4].u);
  EXPECT_EQ(h.cases[4].role, CaseRole::kTrain);
  EXPECT_NE(h.source.find("bimorph-fin/nominal"), std::string::npos) << h.source;
  EXPECT_TRUE(kinds::All().Validate(s).empty());
  EXPECT_EQ(s.ga->population, 60);
  EXPECT_EQ(s.ga->generations, 40);

  JobSpec paper;
  ASSERT_TRUE(svcclient::LoadJobSpecFile(kExamples / "hgann_paper_job.json", &paper, &v).ok())
      << All(v);
  EXPECT_EQ(paper.ga->population, 400);
  EXPECT_EQ(paper.ga->generations, 1000);
  EXPECT_EQ(paper.ga->stall_generations, 200);
  EXPECT_EQ(paper.ga->mutation_probability, 0.01);
  EXPECT_FALSE(std::get<job::HgannProblem>(paper.problem).trend_seeds);
  EXPECT_EQ(std::get<job::HgannProblem>(paper.problem).preset, "paper");
  EXPECT_EQ(paper.ga->islands, 1);
  EXPECT_EQ(std::get<job::HgannProblem>(paper.problem).spread_penalty, 10);  // given beside it
  EXPECT_TRUE(kinds::All().Validate(paper).empty());

  // The default job: the robust preset of `piezoid identify` (hgann::SearchPreset("robust")),
  // which the file does not spell out: it is what the spec's unset fields mean.
  JobSpec robust;
  ASSERT_TRUE(svcclient::LoadJobSpecFile(kExamples / "hgann_job.json", &robust, &v).ok()) << All(v);
  const auto preset = hgann::SearchPreset("robust");
  ASSERT_TRUE(preset.has_value());
  EXPECT_EQ(robust.ga->population, 400);
  EXPECT_EQ(robust.ga->islands, preset->islands);
  EXPECT_EQ(robust.ga->generations, preset->generations);
  EXPECT_EQ(robust.ga->stall_generations, preset->stall_generations);  // 30, not the GA's 200
  EXPECT_EQ(job::ToGaOptions(robust, job::GenomeLayout{1415, 0}).stall_relative,
            preset->stall_relative);
  EXPECT_EQ(job::ToGaOptions(paper, job::GenomeLayout{1415, 0}).stall_relative, 0.0);
  EXPECT_EQ(std::get<job::HgannProblem>(robust.problem).spread_penalty, preset->spread_penalty);
  EXPECT_EQ(std::get<job::HgannProblem>(robust.problem).trend_seeds, preset->trend_seeds);
  EXPECT_EQ(robust.seed, paper.seed);
  EXPECT_TRUE(kinds::All().Validate(robust).empty());

  // The archipelago: the same job with islands and generations, the migration by its defaults.
  JobSpec islands;
  ASSERT_TRUE(svcclient::LoadJobSpecFile(kExamples / "hgann_islands_job.json", &islands, &v).ok())
      << All(v);
  EXPECT_EQ(islands.ga->islands, 4);
  EXPECT_EQ(islands.ga->generations, 560);
  EXPECT_EQ(islands.ga->migration_interval, 25);
  EXPECT_EQ(islands.ga->migration_margin, 0.2);
  EXPECT_EQ(islands.ga->topology, opt::MigrationTopology::kFullyConnected);
  EXPECT_TRUE(islands.ga->island_mutation.empty());
  EXPECT_EQ(islands.ga->output_moves, opt::GaOptions::kAutoOutputMoves);
  EXPECT_EQ(job::ToGaOptions(islands, job::GenomeLayout{1415, 0}).OutputMoves(), 32);
  EXPECT_EQ(islands.seed, paper.seed);
  EXPECT_TRUE(kinds::All().Validate(islands).empty());

  // Cases and a folder at once, or a folder that is not a case set: named.
  v.clear();
  Status st = svcclient::JobSpecFromJsonFile(
      R"({"version": 1, "hgann": {"case_set_dir": "x", "cases": [{"number": 1}]}, "ga": {}})", ".",
      &s, &v);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(HasField(v, "hgann.case_set_dir", "cannot be combined")) << All(v);
  v.clear();
  st = svcclient::JobSpecFromJsonFile(
      R"({"version": 1, "hgann": {"case_set_dir": "nowhere"}, "ga": {}})",
      fs::path(PIEZOID_TEST_DATA_DIR), &s, &v);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(HasField(v, "hgann.case_set_dir", "cannot be read")) << All(v);
  EXPECT_NE(st.message().find("nowhere"), std::string::npos);
}

}  // namespace
}  // namespace pz::client
