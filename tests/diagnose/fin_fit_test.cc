// The global fit of the diagnosis (diagnose/problem.h, optimize.h, fit.h): parameter layout and its
// search coordinates, the optimisers on problems with known answers, determinism across evaluators,
// and a global fit that recovers the parameters of a synthetic, encoder-quantised bench.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "diagnose/fin_fit.h"
#include "opt/inline_evaluator.h"
#include "opt/thread_pool_evaluator.h"

namespace pz::diagnose {

using opt::LevenbergMarquardt;
using opt::LmOptions;
using opt::LmResult;
using opt::ResidualFunction;
namespace {

using model::EffectKind;

TEST(ParameterLayoutTest, UnitCoordinatesRoundTripAndKeepTheLoopBounded) {
  const ParameterLayout l({EffectKind::Named("creep"), EffectKind::Named("delay")});
  ASSERT_EQ(l.size(), 7 + 2 + 1);
  EXPECT_EQ(l.specs()[7].name, "creep.k_c");
  EXPECT_EQ(l.specs()[9].name, "delay.tau_d_s");
  const std::vector<double> u = {0.2, 0.1, 0.125, 0.5, 0.7, 0.1, 0.15, 0.3, 0.4, 0.05};
  const std::vector<double> x = l.FromUnit(u);
  EXPECT_NEAR(x[4], x[3] * (-0.98 + 0.7 * 1.98), 1e-15);  // γ = g β
  const std::vector<double> back = l.ToUnit(x);
  for (size_t i = 0; i < u.size(); ++i) EXPECT_NEAR(back[i], u[i], 1e-12) << i;
  // Every corner of the box is a bounded loop.
  for (double g : {0.0, 1.0})
    for (double b : {0.0, 1.0}) {
      std::vector<double> c = u;
      c[3] = b;
      c[4] = g;
      const std::vector<double> xc = l.FromUnit(c);
      model::BimorphParams p;
      std::vector<model::Effect> e;
      l.Decode(xc, &p, &e);
      EXPECT_TRUE(p.HysteresisBounded());
      ASSERT_EQ(e.size(), 2u);
      EXPECT_EQ(e[1].params[0], xc[9]);
    }
}

TEST(ParameterLayoutTest, UnitJacobianMatchesFiniteDifferences) {
  const ParameterLayout l({EffectKind::Named("hinge-friction")});
  const std::vector<double> u = {0.2, 0.1, 0.125, 0.5, 0.7, 0.1, 0.15, 0.3, 0.4};
  const std::vector<double> t = l.UnitJacobian(u);
  const int n = l.size();
  for (int j = 0; j < n; ++j) {
    std::vector<double> up = u, dn = u;
    up[j] += 1e-6;
    dn[j] -= 1e-6;
    const std::vector<double> xp = l.FromUnit(up), xm = l.FromUnit(dn);
    for (int i = 0; i < n; ++i) {
      const double fd = (xp[i] - xm[i]) / 2e-6;
      EXPECT_NEAR(t[static_cast<size_t>(j) * n + i], fd, 1e-6 * (std::abs(fd) + 1e-3))
          << i << "," << j;
    }
  }
}

TEST(ParameterLayoutTest, ExtendKeepsTheBaseAndStartsNewEffectsAtTheIdentity) {
  const ParameterLayout base({});
  const ParameterLayout ext({EffectKind::Named("driver-lowpass"), EffectKind::Named("creep")});
  const std::vector<double> xb = {95, 0.1, 2.5e-3, 6e-3, 4e-3, 0.1, 0.15};
  const std::vector<double> x = ext.Extend(xb, base);
  for (int i = 0; i < 7; ++i) EXPECT_EQ(x[i], xb[i]);
  EXPECT_EQ(x[7], 0.0);  // low-pass τ
  EXPECT_EQ(x[8], 0.0);  // creep gain
  model::BimorphParams p;
  std::vector<model::Effect> e;
  ext.Decode(x, &p, &e);
  for (const auto& ef : e) EXPECT_TRUE(ef.IsIdentity());
}

// Σ (x_i − c_i)² as a fitness over Genome.reals.
class Sphere final : public opt::FitnessFunction {
 public:
  opt::FitnessResult Evaluate(const opt::Genome& g) const override {
    double s = 0;
    for (size_t i = 0; i < g.reals.size(); ++i)
      s += (g.reals[i] - 0.3 - 0.1 * i) * (g.reals[i] - 0.3 - 0.1 * i);
    return {s, opt::FitnessStatus::kOk, ""};
  }
};

TEST(OptimizeTest, LevenbergMarquardtFitsAnExponentialAndRespectsBounds) {
  // r_k = 2 e^{−0.7 t_k} − a e^{−b t_k}: minimum at (2, 0.7); with b ≤ 0.5 the bound is active.
  ResidualFunction f = [](std::span<const double> x, std::vector<double>& r) {
    r.resize(20);
    for (int k = 0; k < 20; ++k) {
      const double t = 0.2 * k;
      r[k] = 2 * std::exp(-0.7 * t) - x[0] * std::exp(-x[1] * t);
    }
    return true;
  };
  LmOptions o;
  o.fd_step = 1e-6;
  const LmResult r =
      LevenbergMarquardt(f, {1.0, 0.1}, std::vector<double>{0, 0}, std::vector<double>{5, 5}, o);
  EXPECT_NEAR(r.x[0], 2.0, 1e-6);
  EXPECT_NEAR(r.x[1], 0.7, 1e-6);
  EXPECT_TRUE(r.converged) << r.message;
  const LmResult c =
      LevenbergMarquardt(f, {1.0, 0.1}, std::vector<double>{0, 0}, std::vector<double>{5, 0.5}, o);
  EXPECT_DOUBLE_EQ(c.x[1], 0.5);
  EXPECT_GT(c.cost, r.cost);
}

TEST(FitTest, GlobalFitRecoversTheParametersOfAQuantisedSyntheticBench) {
  // Four cases made by the plant itself (no saturation: the whole loop is seen), read through the
  // bench's encoder (no jitter); the last one is withheld.
  auto plant = std::make_shared<const model::BimorphPlant>();
  const model::EffectSimulator sim(*plant);
  const double q = 360.0 / 8192;
  model::BimorphParams truth;  // μ 95, δ 0.1, α 2.5e-3, β 6e-3, γ 4e-3, a1 0.1, a2 0.15
  truth.b1 = 20;
  truth.b2 = -20;
  std::vector<DiagCase> cases;
  const double vf[4][2] = {{375, 0.25}, {500, 0.5}, {750, 1.0}, {500, 1.0}};
  for (int c = 0; c < 4; ++c) {
    const model::Sinusoid d{vf[c][0], vf[c][1]};
    std::vector<double> y(d.NumSamples());
    ASSERT_TRUE(sim.SimulateAngle(truth, {}, d, y).ok());
    for (double& v : y) v = q * std::round(v / q);
    cases.push_back(MakeCase(c + 1, d, y, c < 3));
  }
  const DiagnosisModel m(plant, cases);
  const ParameterLayout layout({});
  FitOptions o;
  o.de.population = 24;
  o.de.generations = 60;
  o.lm.max_iterations = 30;
  const FitResult fit = FitGlobal(m, layout, o);
  ASSERT_TRUE(fit.ok) << fit.message;
  EXPECT_LT(std::sqrt(fit.train_pi / fit.train_samples), q / std::sqrt(12.0) * 1.2);
  EXPECT_NEAR(fit.x[2], truth.alpha, 0.1 * truth.alpha);     // α
  EXPECT_NEAR(fit.x[5], truth.a1, 0.02);                     // a1 [deg]
  EXPECT_NEAR(fit.x[1] + fit.x[0] / 1.35e5, 0.1007, 0.005);  // the slow time constant δ + μ/ω₁²
  ASSERT_EQ(fit.params.size(), 7u);
  for (const ParamEstimate& p : fit.params) EXPECT_GT(p.std_error, 0) << p.name;
  // μ and δ act together on the slow pole: the table says so.
  EXPECT_NE(fit.params[0].note.find("delta"), std::string::npos) << fit.params[0].note;
}

TEST(FitTest, BetaAndGammaHaveNoEffectWhenAlphaIsZero) {
  auto plant = std::make_shared<const model::BimorphPlant>();
  const model::Sinusoid d{500, 1.0};
  std::vector<double> y(d.NumSamples(), 0.0);
  for (size_t k = 0; k < y.size(); ++k) y[k] = std::sin(2 * M_PI * k / 100.0);
  const DiagnosisModel m(plant, {MakeCase(1, d, y, true), MakeCase(2, d, y, false)});
  const ParameterLayout layout({});
  FitResult fit;
  fit.x = {95, 0.1, 0.0, 6e-3, 4e-3, 0.1, 0.15};
  ComputeUncertainty(m, layout, fit, 1);
  ASSERT_EQ(fit.params.size(), 7u);
  EXPECT_EQ(fit.params[3].identifiability, Identifiability::kNoEffect);
  EXPECT_EQ(fit.params[4].identifiability, Identifiability::kNoEffect);
  EXPECT_NE(fit.params[3].note.find("alpha = 0"), std::string::npos);
  EXPECT_NE(fit.params[2].identifiability, Identifiability::kNoEffect);
}

}  // namespace
}  // namespace pz::diagnose
