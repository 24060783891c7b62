// The "hgann" job kind: a spec built from the bundled case set gives the same fitness as
// `piezoid identify` on that folder; every bad field is named; extreme but valid specs evaluate to
// finite costs. (The same run through the job runner: tests/master/job_runner_test.cc; the spec
// through the wire and JSON: tests/service/spec_codec_test.cc; job files:
// tests/svcclient/job_file_test.cc.)
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <random>

#include "hgann/hgann_job.h"
#include "opt/inline_evaluator.h"
#include "tests/testing/hgann_spec.h"
#include "model/chromosome.h"

namespace pz::hgann {

using job::CaseRole;
using job::FieldViolation;
using job::GaSettings;
using job::GenomeLayout;
using job::HgannProblem;
using job::JobKind;
using job::JobKindRegistry;
using job::JobSpec;
using opt::FitnessFunction;
using opt::FitnessResult;
using opt::FitnessStatus;
using opt::Genome;
using opt::SanitizeFitness;
namespace {

using testing::Descriptions;
using testing::HasViolation;
const io::CaseSet& Nominal() { return testing::NominalCaseSet(); }
JobSpec NominalSpec(int population, int generations) {
  return testing::NominalHgannSpec(population, generations);
}
bool HasField(const std::vector<FieldViolation>& v, const std::string& field,
              const std::string& text = "") {
  return HasViolation(v, field, text);
}

/// A registry holding this folder's kind only (the one list of kinds is kinds/kinds.h, a floor up).
const JobKindRegistry& Kinds() {
  static const JobKindRegistry* r = [] {
    auto* k = new JobKindRegistry;
    k->Register(HgannJobKind());
    return k;
  }();
  return *r;
}

std::string All(const std::vector<FieldViolation>& v) { return Descriptions(v); }

TEST(HgannJob, KindIsRegisteredWithThe1415BitLayout) {
  const JobKind* k = Kinds().Find("hgann");
  ASSERT_NE(k, nullptr);
  GenomeLayout l;
  ASSERT_TRUE(Kinds().Layout(NominalSpec(10, 1), &l).ok());
  EXPECT_EQ(l.bits, 1415);
  EXPECT_TRUE(Kinds().Validate(NominalSpec(10, 1)).empty());
}

TEST(HgannJob, SpecOfTheCaseSetBuildsTheSameFitnessAsIdentify) {
  const HgannFitnessConfig direct = HgannConfigFromCaseSet(Nominal(), model::ParameterRanges{});
  HgannFitnessConfig via;
  ASSERT_TRUE(
      HgannConfigFromProblem(std::get<HgannProblem>(NominalSpec(10, 1).problem), &via).ok());
  ASSERT_EQ(via.cases.size(), direct.cases.size());
  for (size_t i = 0; i < via.cases.size(); ++i) {
    EXPECT_EQ(via.cases[i].number, direct.cases[i].number);
    EXPECT_EQ(via.cases[i].drive.amplitude_v, direct.cases[i].drive.amplitude_v);
    EXPECT_EQ(via.cases[i].drive.frequency_hz, direct.cases[i].drive.frequency_hz);
    EXPECT_EQ(via.cases[i].drive.sample_rate_hz, direct.cases[i].drive.sample_rate_hz);
    EXPECT_EQ(via.cases[i].drive.cycles, direct.cases[i].drive.cycles);
    EXPECT_EQ(via.cases[i].measured_deg, direct.cases[i].measured_deg);
    EXPECT_EQ(via.cases[i].b1, direct.cases[i].b1);
    EXPECT_EQ(via.cases[i].b2, direct.cases[i].b2);
    EXPECT_EQ(via.cases[i].training, direct.cases[i].training);
  }
  EXPECT_EQ(via.normalization, direct.normalization);
  EXPECT_EQ(via.ranges, direct.ranges);

  // And so the same cost for any genome, through the registry's factory.
  std::unique_ptr<FitnessFunction> f;
  ASSERT_TRUE(Kinds().MakeFitness(NominalSpec(10, 1), &f).ok());
  const HgannFitness reference(direct);
  std::mt19937_64 rng(5);
  for (int i = 0; i < 20; ++i) {
    Genome g;
    for (int b = 0; b < model::kChromosomeBits; ++b) g.bits.push_back(rng() & 1);
    const FitnessResult a = f->Evaluate(g), b = reference.Evaluate(g);
    EXPECT_EQ(a.cost, b.cost);
    EXPECT_EQ(a.status, b.status);
  }
}

TEST(HgannJob, EveryBadFieldIsNamed) {
  JobSpec s = NominalSpec(10, 1);
  auto& h = std::get<HgannProblem>(s.problem);
  h.cases[3].angle_deg[17] = std::nan("");
  h.cases[1].voltage_v.pop_back();
  h.cases[2].role = CaseRole::kUnspecified;
  h.cases[4].number = h.cases[0].number;
  h.cases[5].frequency_hz = 0;
  h.cases[6].sample_rate_hz = -1;
  h.cases[7].b1 = 3;
  h.ranges_preset = "papier";
  h.ranges = {{"alfa", 0, 1}, {"beta", 1, 0}, {"gamma", 0, 1}, {"gamma", 0, 2}};
  h.spread_penalty = std::nan("");
  h.geometry = {{"tip_lenght_m", 1}, {"n_tip", 2.5}};
  h.case_set_dir = "data/x";
  h.source = std::string(2000, 'x');
  const auto v = Kinds().Validate(s);
  const std::string all = All(v);
  EXPECT_TRUE(HasField(v, "hgann.cases[3].angle_deg[17]",
                       "hgann.cases[3].angle_deg[17] = nan: must be finite"))
      << all;
  EXPECT_TRUE(
      HasField(v, "hgann.cases[1].voltage_v.size()", "must be 0 or the number of angle samples"))
      << all;
  EXPECT_TRUE(HasField(v, "hgann.cases[2].role", "must be CASE_ROLE_TRAIN")) << all;
  EXPECT_TRUE(HasField(v, "hgann.cases[4].number", "duplicates")) << all;
  EXPECT_TRUE(HasField(v, "hgann.cases[5].frequency_hz", "= 0: must be finite and > 0")) << all;
  EXPECT_TRUE(HasField(v, "hgann.cases[6].sample_rate_hz", "= -1")) << all;
  EXPECT_TRUE(HasField(v, "hgann.cases[7].b1", "only with saturation SATURATION_GIVEN")) << all;
  EXPECT_TRUE(HasField(v, "hgann.ranges_preset", "\"papier\"")) << all;
  EXPECT_TRUE(HasField(v, "hgann.ranges[0].name", "must be one of mu, delta, alpha")) << all;
  EXPECT_TRUE(HasField(v, "hgann.ranges[1].max", ">= min (1)")) << all;
  EXPECT_TRUE(HasField(v, "hgann.ranges[3].name", "given twice")) << all;
  EXPECT_TRUE(HasField(v, "hgann.spread_penalty")) << all;
  EXPECT_TRUE(HasField(v, "hgann.geometry.tip_lenght_m", "unknown field")) << all;
  EXPECT_TRUE(HasField(v, "hgann.case_set_dir", "a master never reads client paths")) << all;
  EXPECT_TRUE(HasField(v, "hgann.source")) << all;

  // Saturations given: both required, with their signs.
  s = NominalSpec(10, 1);
  auto& g = std::get<HgannProblem>(s.problem);
  g.saturation = HgannProblem::Saturation::kGiven;
  for (auto& c : g.cases) c.b1 = 1, c.b2 = -1;
  g.cases[0].b2.reset();
  g.cases[1].b1 = -2;
  g.geometry = {{"n_tip", 2.5}};
  auto w = Kinds().Validate(s);
  EXPECT_TRUE(HasField(w, "hgann.cases[0].b2", "required")) << All(w);
  EXPECT_TRUE(HasField(w, "hgann.cases[1].b1", "= -2: must be finite and > 0")) << All(w);
  EXPECT_TRUE(HasField(w, "hgann.geometry.n_tip", "whole number")) << All(w);

  // No training case; no case at all; a record that stays at 0 cannot give its saturations.
  s = NominalSpec(10, 1);
  for (auto& c : std::get<HgannProblem>(s.problem).cases) c.role = CaseRole::kValidate;
  EXPECT_TRUE(HasField(Kinds().Validate(s), "hgann.cases", "CASE_ROLE_TRAIN"));
  std::get<HgannProblem>(s.problem).cases.clear();
  EXPECT_TRUE(HasField(Kinds().Validate(s), "hgann.cases", "at least one case"));
  s = NominalSpec(10, 1);
  auto& z = std::get<HgannProblem>(s.problem).cases[0].angle_deg;
  std::fill(z.begin(), z.end(), 0.0);
  EXPECT_TRUE(HasField(Kinds().Validate(s), "hgann.cases[0].angle_deg", "never rises above 0"));

  // Geometry values are checked by the beam's own rules.
  s = NominalSpec(10, 1);
  std::get<HgannProblem>(s.problem).geometry = {{"core_width_m", -1}};
  EXPECT_TRUE(HasField(Kinds().Validate(s), "hgann.geometry.core_width_m"))
      << All(Kinds().Validate(s));
}

TEST(HgannJob, ExtremeButValidSpecsNeverCrashAnEvaluation) {
  // What a hostile or careless spec can put in front of a worker: each either fails validation
  // with a named field or evaluates every genome to a finite cost.
  std::mt19937_64 rng(9);
  std::vector<std::function<void(HgannProblem&)>> edits = {
      [](HgannProblem& h) { h.cases[0].sample_rate_hz = 1e-300; },
      [](HgannProblem& h) { h.cases[0].sample_rate_hz = 1e300; },
      [](HgannProblem& h) { h.cases[0].amplitude_v = 1e300; },
      [](HgannProblem& h) { h.cases[0].frequency_hz = 1e300; },
      [](HgannProblem& h) { h.cases[0].frequency_hz = 1e-300; },
      [](HgannProblem& h) {
        h.cases[0].angle_deg.assign(2, 1e300);
        h.cases[0].angle_deg[1] = -1e300;
        h.cases[0].voltage_v.clear();
      },
      [](HgannProblem& h) {
        h.ranges = {{"mu", -1e300, 1e300}, {"alpha", 1e300, 1e300}};
      },
      [](HgannProblem& h) {
        h.geometry = {{"core_modulus_pa", 1e-300}, {"n_active", 200}, {"n_tip", 200}};
      },
      [](HgannProblem& h) { h.spread_penalty = 1e300; },
  };
  int evaluated = 0;
  for (size_t e = 0; e < edits.size(); ++e) {
    JobSpec s = NominalSpec(10, 1);
    edits[e](std::get<HgannProblem>(s.problem));
    const auto v = Kinds().Validate(s);
    if (!v.empty()) {
      EXPECT_FALSE(v.front().field.empty()) << e;
      std::printf("edit %zu refused: %s\n", e, v.front().description.substr(0, 100).c_str());
      continue;
    }
    std::unique_ptr<FitnessFunction> f;
    if (Status st = Kinds().MakeFitness(s, &f); !st.ok()) {
      EXPECT_EQ(st.code(), StatusCode::kInvalidArgument) << e << ": " << st.message();
      std::printf("edit %zu: no fitness: %s\n", e, st.message().substr(0, 100).c_str());
      continue;
    }
    // The fitness itself (not the guard around it, which would hide a NaN or an exception) must
    // give a finite cost, a reason whenever it is not ok, and the same answer twice.
    for (int i = 0; i < 5; ++i) {
      Genome g;
      for (int b = 0; b < model::kChromosomeBits; ++b) g.bits.push_back(rng() & 1);
      FitnessResult r, again;
      EXPECT_NO_THROW(r = f->Evaluate(g)) << "edit " << e;
      EXPECT_NO_THROW(again = f->Evaluate(g)) << "edit " << e;
      EXPECT_TRUE(std::isfinite(r.cost)) << "edit " << e << ": cost " << r.cost << " " << r.reason;
      if (r.status != FitnessStatus::kOk) {
        EXPECT_FALSE(r.reason.empty()) << "edit " << e;
      }
      EXPECT_EQ(std::memcmp(&r.cost, &again.cost, sizeof r.cost), 0) << "edit " << e;
      EXPECT_EQ(r.status, again.status) << "edit " << e;
      FitnessResult sanitised = r;
      EXPECT_FALSE(SanitizeFitness(sanitised))
          << "edit " << e << ": the guard had to repair " << r.reason;
    }
    ++evaluated;
    std::printf("edit %zu evaluated\n", e);
  }
  EXPECT_GT(evaluated, 0) << "no edit reached an evaluation: the test would check nothing";
}

}  // namespace
}  // namespace pz::hgann
