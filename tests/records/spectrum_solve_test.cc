// The creep spectrum solved with a linear family's weights (records/spectrum_solve.h): the
// Gauss–Newton iteration never increases the objective, both starts (w = 0, log creep) reach the
// same optimum, no feasible move of the weights lowers the error (the joint least-squares optimum,
// checked against the family's own solve at perturbed weights), and a fit searches only the
// other parameters (a delay), the same bit for bit on one thread or two, its residuals the same
// from the searched parameters or from all of them.
#include "records/spectrum_solve.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <numbers>

#include "records/fit.h"
#include "records/registry.h"
#include "synth/reallike.h"

namespace pz::records {
namespace {

/// 6 s of a stack with log creep of 3 % per decade from 0.05 to 6 s, trained on a sine whose
/// amplitude swings (minor loops and creep both excited), a one-sample sensor lag.
synth::RealLikeSet Stack() {
  synth::RealLikeOptions o;
  o.train_s = 6;
  o.withheld_s = 4;
  o.sensor.oversample = 2;
  o.sensor.lag_samples = 1;
  o.stack.everett_grid = 80;
  o.stack.creep_per_decade = 0.03;
  o.stack.creep_tau_max_s = 6;
  o.second_sine = false;
  o.reversals = false;
  o.seed = 5;
  const double fs = o.sensor.fs_hz, rest_s = 1;
  for (size_t k = 0; k < static_cast<size_t>((rest_s + o.train_s) * fs); ++k) {
    const double t = static_cast<double>(k) / fs - rest_s;
    const double a = 70 * (0.55 + 0.45 * std::cos(2 * std::numbers::pi * t / 3));
    o.train_drive.push_back(t < 0 ? 0.0 : 75 - a * std::cos(2 * std::numbers::pi * 0.8 * t));
  }
  return synth::GenerateRealLikeSet(o);
}

struct Plant {
  synth::RealLikeSet s = Stack();
  std::vector<const io::Record*> train = s.set.WithRole(model::CaseRole::kTrain);
  std::shared_ptr<RecordModel> model;
  explicit Plant(const std::string& family) {
    const DataScale scale = MeasureScale(train);
    model = std::make_shared<RecordModel>(
        MakeFamily(family, scale, {}),
        std::vector<EffectKind>{EffectKind::Named("creep-spectrum"), EffectKind::Named("delay")},
        scale);
  }
};

opt::Genome Genome(std::vector<double> x) {
  opt::Genome g;
  g.reals = std::move(x);
  return g;
}

TEST(SpectrumSolveTest, ConvergesMonotonicallyToTheJointOptimum) {
  Plant su("prandtl-ishlinskii");  // no regularisation: the profiled error is Evaluate's
  const RecordFitness fitness(*su.model, su.train);
  ASSERT_TRUE(fitness.spectrum_solved());
  const auto [first, count] = su.model->EffectParams(EffectKind::Named("creep-spectrum"));
  ASSERT_GE(count, 4u);
  const auto [delay, one] = su.model->EffectParams(EffectKind::Named("delay"));
  ASSERT_EQ(one, 1u);
  ASSERT_EQ(fitness.searched(), std::vector<size_t>{delay});
  std::vector<double> p(su.model->params().size(), 0.0);
  p[delay] = 0.4 * su.train[0]->dt;  // a fractional-sample lag
  const Eigen::MatrixXd D = SpectrumRoughness(count);
  SpectrumProblem sp;
  sp.model = su.model.get();
  sp.records = su.train;
  sp.samples = fitness.samples();
  sp.first = first;
  sp.count = count;
  sp.roughness = &D;
  SpectrumSolution both[2];
  for (int start = 0; start < 2; ++start) {
    sp.zero_start = start == 0;  // each start alone
    sp.log_creep_start = start == 0 ? 0 : 0.01;
    SpectrumSolution& s = both[start];
    s = SolveSpectrum(sp, p);
    EXPECT_EQ(s.start, start);
    std::cout << "start " << start << ": " << s.iterations << " steps, " << s.grams
              << " normal equations, objective";
    for (double f : s.objectives) std::cout << " " << std::setprecision(15) << f;
    std::cout << "\n";
    ASSERT_TRUE(s.ok);
    ASSERT_GE(s.objectives.size(), 2u);
    for (size_t i = 1; i < s.objectives.size(); ++i)
      EXPECT_LT(s.objectives[i], s.objectives[i - 1]) << i;
    EXPECT_EQ(s.objective, s.objectives.back());
    EXPECT_LE(s.iterations, 20);
    for (double w : s.w) {
      EXPECT_GE(w, 0);
      EXPECT_LE(w, su.model->params()[first].upper);
    }
  }
  // Both starts at the same optimum; the creep found (log creep of 3 % per decade: ~1.5 % per
  // weight).
  EXPECT_NEAR(both[0].objective, both[1].objective, 1e-9 * both[0].objective);
  double sum = 0;
  for (size_t i = 0; i < count; ++i) {
    EXPECT_NEAR(both[0].w[i], both[1].w[i], 1e-5) << i;
    sum += both[0].w[i];
  }
  EXPECT_GT(sum, 0.02);
  // The objective is the family's own error at those weights (θ re-solved by its NNLS).
  std::vector<double> q = p;
  for (size_t i = 0; i < count; ++i) q[first + i] = both[0].w[i];
  const double n = static_cast<double>(fitness.samples());
  const double at = fitness.Evaluate(Genome(q)).cost;
  EXPECT_NEAR(at * n, both[0].sse, 1e-9 * both[0].sse);
  // No feasible move of one weight, or of all together, lowers it (the family's weights re-solved).
  for (size_t i = 0; i <= count; ++i) {
    for (double step : {-1e-3, 1e-3, -1e-5, 1e-5}) {
      std::vector<double> r = q;
      for (size_t j = 0; j < count; ++j)
        if (j == i || i == count)
          r[first + j] = std::clamp(q[first + j] + step, 0.0, su.model->params()[first + j].upper);
      if (r == q) continue;
      EXPECT_GE(fitness.Evaluate(Genome(r)).cost, at * (1 - 1e-12)) << i << " " << step;
    }
  }
  // Evaluate and Residuals from the searched parameters: the same as from every parameter.
  const opt::FitnessResult searched = fitness.Evaluate(Genome({p[delay]}));
  EXPECT_NEAR(searched.cost, at, 1e-9 * at);
  std::vector<double> ra, rb;
  ASSERT_TRUE(fitness.Residuals(std::vector<double>{p[delay]}, ra));
  ASSERT_TRUE(fitness.Residuals(fitness.Expand(std::vector<double>{p[delay]}), rb));
  EXPECT_EQ(ra, rb);
}

TEST(SpectrumSolveTest, AFitSearchesTheDelayOnlyTheSameOnAnyThreadCount) {
  Plant su("preisach");
  FitOptions f;
  f.family = "preisach";
  f.effects = {EffectKind::Named("creep-spectrum"), EffectKind::Named("delay")};
  f.sizing.enabled = true;
  f.polish_repetitions = true;
  f.threads = 1;
  const FitResult one = FitModel(su.s.set, su.model, f);
  f.threads = 2;
  const FitResult two = FitModel(su.s.set, su.model, f);
  EXPECT_EQ(one.searched_parameters, 1u);
  EXPECT_TRUE(one.spectrum_solved);
  EXPECT_EQ(one.solved_parameters,
            su.model->EffectParams(EffectKind::Named("creep-spectrum")).second);
  EXPECT_EQ(one.algorithm, opt::SearchAlgorithm::kLine);  // the delay alone: the line search
  EXPECT_LE(one.evaluations, 300);
  EXPECT_EQ(one.search.evaluations, two.search.evaluations);
  EXPECT_EQ(one.search.trace.best_cost, two.search.trace.best_cost);
  EXPECT_EQ(one.params, two.params);
  EXPECT_EQ(one.weights, two.weights);
  EXPECT_EQ(one.train_mse, two.train_mse);
  // The table covers every parameter (the spectrum's weights too) and the penalty's validation ran.
  EXPECT_EQ(one.uncertainty.params.size(), su.model->params().size());
  EXPECT_TRUE(one.spectrum_regularisation.used);
  EXPECT_EQ(one.spectrum_sigma.size(),
            su.model->EffectParams(EffectKind::Named("creep-spectrum")).second);
  // At the training floor (the family matches the plant: Preisach + creep + lag).
  const double floor = su.s.truth[0].noise_rms_um;
  EXPECT_LE(one.metrics[0].rmse, 1.15 * floor);
}

}  // namespace
}  // namespace pz::records
