// The discrete Preisach model and the asymmetric PI operator (model/preisach.h): wiping-out and
// return-point memory, the play representation against the PI operator, the exact inverses
// (inverse then forward returns the reference within 1e-9 of its range) and bad input.
#include "model/preisach.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "model/prandtl_ishlinskii.h"
#include "tests/testing/expect_error.h"

namespace pz::model {
namespace {

/// Piecewise-linear drive through the given turning points, `step` apart (exact multiples).
std::vector<double> Ramps(const std::vector<double>& turns, double step) {
  std::vector<double> u = {turns[0]};
  for (size_t i = 1; i < turns.size(); ++i) {
    const double a = turns[i - 1], b = turns[i];
    const int n = static_cast<int>(std::lround(std::abs(b - a) / step));
    for (int k = 1; k <= n; ++k) u.push_back(a + (b - a) * k / n);
  }
  return u;
}

std::vector<double> RandomWeights(size_t n, uint64_t seed, double zero_share) {
  std::mt19937_64 g(seed);
  std::uniform_real_distribution<double> d(0, 1);
  std::vector<double> w(n);
  for (double& x : w) x = d(g) < zero_share ? 0.0 : d(g);
  return w;
}

std::vector<double> Forward(const PreisachGrid& g, const std::vector<double>& w,
                            const std::vector<double>& u) {
  std::vector<double> y(u.size());
  ApplyPreisach(g, w, u, y);
  return y;
}

TEST(Preisach, WipingOutErasesTheMinorLoopsAMaximumExceeds) {
  const PreisachGrid g{0, 12, 9};
  const auto w = RandomWeights(g.cells(), 1, 0.2);
  // A: a minor loop 8 → 5 inside 10 → 3, then up to 12; B: straight from 3 to 12.
  const auto ua = Ramps({0, 10, 3, 8, 5, 12}, 0.25), ub = Ramps({0, 10, 3, 12}, 0.25);
  const auto ya = Forward(g, w, ua), yb = Forward(g, w, ub);
  int compared = 0;
  for (size_t ka = ua.size() - 1, kb = ub.size() - 1; ua[ka] > 8; --ka, --kb) {
    ASSERT_EQ(ua[ka], ub[kb]);
    EXPECT_NEAR(ya[ka], yb[kb], 1e-12) << "u = " << ua[ka];
    ++compared;
  }
  EXPECT_GT(compared, 10);
  // Below 8 the minor loop is still remembered: the two differ somewhere.
  double diff = 0;
  for (size_t ka = ua.size() - 1, kb = ub.size() - 1; ua[ka] > 5.5; --ka, --kb)
    diff = std::max(diff, std::abs(ya[ka] - yb[kb]));
  EXPECT_GT(diff, 1e-6);
}

TEST(Preisach, ReturnPointMemoryClosesEveryMinorLoop) {
  const PreisachGrid g{-5, 7, 10};
  const auto w = RandomWeights(g.cells(), 2, 0.3);
  const auto u = Ramps({-5, 7, -1, 4, 0.5, 4, 2, 4, -1, 6}, 0.125);
  const auto y = Forward(g, w, u);
  // Arrivals at 4 from below: the first rise from −5, then from −1, 0.5, 2 and (after the fall
  // back to −1, which closes the loop −1 → 4 → −1) from −1 again: the last four are one state.
  std::vector<double> at4;
  for (size_t k = 1; k < u.size(); ++k)
    if (u[k] == 4 && u[k - 1] < 4) at4.push_back(y[k]);
  ASSERT_EQ(at4.size(), 5u);
  for (size_t i = 2; i < 5; ++i) EXPECT_NEAR(at4[i], at4[1], 1e-12) << i;
  EXPECT_GT(std::abs(at4[0] - at4[1]), 1e-6);  // the first rise (from −5) is another branch
  // And the outer loop closes: back at −1 from above after the nested loops equals the first −1
  // turn's state.
  std::vector<double> at_m1;
  for (size_t k = 1; k < u.size(); ++k)
    if (u[k] == -1 && u[k - 1] > -1) at_m1.push_back(y[k]);
  ASSERT_EQ(at_m1.size(), 2u);
  EXPECT_NEAR(at_m1[1], at_m1[0], 1e-12);
}

TEST(Preisach, RegressorsTimesWeightsIsTheModel) {
  const PreisachGrid g{0, 150, 12};
  const auto w = RandomWeights(g.cells(), 3, 0.1);
  std::vector<double> u;
  for (int k = 0; k < 900; ++k)
    u.push_back(75 - 75 * std::cos(2 * std::numbers::pi * k / 300.0) * (1 - k / 1200.0));
  const auto y = Forward(g, w, u);
  std::vector<double> reg(u.size() * g.cells());
  PreisachRegressors(g, u, reg);
  for (size_t k = 0; k < u.size(); ++k) {
    double acc = 0;
    for (size_t j = 0; j < g.cells(); ++j) acc += reg[k * g.cells() + j] * w[j];
    ASSERT_NEAR(acc, y[k], 1e-9);
  }
}

TEST(Preisach, ADensityConstantAlongTheCentreIsThePiOperator) {
  const PreisachGrid g{-2, 10, 8};
  std::vector<double> per_width = {0.7, 0.1, 0.4, 0.05, 0.3, 0.2, 0.15, 0.1};
  std::vector<double> w;
  for (int i = 0; i < g.levels; ++i)
    for (int j = 0; j < g.levels - i; ++j) w.push_back(per_width[static_cast<size_t>(i)]);
  PiOperator pi;
  pi.w0 = per_width[0];
  for (int i = 1; i < g.levels; ++i) {
    pi.thresholds.push_back(g.half_width(i));
    pi.weights.push_back(per_width[static_cast<size_t>(i)]);
  }
  std::vector<double> u;  // starts at the range's middle, sweeps it whole, then minor loops
  for (int k = 0; k < 2000; ++k)
    u.push_back(4 + 6 * std::sin(2 * std::numbers::pi * k / 400.0) * (k < 800 ? 1 : 0.4));
  std::vector<double> ypi(u.size());
  ApplyPi(pi, u, ypi);
  const auto y = Forward(g, w, u);
  for (size_t k = 0; k < u.size(); ++k) ASSERT_NEAR(y[k], ypi[k], 1e-9) << k;
}

TEST(Preisach, InverseThenForwardReturnsTheReference) {
  const PreisachGrid g{0, 100, 12};
  for (uint64_t seed : {4u, 5u, 6u}) {
    const auto w =
        RandomWeights(g.cells(), seed, seed == 6 ? 0.6 : 0.1);  // 60 % zero cells: flat pieces
    // The reference: the model's own output on nested minor loops (reachable by construction),
    // and a smooth reference inside its range.
    std::vector<double> u;
    for (int k = 0; k < 3000; ++k) {
      const double a = std::abs(1 - 2 * k / 3000.0);
      u.push_back(50 - 50 * a * std::cos(2 * std::numbers::pi * k / 250.0));
    }
    const auto ref = Forward(g, w, u);
    const double range =
        *std::max_element(ref.begin(), ref.end()) - *std::min_element(ref.begin(), ref.end());
    std::vector<double> v(ref.size());
    const InverseReport rep = InvertPreisach(g, w, ref, 0, 100, v);
    EXPECT_EQ(rep.saturated, 0u);
    const auto back = Forward(g, w, v);
    for (size_t k = 0; k < ref.size(); ++k)
      ASSERT_NEAR(back[k], ref[k], 1e-9 * range) << "seed " << seed << " k " << k;
  }
}

TEST(Preisach, InverseSaturatesAtTheDriveLimitsAndSaysSo) {
  const PreisachGrid g{0, 10, 4};
  const std::vector<double> w(g.cells(), 1.0);
  const std::vector<double> u = Ramps({0, 10, 0}, 0.5);
  auto ref = Forward(g, w, u);
  ref[10] += 100;  // beyond what any drive reaches
  std::vector<double> v(ref.size());
  const InverseReport rep = InvertPreisach(g, w, ref, 0, 10, v);
  EXPECT_EQ(rep.saturated, 1u);
  EXPECT_EQ(v[10], 10);
  std::vector<double> at_limit(u.begin(), u.begin() + 11);
  at_limit[10] = 10;
  EXPECT_NEAR(rep.max_shortfall, ref[10] - Forward(g, w, at_limit)[10], 1e-9);
  for (double x : v) EXPECT_TRUE(std::isfinite(x));
}

TEST(Preisach, BadInputIsNamed) {
  std::vector<double> y(3), u = {0, 1, 2}, w(3, 1.0);
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] {
                  ApplyPreisach(PreisachGrid{1, 1, 2}, w, u, y);
                }),
                "preisach.range");
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] {
                  ApplyPreisach(PreisachGrid{0, 1, 0}, w, u, y);
                }),
                "preisach.levels");
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] {
                  ApplyPreisach(PreisachGrid{0, 1, 3}, w, u, y);
                }),
                "weights for 6 cells");
  std::vector<double> bad = {1, -0.5, 1};
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] {
                  InvertPreisach(PreisachGrid{0, 1, 2}, bad, u, 0, 1, y);
                }),
                ">= 0");
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] {
                  InvertPreisach(PreisachGrid{0, 1, 2}, w, u, 1, 0, y);
                }),
                "drive limits");
}

AsymmetricPi MakeAsymmetric(uint64_t seed, double w0) {
  AsymmetricPi op;
  op.w0 = w0;
  op.thresholds = PiThresholds(8, 50);
  op.weights = RandomWeights(8, seed, 0.2);
  op.knots = AsymmetricPiKnots(4, 0, 100);
  op.up = RandomWeights(4, seed + 10, 0.3);
  op.down = RandomWeights(4, seed + 20, 0.3);
  return op;
}

TEST(AsymmetricPi, RegressorsTimesWeightsIsTheOperatorAndItsLoopIsAsymmetric) {
  AsymmetricPi op = MakeAsymmetric(7, 0.3);
  op.up = {0, 0, 0, 0.8};  // a steeper top: ascending and descending branches differ in shape
  std::vector<double> u;
  for (int k = 0; k < 1200; ++k) u.push_back(50 - 50 * std::cos(2 * std::numbers::pi * k / 400.0));
  std::vector<double> y(u.size());
  ApplyAsymmetricPi(op, u, y);
  const size_t m = 1 + op.thresholds.size() + 2 * op.knots.size();
  std::vector<double> reg(u.size() * m), w = {op.w0};
  w.insert(w.end(), op.weights.begin(), op.weights.end());
  w.insert(w.end(), op.up.begin(), op.up.end());
  w.insert(w.end(), op.down.begin(), op.down.end());
  AsymmetricPiRegressors(op.thresholds, op.knots, u, reg);
  for (size_t k = 0; k < u.size(); ++k) {
    double acc = 0;
    for (size_t j = 0; j < m; ++j) acc += reg[k * m + j] * w[j];
    ASSERT_NEAR(acc, y[k], 1e-9);
  }
  // Point symmetry of a PI loop about its centre: y(up, u) + y(down, 100 − u) = const. Broken here.
  const size_t up = 400 + 100, down = 400 + 300;  // u = 50 rising, u = 50 falling (periodic regime)
  const size_t up2 = 400 + 50, down2 = 400 + 250;  // u ≈ 14.6 rising and u ≈ 85.4 falling
  const double a = y[up] + y[down], b = y[up2] + y[down2];
  EXPECT_GT(std::abs(a - b), 1e-3);
}

TEST(AsymmetricPi, InverseThenForwardReturnsTheReferenceAndTheDrive) {
  for (uint64_t seed : {8u, 9u}) {
    const AsymmetricPi op = MakeAsymmetric(seed, 0.2);
    std::vector<double> u;
    for (int k = 0; k < 3000; ++k) {
      const double a = std::abs(1 - 2 * k / 3000.0);
      u.push_back(50 - 50 * a * std::cos(2 * std::numbers::pi * k / 250.0) +
                  (k > 2500 ? 30 : 0));  // and beyond the knots
    }
    std::vector<double> ref(u.size()), v(u.size()), back(u.size());
    ApplyAsymmetricPi(op, u, ref);
    const double range =
        *std::max_element(ref.begin(), ref.end()) - *std::min_element(ref.begin(), ref.end());
    InvertAsymmetricPi(op, ref, v);
    ApplyAsymmetricPi(op, v, back);
    for (size_t k = 0; k < u.size(); ++k) {
      ASSERT_NEAR(back[k], ref[k], 1e-9 * range) << k;
      ASSERT_NEAR(v[k], u[k], 1e-8 * 130) << k;  // w0 > 0: strictly increasing, the drive itself
    }
  }
}

/// Preisach and asymmetric PI in the descended / ascended states: the centred model after the drive
/// rose (fell) by the whole grid range and came back (the state's history), and the inverses start
/// in that state: inverse then forward returns the reference.
TEST(Preisach, InitialStatesAreHistoriesAndInvertExactly) {
  const PreisachGrid g{0, 100, 12};
  const auto w = RandomWeights(g.cells(), 11, 0.1);
  const AsymmetricPi a = MakeAsymmetric(12, 0.2);
  std::vector<double> u;
  for (int k = 0; k < 2000; ++k)
    u.push_back(40 + 35 * std::sin(2 * std::numbers::pi * k / 300.0 + 0.4));
  for (InitialState start : {InitialState::kDescended, InitialState::kAscended}) {
    const double swing = start == InitialState::kDescended ? 200 : -200;
    std::vector<double> history = {u[0], u[0] + swing};
    history.insert(history.end(), u.begin(), u.end());
    std::vector<double> y(u.size()), v(u.size()), back(u.size());
    const auto y_hist = Forward(g, w, history);
    ApplyPreisach(g, w, u, y, start);
    for (size_t k = 0; k < u.size(); ++k)
      ASSERT_NEAR(y[k], y_hist[k + 2], 1e-12) << InitialStateName(start) << " " << k;
    EXPECT_GT(std::abs(y[0] - Forward(g, w, u)[0]), 1e-3) << InitialStateName(start);
    const double range =
        *std::max_element(y.begin(), y.end()) - *std::min_element(y.begin(), y.end());
    EXPECT_EQ(InvertPreisach(g, w, y, 0, 100, v, start).saturated, 0u);
    ApplyPreisach(g, w, v, back, start);
    for (size_t k = 0; k < u.size(); ++k)
      ASSERT_NEAR(back[k], y[k], 1e-9 * range) << InitialStateName(start) << " " << k;

    AsymmetricPi s = a;
    s.start = start;
    std::vector<double> ya_hist(history.size()), ya(u.size());
    ApplyAsymmetricPi(a, history, ya_hist);
    ApplyAsymmetricPi(s, u, ya);
    for (size_t k = 0; k < u.size(); ++k)
      ASSERT_NEAR(ya[k], ya_hist[k + 2], 1e-12) << InitialStateName(start) << " " << k;
    InvertAsymmetricPi(s, ya, v);
    for (size_t k = 0; k < u.size(); ++k)
      ASSERT_NEAR(v[k], u[k], 1e-8 * 100) << InitialStateName(start) << " " << k;
  }
}

TEST(AsymmetricPi, BadInputIsNamed) {
  AsymmetricPi op = MakeAsymmetric(1, 0.5);
  op.up[1] = -1;
  std::vector<double> y(2), u = {0, 1};
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { InvertAsymmetricPi(op, u, y); }), "monotone");
  op.up.pop_back();
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { ApplyAsymmetricPi(op, u, y); }),
                "asymmetric-pi.up");
  AsymmetricPi zero = MakeAsymmetric(1, 0);
  std::fill(zero.weights.begin(), zero.weights.end(), 0.0);
  std::fill(zero.up.begin(), zero.up.end(), 0.0);
  std::fill(zero.down.begin(), zero.down.end(), 0.0);
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { InvertAsymmetricPi(zero, u, y); }),
                "every weight is zero");
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { AsymmetricPiKnots(0, 0, 1); }), "knots");
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { AsymmetricPiKnots(3, 1, 1); }), "empty");
}

}  // namespace
}  // namespace pz::model
