// The asymmetric backlash (play) operator of the paper's Appendix A (model/backlash.h):
//   y_k = min(b1, max(b2, max(θ_k − a1, min(θ_k + a2, y_{k−1})))),  y_{−1} = 0
// Its defining properties, the sequence the spec (§3) describes, and its place in the plant.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "model/backlash.h"
#include "model/bimorph.h"

namespace pz::model {
namespace {

std::vector<double> Apply(const BacklashParams& p, const std::vector<double>& theta,
                          double y0 = 0.0) {
  std::vector<double> y(theta.size());
  ApplyBacklash(p, theta, y, y0);
  return y;
}

std::vector<double> Ramp(double from, double to, int n) {
  std::vector<double> v(n);
  for (int k = 0; k < n; ++k) v[k] = from + (to - from) * k / (n - 1);
  return v;
}

std::vector<double> RandomWalk(unsigned seed, int n, double step) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> d(-step, step);
  std::vector<double> v(n);
  double x = 0;
  for (double& e : v) e = x += d(rng);
  return v;
}

TEST(Backlash, StaysZeroFromRestUntilThetaExceedsA1) {
  const BacklashParams p{0.3, 0.2, 5.0, -5.0};
  const std::vector<double> theta = Ramp(0.0, 1.0, 101);
  const std::vector<double> y = Apply(p, theta);
  for (size_t k = 0; k < theta.size(); ++k) {
    if (theta[k] <= p.a1)
      EXPECT_EQ(y[k], 0.0) << theta[k];
    else
      EXPECT_DOUBLE_EQ(y[k], theta[k] - p.a1) << theta[k];
  }
  // Falling from rest it stays 0 until θ < −a2.
  const std::vector<double> down = Apply(p, Ramp(0.0, -1.0, 101));
  for (size_t k = 0; k < down.size(); ++k) {
    const double th = -static_cast<double>(k) / 100;
    if (th >= -p.a2)
      EXPECT_EQ(down[k], 0.0) << th;
    else
      EXPECT_DOUBLE_EQ(down[k], th + p.a2) << th;
  }
}

TEST(Backlash, OutputBoundedBySaturations) {
  const BacklashParams p{0.1, 0.25, 1.2, -0.7};
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const std::vector<double> y = Apply(p, RandomWalk(seed, 5000, 0.3));
    for (double v : y) {
      EXPECT_LE(v, p.b1);
      EXPECT_GE(v, p.b2);
    }
    EXPECT_EQ(*std::max_element(y.begin(), y.end()), p.b1);  // the walk goes far enough to saturate
    EXPECT_EQ(*std::min_element(y.begin(), y.end()), p.b2);
  }
}

// After a reversal the output holds until θ has come back a1 + a2 (the dead band), in both
// directions.
TEST(Backlash, DeadBandOnReversalIsA1PlusA2) {
  const BacklashParams p{0.3, 0.2, 10.0, -10.0};
  const double peak = 2.0;
  std::vector<double> theta = Ramp(0.0, peak, 201);
  const std::vector<double> back = Ramp(peak, -peak, 401);
  theta.insert(theta.end(), back.begin() + 1, back.end());
  const std::vector<double> y = Apply(p, theta);
  const double held = peak - p.a1;
  for (size_t k = 200; k < theta.size(); ++k) {
    if (theta[k] >= peak - (p.a1 + p.a2))
      EXPECT_DOUBLE_EQ(y[k], held) << theta[k];
    else
      EXPECT_DOUBLE_EQ(y[k], theta[k] + p.a2) << theta[k];
  }
  // And from the bottom back up: held at −peak + a2 until θ rises by a1 + a2.
  std::vector<double> up = Ramp(-peak, peak, 401);
  std::vector<double> th2(theta.begin(), theta.end());
  th2.insert(th2.end(), up.begin() + 1, up.end());
  const std::vector<double> y2 = Apply(p, th2);
  for (size_t k = theta.size(); k < th2.size(); ++k) {
    if (th2[k] <= -peak + (p.a1 + p.a2))
      EXPECT_DOUBLE_EQ(y2[k], -peak + p.a2) << th2[k];
    else
      EXPECT_DOUBLE_EQ(y2[k], th2[k] - p.a1) << th2[k];
  }
}

TEST(Backlash, IdentityWithoutPlayAndWideSaturations) {
  const BacklashParams p{0.0, 0.0, 1e9, -1e9};
  const std::vector<double> theta = RandomWalk(9, 2000, 1.0);
  EXPECT_EQ(Apply(p, theta), theta);
}

// Order preservation: θ ≤ θ' sample by sample implies y ≤ y' (and a larger start gives a larger y).
TEST(Backlash, MonotoneInTheta) {
  const BacklashParams p{0.15, 0.35, 1.5, -1.1};
  for (unsigned seed = 1; seed <= 5; ++seed) {
    const std::vector<double> a = RandomWalk(seed, 3000, 0.2);
    std::vector<double> b = a;
    std::mt19937 rng(100 + seed);
    std::uniform_real_distribution<double> bump(0.0, 0.5);
    for (double& v : b) v += bump(rng);
    const std::vector<double> ya = Apply(p, a), yb = Apply(p, b), yc = Apply(p, a, 0.4);
    for (size_t k = 0; k < a.size(); ++k) {
      EXPECT_LE(ya[k], yb[k]) << k;
      EXPECT_LE(ya[k], yc[k]) << k;
    }
  }
}

// Spec §3: from rest the output stays 0 until θ exceeds a1, follows θ − a1 up to b1, holds b1 after
// the reversal until θ + a2 falls below it, then follows θ + a2 down to b2.
TEST(Backlash, SpecSequenceOnASinusoid) {
  const BacklashParams p{0.281, 0.294, 4.21, -4.03};  // case 7 of the paper
  const double amp = 5.0;
  std::vector<double> theta(240);  // up, down, and up again (stopping before the second peak)
  for (size_t k = 0; k < theta.size(); ++k)
    theta[k] = amp * std::sin(2 * std::numbers::pi * k / 200.0);
  const std::vector<double> y = Apply(p, theta);
  enum Phase {
    kRest,
    kRising,
    kTop,
    kHoldTop,
    kFalling,
    kBottom,
    kHoldBottom,
    kRising2
  } phase = kRest;
  for (size_t k = 0; k < theta.size(); ++k) {
    const double th = theta[k];
    const bool rising = k > 0 && th > theta[k - 1];
    switch (phase) {
      case kRest:
        if (th > p.a1) phase = kRising;
        break;
      case kRising:
        if (th - p.a1 >= p.b1) phase = kTop;
        break;
      case kTop:
        if (!rising) phase = kHoldTop;
        break;
      case kHoldTop:
        if (th + p.a2 < p.b1) phase = kFalling;
        break;
      case kFalling:
        if (th + p.a2 <= p.b2) phase = kBottom;
        break;
      case kBottom:
        if (rising) phase = kHoldBottom;
        break;
      case kHoldBottom:
        if (th - p.a1 > p.b2) phase = kRising2;
        break;
      case kRising2:
        break;
    }
    switch (phase) {
      case kRest:
        EXPECT_EQ(y[k], 0.0) << k;
        break;
      case kRising:
      case kRising2:
        EXPECT_DOUBLE_EQ(y[k], std::min(th - p.a1, p.b1)) << k;
        break;
      case kTop:
      case kHoldTop:
        EXPECT_EQ(y[k], p.b1) << k;
        break;
      case kFalling:
        EXPECT_DOUBLE_EQ(y[k], th + p.a2) << k;
        break;
      case kBottom:
      case kHoldBottom:
        EXPECT_EQ(y[k], p.b2) << k;
        break;
    }
  }
  EXPECT_EQ(phase, kRising2);  // the sinusoid went through every stage
}

TEST(Backlash, InPlaceApplicationAndInitialOutput) {
  const BacklashParams p{0.2, 0.1, 2.0, -2.0};
  std::vector<double> theta = RandomWalk(4, 500, 0.2);
  const std::vector<double> expected = Apply(p, theta, 0.5);
  ApplyBacklash(p, theta, theta, 0.5);  // y aliases θ
  EXPECT_EQ(theta, expected);
  // One step: the falling branch pulls a held 0.5 down to θ + a2 = 0.1.
  EXPECT_DOUBLE_EQ(BacklashStep(p, 0.0, 0.5), 0.1);
}

// In the plant the measured angle is the operator applied to the sampled linear angle.
// BacklashRun cuts the serial chain into four parts joined by composed maps: every value must be
// the one of the plain step-by-step recursion, bit for bit, for any length (including those too
// short to split and those with a remainder), any start value and parameters that saturate or not.
TEST(Backlash, RunInPartsEqualsTheStepByStepRecursionBitForBit) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 400; ++trial) {
    const BacklashParams p{0.5 * u(rng), 0.5 * u(rng), 0.2 + 3 * u(rng), -0.2 - 3 * u(rng)};
    const int n = trial < 40 ? trial : 40 + static_cast<int>(400 * u(rng));
    const std::vector<double> theta =
        RandomWalk(static_cast<unsigned>(trial), n, 0.05 + 0.5 * u(rng));
    const double y0 = 2 * u(rng) - 1;
    std::vector<double> y(theta.size());
    const double last = BacklashRun(p, theta.data(), y.data(), n, y0);
    double prev = y0;
    for (int k = 0; k < n; ++k) {
      prev = BacklashStep(p, theta[k], prev);
      ASSERT_EQ(y[k], prev) << "trial " << trial << ", n = " << n << ", k = " << k;
    }
    EXPECT_EQ(last, prev) << "trial " << trial;
  }
}

TEST(Backlash, PlantAngleIsBacklashOfLinearAngle) {
  const BimorphPlant plant;
  BimorphParams params;
  params.a1 = 0.1;
  params.a2 = 0.15;
  params.b1 = 1.37;
  params.b2 = -1.5;
  const BimorphTrace tr = Simulate(plant, params, Sinusoid{375, 0.25, 3, 100});
  ASSERT_TRUE(tr.summary.ok()) << tr.summary.BriefReport();
  EXPECT_EQ(tr.angle_deg, Apply(params.backlash(), tr.theta_deg));
}

}  // namespace
}  // namespace pz::model
