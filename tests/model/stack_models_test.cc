// The stack models of seed 002 (model/stack_models.h): the Bouc–Wen model with driver filter and
// the backlash-like model. Closed forms, the filter's step response, periodic loops, and the
// convergence of the discretisation against finer steps.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "model/stack_models.h"
#include "tests/testing/expect_error.h"

namespace pz::model {
namespace {

constexpr double kPi = std::numbers::pi;

// u_k = offset + A sin(2π f k / fs), k = 0 … n − 1.
std::vector<double> Sine(double offset, double amp, double f, double fs, int n) {
  std::vector<double> u(n);
  for (int k = 0; k < n; ++k) u[k] = offset + amp * std::sin(2 * kPi * f * k / fs);
  return u;
}

std::vector<double> BoucWen(const StackBoucWenParams& p, const std::vector<double>& u, double dt,
                            int substeps = 2) {
  std::vector<double> y(u.size());
  SimulateStackBoucWen(p, u, dt, y, StackSimOptions{substeps});
  return y;
}

std::vector<double> Backlash(const BacklashLikeParams& p, const std::vector<double>& u) {
  std::vector<double> y(u.size());
  SimulateBacklashLike(p, u, y);
  return y;
}

TEST(StackBoucWen, StartsAtRestAtTheOffset) {
  const StackBoucWenParams p;
  const std::vector<double> u(50, 400.0);
  std::vector<double> y(u.size()), h(u.size());
  SimulateStackBoucWen(p, u, 2e-4, y, {}, h);
  for (size_t k = 0; k < u.size(); ++k) {
    EXPECT_EQ(h[k], 0.0) << k;
    EXPECT_DOUBLE_EQ(y[k], p.d * 400.0) << k;
  }
}

/// StackRestState is the memory after the drive rose from a virgin rest by the range and came back
/// (descended; ascended: the mirror): the simulation from it is the virgin simulation after that
/// history — exactly for the backlash-like model, h to rounding for Bouc–Wen (its filter starts at
/// rest, so only h is compared) — and a descended stack rests above its virgin output.
TEST(StackModels, RestStatesAreTheStatesAfterAMajorSwing) {
  const StackBoucWenParams bw;
  const BacklashLikeParams bl{0.01, 0.05, 0.02};
  const double range = 300;
  const auto u = Sine(400, 150, 50, 5000, 400);
  for (InitialState start : {InitialState::kDescended, InitialState::kAscended}) {
    const double swing = start == InitialState::kDescended ? range : -range;
    std::vector<double> history = {u[0], u[0] + swing};
    history.insert(history.end(), u.begin(), u.end());
    std::vector<double> y_hist(history.size()), y(u.size());
    SimulateBacklashLike(bl, history, y_hist);
    const double w0 = StackRestState(bl, range, start);
    SimulateBacklashLike(bl, u, y, w0);
    EXPECT_GT(std::abs(w0), 1.0) << InitialStateName(start);
    for (size_t k = 0; k < u.size(); ++k)
      ASSERT_NEAR(y[k], y_hist[k + 2], 1e-12 * 400) << InitialStateName(start) << " " << k;

    std::vector<double> h_hist(history.size()), yb_hist(history.size()), h(u.size()), yb(u.size());
    SimulateStackBoucWen(bw, history, 2e-4, yb_hist, {}, h_hist);
    StackSimOptions o;
    o.rest_state = StackRestState(bw, range, start);
    SimulateStackBoucWen(bw, u, 2e-4, yb, o, h);
    EXPECT_EQ(h[0], o.rest_state);
    EXPECT_DOUBLE_EQ(yb[0], bw.d * (u[0] - o.rest_state));
    for (size_t k = 0; k < u.size(); ++k)
      ASSERT_NEAR(h[k], h_hist[k + 2], 1e-9 * 400) << InitialStateName(start) << " " << k;
  }
  EXPECT_GT(StackRestState(bw, range, InitialState::kAscended),
            0);  // h > 0 after a rise: the output below d u
  EXPECT_LT(StackRestState(bw, range, InitialState::kDescended), 0);  // and above it after a fall
  EXPECT_EQ(StackRestState(bw, range, InitialState::kCentred), 0);
}

// α = 0 keeps h at 0, so ŷ = LPF[d u]: a step of u over one sample then held. Closed form of the
// first-order filter for the ramp piece and the exponential approach after it.
TEST(StackBoucWen, FilterStepResponseIsTheFirstOrderClosedForm) {
  StackBoucWenParams p;
  p.alpha = 0;
  p.d = 0.05;
  p.fc_hz = 300;
  const double dt = 2e-4, u0 = 400, u1 = 500;
  std::vector<double> u(400, u1);
  u[0] = u0;
  for (int m : {1, 3}) {
    const auto y = BoucWen(p, u, dt, m);
    const double w = 2 * kPi * p.fc_hz;
    const double x0 = p.d * u0, x1 = p.d * u1, slope = (x1 - x0) / dt;
    const double y_ramp_end = x1 - slope / w + (x0 - x0 + slope / w) * std::exp(-w * dt);
    EXPECT_NEAR(y[0], x0, 1e-13);
    for (size_t k = 1; k < u.size(); ++k) {
      const double want = x1 + (y_ramp_end - x1) * std::exp(-w * (k - 1) * dt);
      EXPECT_NEAR(y[k], want, 1e-12 * x1) << "k " << k << " substeps " << m;
    }
    // One time constant after the ramp: 1 − e^{−1} of the way from y_ramp_end to the target.
    const double tau = 1 / w;
    const double t_tau = dt + tau;
    const size_t k = static_cast<size_t>(std::lround(t_tau / dt));
    const double frac = (y[k] - y_ramp_end) / (x1 - y_ramp_end);
    EXPECT_NEAR(frac, 1 - std::exp(-((k - 1) * dt) / tau), 1e-12);
    EXPECT_NEAR(frac, 1 - std::exp(-1.0), 0.05);  // k dt is within one sample of tau
  }
}

// The state update integrates dh/du = α − (β s + γ sgn h) h exactly, also across h = 0.
TEST(StackBoucWen, StateStepMatchesAFineIntegrationAcrossZero) {
  const double alpha = 0.3, beta = 0.0045, gamma = 0.0015;
  for (double h0 : {-30.0, -1.0, 0.0, 12.0, 49.0}) {
    for (double du : {150.0, -150.0, 3.0, -0.5}) {
      // RK4 in u with 200,000 steps (the right-hand side is Lipschitz; the kink at 0 costs one
      // step's accuracy).
      const int n = 200000;
      const double s = du > 0 ? 1 : -1, step = du / n;
      auto f = [&](double h) { return alpha - (beta * s + (h >= 0 ? gamma : -gamma)) * h; };
      double h = h0;
      for (int i = 0; i < n; ++i) {
        const double k1 = f(h), k2 = f(h + 0.5 * step * k1), k3 = f(h + 0.5 * step * k2),
                     k4 = f(h + step * k3);
        h += step / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      }
      EXPECT_NEAR(BoucWenStateStep(h0, du, alpha, beta, gamma), h, 1e-7)
          << "h0 " << h0 << " du " << du;
    }
  }
  EXPECT_EQ(BoucWenStateStep(5.0, 0.0, alpha, beta, gamma), 5.0);
}

// A periodic drive reaches a periodic loop: the last two periods agree, and the loop is open
// (ascending and descending branches differ: hysteresis), bounded by the saturation α/(β+γ).
TEST(StackBoucWen, LoopClosesOnAPeriodicDrive) {
  const StackBoucWenParams p;
  const double fs = 5000, f = 50;
  const int per = 100, periods = 30;
  const auto u = Sine(400, 400, f, fs, per * periods + 1);
  std::vector<double> y(u.size()), h(u.size());
  SimulateStackBoucWen(p, u, 1 / fs, y, {}, h);
  double diff = 0, hmax = 0;
  for (int k = 0; k < per; ++k) {
    const size_t a = per * (periods - 2) + k, b = per * (periods - 1) + k;
    diff = std::max(diff, std::abs(y[b] - y[a]));
  }
  for (double v : h) hmax = std::max(hmax, std::abs(v));
  EXPECT_LT(diff, 1e-9);
  EXPECT_LE(hmax, p.alpha / (p.beta + p.gamma) + 1e-9);
  // Same drive value u = 400 V on the way up (k = 0) and down (k = 50) of the last period.
  const size_t up = per * (periods - 1), down = up + per / 2;
  EXPECT_NEAR(u[up], u[down], 1e-9);
  EXPECT_GT(std::abs(y[up] - y[down]), 0.5);  // µm of hysteresis
}

TEST(StackBacklashLike, LoopClosesOnAPeriodicDrive) {
  const BacklashLikeParams p{0.01, 0.05, 0.02};
  const int per = 100, periods = 30;
  const auto u = Sine(400, 400, 50, 5000, per * periods + 1);
  const auto y = Backlash(p, u);
  double diff = 0;
  for (int k = 0; k < per; ++k)
    diff = std::max(diff, std::abs(y[per * (periods - 1) + k] - y[per * (periods - 2) + k]));
  EXPECT_LT(diff, 1e-9);
  const size_t up = per * (periods - 1), down = up + per / 2;
  EXPECT_GT(std::abs(y[up] - y[down]), 1.0);
}

// On a monotone drive from rest the backlash-like model has Su et al.'s closed form
//   ŷ(u) = c u − w*(1 − e^{−α |u − u0|}) · s,   w* = (c − B1)/α,
// and after a reversal at u_r with w_r: w(u) = −w* + (w_r + w*) e^{−α (u_r − u)}.
TEST(StackBacklashLike, ReducesToTheClosedFormOnRampsUpAndDown) {
  const BacklashLikeParams p{0.02, 0.05, 0.015};
  const double ws = (p.c - p.b1) / p.alpha;
  const int n = 2001;
  std::vector<double> u(2 * n - 1);
  for (int k = 0; k < n; ++k) u[k] = 400 + 0.2 * k;          // up to 800 V
  for (int k = 1; k < n; ++k) u[n - 1 + k] = 800 - 0.3 * k;  // down to 200 V
  const auto y = Backlash(p, u);
  for (int k = 0; k < n; ++k) {
    const double want = p.c * u[k] - ws * (1 - std::exp(-p.alpha * (u[k] - 400)));
    EXPECT_NEAR(y[k], want, 1e-11) << k;
  }
  const double wr = ws * (1 - std::exp(-p.alpha * 400));
  for (int k = n; k < 2 * n - 1; ++k) {
    const double want = p.c * u[k] - (-ws + (wr + ws) * std::exp(-p.alpha * (800 - u[k])));
    EXPECT_NEAR(y[k], want, 1e-11) << k;
  }
}

// The discretisation converges at second order: the filter sub-steps (Bouc–Wen), and the drive's
// sampling (both models; a sinusoid sampled at fs·r compared on the common samples with a very
// fine reference).
TEST(StackModels, DiscretisationConvergesAtSecondOrder) {
  const StackBoucWenParams p;  // fc 1500 Hz: ω Δt ≈ 1.9 at 5 kHz
  const double fs = 5000, f = 340;
  const int n = 2500;
  const auto u = Sine(400, 400, f, fs, n);
  const auto ref = BoucWen(p, u, 1 / fs, 256);
  std::vector<double> err;
  for (int m : {1, 2, 4, 8}) {
    const auto y = BoucWen(p, u, 1 / fs, m);
    double e = 0;
    for (int k = 0; k < n; ++k) e = std::max(e, std::abs(y[k] - ref[k]));
    err.push_back(e);
  }
  EXPECT_LT(err[1], 0.05);  // µm, the default (2 sub-steps) against the fine reference
  for (size_t i = 1; i < err.size(); ++i) {
    EXPECT_GT(err[i - 1] / err[i], 3.0) << "sub-steps " << (1 << (i - 1));
    EXPECT_LT(err[i - 1] / err[i], 5.0) << "sub-steps " << (1 << (i - 1));
  }

  // Drive sampling: the same sinusoid sampled r times finer, compared at t = k / fs.
  const int r_ref = 128;
  const BacklashLikeParams b{0.01, 0.05, 0.02};
  const auto u_ref = Sine(400, 400, f, fs * r_ref, (n - 1) * r_ref + 1);
  const auto bw_ref = BoucWen(p, u_ref, 1 / (fs * r_ref), 1);
  const auto bl_ref = Backlash(b, u_ref);
  std::vector<double> e_bw, e_bl;
  for (int r : {1, 2, 4, 8}) {
    const auto ur = Sine(400, 400, f, fs * r, (n - 1) * r + 1);
    const auto bw = BoucWen(p, ur, 1 / (fs * r), 1);
    const auto bl = Backlash(b, ur);
    double a = 0, c = 0;
    for (int k = 0; k < n; ++k) {
      a = std::max(a, std::abs(bw[k * r] - bw_ref[k * r_ref]));
      c = std::max(c, std::abs(bl[k * r] - bl_ref[k * r_ref]));
    }
    e_bw.push_back(a);
    e_bl.push_back(c);
  }
  for (size_t i = 1; i < e_bw.size(); ++i) {
    EXPECT_GT(e_bw[i - 1] / e_bw[i], 3.0) << i;
    EXPECT_GT(e_bl[i - 1] / e_bl[i], 3.0) << i;
  }
}

TEST(StackModels, VectorInterfaceMatchesTheStructs) {
  const auto u = Sine(400, 300, 125, 5000, 3000);
  const StackBoucWenParams p{0.25, 0.004, -0.001, 0.052, 2200};
  std::vector<double> a(u.size()), b(u.size());
  SimulateStackBoucWen(p, u, 2e-4, a);
  SimulateStack(StackFamily::kBoucWen, ToVector(p), u, 2e-4, b);
  EXPECT_EQ(a, b);
  const BacklashLikeParams q{0.03, 0.049, 0.01};
  SimulateBacklashLike(q, u, a);
  SimulateStack(StackFamily::kBacklashLike, ToVector(q), u, 2e-4, b);
  EXPECT_EQ(a, b);
  EXPECT_EQ(StackParamNames(StackFamily::kBoucWen).size(), 5u);
  EXPECT_EQ(ParseStackFamily("backlash-like"), StackFamily::kBacklashLike);
  EXPECT_FALSE(ParseStackFamily("bouc_wen").has_value());
}

TEST(StackModels, BadInputIsNamed) {
  using pz::testing::InputErrorOf;
  const auto u = Sine(400, 300, 125, 5000, 10);
  std::vector<double> y(u.size()), shorter(5);
  StackBoucWenParams p;
  p.fc_hz = 0;
  PZ_EXPECT_HAS(InputErrorOf([&] { SimulateStackBoucWen(p, u, 2e-4, y); }), "fc_Hz = 0");
  p = {};
  p.beta = NAN;
  PZ_EXPECT_HAS(InputErrorOf([&] { SimulateStackBoucWen(p, u, 2e-4, y); }), "beta = nan");
  p = {};
  PZ_EXPECT_HAS(InputErrorOf([&] { SimulateStackBoucWen(p, u, 0, y); }), "dt = 0");
  PZ_EXPECT_HAS(InputErrorOf([&] { SimulateStackBoucWen(p, u, 2e-4, y, StackSimOptions{0}); }),
                "substeps = 0");
  PZ_EXPECT_HAS(InputErrorOf([&] { SimulateStackBoucWen(p, u, 2e-4, shorter); }),
                "u has 10 samples, yhat has 5");
  PZ_EXPECT_HAS(InputErrorOf([&] { SimulateBacklashLike({-1, 0.05, 0.01}, u, y); }), "alpha = -1");
  const std::vector<double> four(4);
  PZ_EXPECT_HAS(InputErrorOf([&] { SimulateStack(StackFamily::kBacklashLike, four, u, 2e-4, y); }),
                "4 values given, 3 expected");
}

}  // namespace
}  // namespace pz::model
