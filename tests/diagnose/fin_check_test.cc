// The diagnosis on data whose effect is withheld from it (a small diagnose-check): synthetic
// benches are deterministic and read like the encoder; a withheld delay is named and its gap
// closed, a clean bench gets "no significant gap"; the check tallies its confusion matrix; and on
// the bundled driver-lowpass bench the right effect is named, with a time constant that matches the
// bench's truth.json (read only here, after the diagnosis, to check its answer).
#include <gtest/gtest.h>

#include "tests/testing/expect_error.h"

#include <cmath>
#include <fstream>
#include <memory>
#include <numbers>
#include <regex>
#include <sstream>

#include "diagnose/fin_check.h"
#include "io/bench_data.h"

namespace pz::diagnose {
namespace {

using model::EffectKind;

// A small search (the CLI's --quick) on the fast candidates only: seconds per diagnosis.
DiagnoseOptions Quick(std::vector<EffectKind> candidates) {
  DiagnoseOptions o;
  o.candidates = std::move(candidates);
  o.de_base.population = 24;
  o.de_base.generations = 40;
  o.de_candidate.population = 24;
  o.de_candidate.generations = 30;
  o.lm.max_iterations = 20;
  o.second_effect = false;
  o.trends = false;
  return o;
}

TEST(SyntheticTest, BenchesAreDeterministicAndReadThroughTheEncoder) {
  const model::BimorphPlant plant;
  SyntheticOptions so;
  const SyntheticTrial a = MakeSyntheticTrial(plant, 11, so), b = MakeSyntheticTrial(plant, 11, so);
  ASSERT_EQ(a.cases.size(), 9u);
  int training = 0;
  for (size_t c = 0; c < 9; ++c) {
    EXPECT_EQ(a.cases[c].measured_deg, b.cases[c].measured_deg);
    training += a.cases[c].training;
    for (double y : a.cases[c].measured_deg) {
      const double r = y / so.quantum_deg;
      ASSERT_NEAR(r, std::round(r), 1e-9);
    }
  }
  EXPECT_EQ(training, 4);  // the paper's split
  EXPECT_EQ(a.Describe(), b.Describe());
  so.none_probability = 1.0;
  const SyntheticTrial clean = MakeSyntheticTrial(plant, 12, so);
  EXPECT_EQ(clean.truth, EffectKind());
  EXPECT_TRUE(clean.effects.empty());
}

// Seed 14 draws a cubic stiffening whose case 9 (750 V, 1 Hz) stopped CVODE's BDF at order 5 with
// repeated error-test failures at t = 2.33 s (h = 2e-8 s): the check stopped there with an error.
// IntegrateCvode retries such a run at order ≤ 2 (model/cvode.h); the bench is then simulated, and
// every reading is finite and on the encoder's grid.
TEST(SyntheticTest, AStiffeningTheHighOrderBdfCannotPassIsSimulated) {
  const model::BimorphPlant plant;
  const SyntheticOptions so;
  const SyntheticTrial t = MakeSyntheticTrial(plant, 14, so);
  EXPECT_EQ(t.truth.name(), std::string("cubic-stiffening"));
  ASSERT_EQ(t.cases.size(), 9u);
  for (const DiagCase& c : t.cases)
    for (double y : c.measured_deg) {
      ASSERT_TRUE(std::isfinite(y));
      ASSERT_NEAR(y / so.quantum_deg, std::round(y / so.quantum_deg), 1e-9);
    }
}

TEST(CheckTest, WithheldDelayIsNamedAndACleanBenchIsNot) {
  auto plant = std::make_shared<const model::BimorphPlant>();
  const DiagnoseOptions o = Quick({EffectKind::Named("driver-lowpass"), EffectKind::Named("delay"),
                                   EffectKind::Named("drift")});
  SyntheticOptions so;
  model::BimorphParams p;  // the physical bench's values
  std::vector<std::pair<double, double>> sat;
  for (double v : {375.0, 500.0, 750.0})
    for (double f : {0.25, 0.5, 1.0})
      sat.push_back({0.0065 * v - 0.85 * f - 0.63, -0.0062 * v + 0.68 * f + 0.71});
  CheckSummary summary;
  for (const bool with_delay : {true, false}) {
    opt::Rng rng(with_delay ? 1 : 2);
    std::vector<model::Effect> effects;
    if (with_delay) effects = {{EffectKind::Named("delay"), {0.02}}};
    const DiagnosisModel m(plant, SimulateBench(*plant, p, effects, sat, so, rng));
    const records::RecordDiagnosis d = DiagnoseBench(m, o).records;
    CheckTrial t;
    t.truth = with_delay ? EffectKind::Named("delay") : EffectKind();
    t.verdict_kind = d.verdict_kind;
    t.named = d.named_effects.empty() ? EffectKind() : d.named_effects.front();
    t.significant = d.significant;
    t.closed = d.closed_total;
    Tally(summary, t);
    if (with_delay) {
      // On phase-zero sines a delay and a driver low-pass explain the grid equally: the verdict
      // says so (issue 14) rather than claiming certainty, and still names the better one.
      EXPECT_TRUE(d.verdict_kind == "effect" || d.verdict_kind == "inseparable") << d.verdict;
      if (d.verdict_kind == "inseparable") {
        PZ_EXPECT_HAS(d.verdict, "cannot separate");
        EXPECT_LT(d.confidence, 0.9) << d.verdict;
      }
      ASSERT_FALSE(d.named_effects.empty());
      EXPECT_EQ(d.named_effects.front(), EffectKind::Named("delay")) << d.verdict;
      EXPECT_GE(d.closed_total, 0.7) << d.verdict;
      if (d.verdict_kind == "effect") {
        EXPECT_GT(d.confidence, 0.5);  // the named effect carries most of the weight
      }
      const auto& params = d.final_fit->uncertainty.params;
      ASSERT_EQ(params.size(), 8u);
      EXPECT_NEAR(params[7].value, 0.02, 3 * params[7].std_error + 1e-3);
    } else {
      EXPECT_EQ(d.verdict_kind, "none") << d.verdict;
      EXPECT_LT(d.rms_ratio, o.rules.significance_ratio);
    }
  }
  EXPECT_EQ(summary.confusion[model::FinIndex(EffectKind::Named("delay"))]
                             [model::FinIndex(EffectKind::Named("delay"))],
            1);
  EXPECT_EQ(summary.confusion[0][0], 1);
  EXPECT_EQ(summary.accuracy(), 1.0);
  EXPECT_EQ(summary.false_alarm_rate(), 0.0);
  EXPECT_EQ(summary.closed.size(), 1u);
}

TEST(CheckTest, RunCheckTalliesEveryTrial) {
  SyntheticOptions so;
  so.kinds = {EffectKind::Named("drift")};
  so.none_probability = 0.0;
  int seen = 0;
  const CheckSummary s =
      RunCheck(1, 3, Quick({EffectKind::Named("drift"), EffectKind::Named("delay")}), so,
               [&](const CheckTrial& t, int) {
                 ++seen;
                 EXPECT_EQ(t.truth, EffectKind::Named("drift"));
               });
  EXPECT_EQ(seen, 1);
  ASSERT_EQ(s.trials.size(), 1u);
  int total = 0;
  for (const auto& row : s.confusion)
    for (int n : row) total += n;
  EXPECT_EQ(total, 1);
  const CheckTrial& t = s.trials[0];
  EXPECT_TRUE(t.verdict_kind == "effect" || t.verdict_kind == "inseparable" ||
              t.verdict_kind == "none" || t.verdict_kind == "unexplained");
  if (t.significant) {
    EXPECT_TRUE(t.correct()) << t.truth_description << " -> " << t.verdict_kind;
  }
}

TEST(CheckTest, BundledDriverLowpassBenchIsNamedWithTheTimeConstantOfItsTruth) {
  const std::string dir = std::string(PIEZOID_DATA_DIR) + "/bimorph-fin/driver-lowpass";
  auto plant = std::make_shared<const model::BimorphPlant>();
  const DiagnosisModel m(plant, CasesFromCaseSet(io::LoadCaseSet(dir)));
  const records::RecordDiagnosis d =
      DiagnoseBench(m, Quick({EffectKind::Named("driver-lowpass"), EffectKind::Named("delay"),
                              EffectKind::Named("creep")}))
          .records;
  // The grid's phase-zero sines cannot tell a low-pass from a delay (issue 14): the verdict says
  // so.
  ASSERT_TRUE(d.verdict_kind == "effect" || d.verdict_kind == "inseparable") << d.verdict;
  if (d.verdict_kind == "inseparable") {
    PZ_EXPECT_HAS(d.verdict, "The data cannot separate driver-lowpass from");
  }
  ASSERT_FALSE(d.named_effects.empty()) << d.verdict;
  EXPECT_EQ(d.named_effects.front(), EffectKind::Named("driver-lowpass")) << d.verdict;
  EXPECT_GE(d.closed_total, 0.7);
  // Only now, to check the answer: the bench's low-pass corner frequency.
  std::ifstream in(dir + "/truth.json");
  std::stringstream ss;
  ss << in.rdbuf();
  std::smatch mt;
  const std::string text = ss.str();
  ASSERT_TRUE(std::regex_search(text, mt,
                                std::regex("\"lpf\"\\s*:\\s*\\{\\s*\"fc\"\\s*:\\s*([0-9.eE+-]+)")));
  const double tau_truth = 1.0 / (2 * std::numbers::pi * std::stod(mt[1]));
  EXPECT_NEAR(d.final_fit->uncertainty.params[7].value, tau_truth, 0.1 * tau_truth);
}

}  // namespace
}  // namespace pz::diagnose
