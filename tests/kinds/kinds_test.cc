// The one list of job kinds (kinds/kinds.h): every kind is there once, under its spec's kind()
// name, with a layout and a fitness; an unknown kind is refused naming it.
#include <gtest/gtest.h>

#include <algorithm>

#include "kinds/kinds.h"
#include "tests/testing/hgann_spec.h"

namespace pz::kinds {
namespace {

TEST(Kinds, AllHasEveryKindOnce) {
  for (const char* name : {"synthetic", "hgann", "complete_model"}) {
    const job::JobKind* k = All().Find(name);
    ASSERT_NE(k, nullptr) << name;
    EXPECT_EQ(k->name, name);
    EXPECT_TRUE(k->validate && k->layout && k->make_fitness) << name;
  }
  EXPECT_EQ(All().Find("hgan"), nullptr);
  EXPECT_EQ(All().Find("diagnose"), nullptr);  // removed (issue 38): its tag is reserved
}

// kind() comes from the problem's type (each problem names its kind): every problem a spec can
// hold has its kind registered, under that name (a problem added to JobSpec::problem without its
// line in kinds/kinds.cc fails here), and the spec without a problem is told which there are.
TEST(Kinds, EveryProblemOfASpecHasItsRegisteredKind) {
  const std::vector<std::string> names = job::JobKindNames();
  ASSERT_GE(names.size(), 3u);  // new kinds come after these, in the order of JobSpec::problem
  EXPECT_EQ(std::vector<std::string>(names.begin(), names.begin() + 3),
            (std::vector<std::string>{"hgann", "synthetic", "complete_model"}));
  std::string listed;
  for (const std::string& name : names) {
    EXPECT_NE(All().Find(name), nullptr) << name;
    EXPECT_EQ(std::count(names.begin(), names.end(), name), 1) << name;
    listed += (listed.empty() ? "" : ", ") + name;
  }
  job::JobSpec spec;
  spec.problem = job::CompleteModelProblem{};
  EXPECT_EQ(spec.kind(), "complete_model");
  spec.problem = std::monostate{};
  EXPECT_EQ(spec.kind(), "");
  spec.ga = job::GaSettings{};
  const std::vector<job::FieldViolation> v = All().Validate(spec);
  ASSERT_EQ(v.size(), 1u) << testing::Descriptions(v);
  EXPECT_EQ(v[0].field, "problem");
  EXPECT_EQ(v[0].description, "problem: one of " + listed + " must be set");
}

TEST(Kinds, SpecsOfEachKindFindTheirKind) {
  const job::JobSpec hgann = testing::NominalHgannSpec(10, 1);
  EXPECT_EQ(hgann.kind(), "hgann");
  job::GenomeLayout l;
  ASSERT_TRUE(All().Layout(hgann, &l).ok());
  EXPECT_EQ(l.bits, 1415);
  EXPECT_TRUE(All().Validate(hgann).empty()) << testing::Descriptions(All().Validate(hgann));

  job::JobSpec synthetic;
  job::SyntheticProblem p;
  p.genome_bits = 24;
  synthetic.problem = p;
  job::GaSettings ga;
  synthetic.ga = ga;
  EXPECT_EQ(synthetic.kind(), "synthetic");
  ASSERT_TRUE(All().Layout(synthetic, &l).ok());
  EXPECT_EQ(l.bits, 24);
  std::unique_ptr<opt::FitnessFunction> f;
  ASSERT_TRUE(All().MakeFitness(synthetic, &f).ok());
  opt::Genome g;
  g.bits.assign(24, 1);
  EXPECT_EQ(f->Evaluate(g).status, opt::FitnessStatus::kOk);
}

// Output moves (opt/ga.h 9.): the hgann kind has its move (hgann/output_move.h); a kind without one
// runs every offspring bred when the spec leaves them to their default, and refuses a spec that
// asks for them, naming the field.
TEST(Kinds, OnlyAKindWithAMoveTakesOutputMoves) {
  job::JobSpec hgann = testing::NominalHgannSpec(10, 1);
  hgann.ga->islands = 4;
  opt::GeneticAlgorithm::Move move;
  ASSERT_TRUE(All().Move(hgann, &move).ok());
  EXPECT_FALSE(static_cast<bool>(move))
      << "unset, without a spread penalty: none (hgann::HgannOutputMoves)";
  std::get<job::HgannProblem>(hgann.problem).spread_penalty = 10;
  ASSERT_TRUE(All().Move(hgann, &move).ok());
  EXPECT_TRUE(static_cast<bool>(move));
  std::get<job::HgannProblem>(hgann.problem).spread_penalty = 0;
  hgann.ga->output_moves = 3;  // asked for: at any λ
  ASSERT_TRUE(All().Move(hgann, &move).ok());
  EXPECT_TRUE(static_cast<bool>(move));
  EXPECT_TRUE(All().Validate(hgann).empty()) << testing::Descriptions(All().Validate(hgann));

  job::JobSpec synthetic;
  job::SyntheticProblem p;
  p.genome_bits = 24;
  synthetic.problem = p;
  synthetic.ga = job::GaSettings{};
  synthetic.ga->islands = 4;
  ASSERT_TRUE(All().Move(synthetic, &move).ok());
  EXPECT_FALSE(static_cast<bool>(move));
  EXPECT_TRUE(All().Validate(synthetic).empty()) << "unset: none for a kind without a move";
  synthetic.ga->output_moves = 0;
  EXPECT_TRUE(All().Validate(synthetic).empty());
  synthetic.ga->output_moves = 2;
  const std::vector<job::FieldViolation> v = All().Validate(synthetic);
  ASSERT_EQ(v.size(), 1u) << testing::Descriptions(v);
  EXPECT_EQ(v[0].field, "ga.output_moves");
  EXPECT_EQ(v[0].description,
            "ga.output_moves = 2: the synthetic kind has no output move; must be 0 or unset");
}

}  // namespace
}  // namespace pz::kinds
