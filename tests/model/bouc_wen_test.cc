// Bouc–Wen hysteresis (exponent 1): the closed form against a fine numerical integration, the
// boundedness rule of the spec checked numerically, and what model::Simulate does with the paper's
// Table 3 ranges (α, β, γ ∈ [−0.1, 0]) and with α = 0.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "model/bimorph.h"
#include "model/bouc_wen.h"
#include "model/modal_simulator.h"
#include "tests/testing/expect_error.h"

namespace pz::model {
namespace {

// RK4 with 2000 sub-steps per sample: its error (second order at the kinks of |z|) is below this
// [N].
constexpr double kRk4Tol = 1e-8;

const BimorphPlant& DefaultPlant() {
  static const BimorphPlant plant;
  return plant;
}

// ż = α u̇ − β |u̇| z − γ u̇ |z| by classical RK4 on a fine grid, u = V sin(2π f t); z at t_k =
// k/fs.
std::vector<double> IntegrateRk4(const BoucWenParams& p, const Sinusoid& s, int substeps) {
  const double w = 2 * std::numbers::pi * s.frequency_hz;
  auto rhs = [&](double t, double z) {
    const double ud = s.amplitude_v * w * std::cos(w * t);
    return p.alpha * ud - p.beta * std::abs(ud) * z - p.gamma * ud * std::abs(z);
  };
  const int n = s.NumSamples();
  const double h = 1.0 / (s.sample_rate_hz * substeps);
  std::vector<double> z(n, 0.0);
  double zc = 0;
  for (int k = 1; k < n; ++k) {
    for (int q = 0; q < substeps; ++q) {
      const double t = ((k - 1) * substeps + q) * h;
      const double k1 = rhs(t, zc), k2 = rhs(t + h / 2, zc + h / 2 * k1),
                   k3 = rhs(t + h / 2, zc + h / 2 * k2), k4 = rhs(t + h, zc + h * k3);
      zc += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    z[k] = zc;
  }
  return z;
}

TEST(BoucWenClosedForm, MatchesFineRk4IntegrationOnBothDrivePaths) {
  struct Case {
    BoucWenParams bw;
    Sinusoid drive;
  };
  const Case cases[] = {
      {{2.5e-3, 6e-3, 4e-3}, {375, 0.25, 3, 100}},     // the paper's stable loop
      {{2.5e-3, 6e-3, 4e-3}, {750, 1.0, 3, 100}},      // fast: κ u̇ h up to 0.47
      {{3.7e-3, 1.8e-2, 2.6e-3}, {750, 0.5, 3, 100}},  // random3: sharp loop, sub-stepped
      {{1e-3, 2e-3, -1.5e-3}, {500, 0.5, 3, 100}},  // γ < 0 (still bounded: β + γ > 0, β − γ ≥ 0)
      {{-2e-3, 5e-3, 5e-3}, {500, 1.0, 3, 100}},  // α < 0, β = γ (κ = 0 on two branches)
  };
  for (const Case& c : cases) {
    const std::vector<double> ref = IntegrateRk4(c.bw, c.drive, 2000);
    BimorphParams p;
    p.alpha = c.bw.alpha;
    p.beta = c.bw.beta;
    p.gamma = c.bw.gamma;
    ASSERT_TRUE(p.HysteresisBounded());
    // Sinusoid path (branches in time, crossings located by asin).
    const BimorphTrace tr = Simulate(DefaultPlant(), p, c.drive);
    ASSERT_TRUE(tr.summary.ok()) << tr.summary.BriefReport();
    // Path function on the samples: z depends on u alone along each monotone stretch, and the
    // polyline through the samples has the sinusoid's extremes (they fall on the 100 Hz grid here),
    // so z agrees at every sample.
    std::vector<double> zpath(ref.size());
    ASSERT_TRUE(BoucWenAlongPath(c.bw, SampleValues(c.drive), zpath));
    double worst = 0, worst_path = 0;
    for (size_t k = 0; k < ref.size(); ++k) {
      worst = std::max(worst, std::abs(tr.z[k] - ref[k]));
      worst_path = std::max(worst_path, std::abs(zpath[k] - ref[k]));
    }
    EXPECT_LT(worst, kRk4Tol) << "alpha " << c.bw.alpha << " beta " << c.bw.beta << " gamma "
                              << c.bw.gamma;
    EXPECT_LT(worst_path, kRk4Tol)
        << "alpha " << c.bw.alpha << " beta " << c.bw.beta << " gamma " << c.bw.gamma;
  }
}

// The same loop through a sampled drive (linear between samples) against RK4 on that polyline.
TEST(BoucWenClosedForm, SampledDriveMatchesRk4OnThePolyline) {
  BimorphParams p;
  SampledSignal s;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> step(-180.0, 180.0);
  double u = 0;
  for (int k = 0; k < 200; ++k) {
    s.t.push_back(0.01 * k);
    s.u.push_back(u);
    u = std::clamp(u + step(rng), -700.0, 700.0);
  }
  const BimorphTrace tr = Simulate(DefaultPlant(), p, s);
  ASSERT_TRUE(tr.summary.ok()) << tr.summary.BriefReport();
  double z = 0, worst = 0;
  for (size_t k = 0; k + 1 < s.t.size(); ++k) {
    const double ud = (s.u[k + 1] - s.u[k]) / (s.t[k + 1] - s.t[k]);
    auto f = [&](double zz) {
      return p.alpha * ud - p.beta * std::abs(ud) * zz - p.gamma * ud * std::abs(zz);
    };
    const int n = 4000;
    const double h = (s.t[k + 1] - s.t[k]) / n;
    for (int q = 0; q < n; ++q) {
      const double k1 = f(z), k2 = f(z + h / 2 * k1), k3 = f(z + h / 2 * k2), k4 = f(z + h * k3);
      z += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    worst = std::max(worst, std::abs(tr.z[k + 1] - z));
  }
  EXPECT_LT(worst, kRk4Tol);
}

// Numerical boundedness: the exact z along triangle waves of growing amplitude 1e2 … 1e6 V. A
// bounded loop saturates in the first half (amplitudes ≤ 1e4 V, where κ·A ≥ 10) and grows no
// further; an unbounded one grows by orders of magnitude or overflows.
bool NumericallyBounded(const BoucWenParams& p) {
  std::vector<double> u{0.0};
  for (int k = 0; k <= 16; ++k) {
    const double a = 100.0 * std::pow(10.0, k / 4.0);
    u.push_back(a);
    u.push_back(-a);
  }
  std::vector<double> z(u.size());
  if (!BoucWenAlongPath(p, u, z)) return false;
  double first = 0, second = 0;  // max |z| over amplitudes ≤ 1e4 V (19 points) and beyond
  for (size_t i = 0; i < z.size(); ++i) {
    double& m = i < 19 ? first : second;
    m = std::max(m, std::abs(z[i]));
  }
  return second <= 1.01 * first;
}

// The model is symmetric under (α, γ, z) → (−α, −γ, −z), so for α < 0 the rule reads with −γ; the
// spec's predicate (β + γ > 0, β − γ ≥ 0) is symmetric in the interior and differs only on the
// boundary lines, which the sampling avoids.
TEST(BoucWenBoundedness, NumericalCheckAgreesWithThePredicate) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> coef(-0.02, 0.02);
  int bounded_seen = 0, unbounded_seen = 0, class2_seen = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const double beta = coef(rng), gamma = coef(rng);
    // Stay clear of the boundaries, where "bounded" needs amplitudes beyond any finite test.
    if (std::abs(beta + gamma) < 1e-3 || std::abs(beta - gamma) < 1e-3 || std::abs(beta) < 1e-3)
      continue;
    for (double alpha : {2.5e-3, -1e-3}) {
      BimorphParams p;
      p.alpha = alpha;
      p.beta = beta;
      p.gamma = gamma;
      const double gamma_eff = alpha > 0 ? gamma : -gamma;
      const bool numerically = NumericallyBounded({alpha, beta, gamma});
      if (p.HysteresisBounded()) {
        // Class I: bounded for every input, by |α|/(β+γ) from rest.
        EXPECT_TRUE(numerically) << "alpha " << alpha << " beta " << beta << " gamma " << gamma;
        ++bounded_seen;
      } else if (beta > 0 && beta + gamma_eff > 0) {
        // β ≥ 0 > β − γ (Ikhouane & Rodellar's class II): from z(0) = 0 the loop stays within
        // |α|/(β+γ) too, but it is not dissipative and the spec (§2) rejects it with class I's
        // rule.
        EXPECT_TRUE(numerically) << "class II: alpha " << alpha << " beta " << beta << " gamma "
                                 << gamma;
        ++class2_seen;
      } else {
        EXPECT_FALSE(numerically) << "alpha " << alpha << " beta " << beta << " gamma " << gamma;
        ++unbounded_seen;
      }
    }
  }
  EXPECT_GT(bounded_seen, 40);
  EXPECT_GT(unbounded_seen, 100);
  EXPECT_GT(class2_seen, 20);
}

TEST(BoucWenBoundedness, ClassOneLoopNeverExceedsAlphaOverBetaPlusGamma) {
  const BoucWenParams p{2.5e-3, 6e-3, 4e-3};
  std::vector<double> u{0.0};
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> target(-2000.0, 2000.0);
  for (int k = 0; k < 2000; ++k) u.push_back(target(rng));
  std::vector<double> z(u.size());
  ASSERT_TRUE(BoucWenAlongPath(p, u, z));
  for (double zz : z) EXPECT_LE(std::abs(zz), p.alpha / (p.beta + p.gamma) * (1 + 1e-12));
}

// Paper Table 3: α, β, γ ∈ [−0.1, 0]. Any α ≠ 0 there makes the loop unbounded: Simulate says so
// (both paths, and the GA's entry point), fast, finite, without NaN.
TEST(BoucWenSimulate, PaperTable3RangesWithNonzeroAlphaAreUnbounded) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> r(-0.1, 0.0);
  const ModalSimulator sim(DefaultPlant());
  const Sinusoid drive{500, 0.5, 3, 100};
  std::vector<double> y(drive.NumSamples());
  for (int trial = 0; trial < 50; ++trial) {
    BimorphParams p;
    p.alpha = std::min(r(rng), -1e-6);
    p.beta = r(rng);
    p.gamma = r(rng);
    EXPECT_FALSE(p.HysteresisBounded());
    for (Solver solver : {Solver::kModal, Solver::kCvode}) {
      SimulateOptions o;
      o.solver = solver;
      const BimorphTrace tr = Simulate(DefaultPlant(), p, drive, o);
      EXPECT_EQ(tr.summary.status, SimStatus::kUnboundedHysteresis) << SolverName(solver);
      PZ_EXPECT_HAS(tr.summary.message, "alpha");
      for (const auto* v : {&tr.t, &tr.u, &tr.z, &tr.w_tip, &tr.theta_deg, &tr.angle_deg})
        for (double x : *v) EXPECT_TRUE(std::isfinite(x));
    }
    const SimulationSummary s = sim.SimulateAngle(p, drive, y);
    EXPECT_EQ(s.status, SimStatus::kUnboundedHysteresis);
  }
}

// α = 0 with z(0) = 0 gives z ≡ 0 whatever β and γ (paper's identified α = 0): the fin angle is
// then that of the linear beam alone.
TEST(BoucWenSimulate, ZeroAlphaGivesZeroHysteresis) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> r(-0.1, 0.0);
  const Sinusoid drive{750, 0.25, 3, 100};
  BimorphParams ref;
  ref.alpha = 0;
  ref.beta = 0;
  ref.gamma = 0;
  const BimorphTrace base = Simulate(DefaultPlant(), ref, drive);
  ASSERT_TRUE(base.summary.ok());
  for (int trial = 0; trial < 10; ++trial) {
    BimorphParams p = ref;
    p.beta = r(rng);
    p.gamma = r(rng);
    ASSERT_TRUE(p.HysteresisBounded());
    const BimorphTrace tr = Simulate(DefaultPlant(), p, drive);
    ASSERT_TRUE(tr.summary.ok()) << tr.summary.BriefReport();
    for (double z : tr.z) ASSERT_EQ(z, 0.0);
    EXPECT_EQ(tr.theta_deg, base.theta_deg);
  }
}

// Branch algebra: the zero crossing is where the branch formula vanishes, and z leaves 0 the way
// α·s points.
TEST(BoucWenBranch, ZeroCrossingAndStartSign) {
  const BoucWenParams p{2.5e-3, 6e-3, 4e-3};
  const BoucWenBranch b = StartBranch(p, 375.0, 0.2, -1.0);  // falling from z > 0: κ = −β + γ
  EXPECT_EQ(b.sigma, 1);
  EXPECT_DOUBLE_EQ(b.kappa, -p.beta + p.gamma);
  double uc = 0;
  ASSERT_TRUE(b.ZeroCrossing(&uc));
  EXPECT_LT(uc, 375.0);
  EXPECT_NEAR(b.Z(uc), 0.0, 1e-15);
  const BoucWenBranch up = StartBranch(p, uc, 0.0, -1.0);
  EXPECT_EQ(up.sigma, -1);  // α s < 0: z goes negative
  EXPECT_FALSE(up.ZeroCrossing(&uc));
  EXPECT_FALSE(StartBranch(p, 0.0, 0.1, 1.0).ZeroCrossing(&uc));  // moving away from 0
}

}  // namespace
}  // namespace pz::model
