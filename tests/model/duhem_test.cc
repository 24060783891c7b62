// The Duhem-type model (model/duhem.h): with c3 = 0 and λ = 0 it is the backlash-like model (exact
// for a piecewise-linear drive, so the two agree to rounding); its ETD2 sub-steps converge to a
// fine reference at second order; it starts at rest on its curve; bad parameters are named.
#include "model/duhem.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "model/stack_models.h"
#include "tests/testing/expect_error.h"

namespace pz::model {
namespace {

std::vector<double> Drive(int n, double dt) {
  std::vector<double> u(n);
  for (int k = 0; k < n; ++k) {
    const double t = k * dt;
    u[k] = t < 0.05 ? 10
                    : 10 + 100 * std::sin(2 * std::numbers::pi * 7 * (t - 0.05) + 2) +
                          20 * std::sin(60 * t);
  }
  return u;
}

TEST(Duhem, ReducesToTheBacklashLikeModel) {
  const double dt = 2e-4;
  const auto u = Drive(5000, dt);
  std::vector<double> a(u.size()), b(u.size());
  SimulateDuhem({0.03, 0.12, 0, 0.05, 0}, u, dt, a);
  SimulateBacklashLike({0.03, 0.12, 0.05}, u, b);
  for (size_t k = 0; k < u.size(); ++k) ASSERT_NEAR(a[k], b[k], 1e-9 * (1 + std::abs(b[k]))) << k;
}

TEST(Duhem, ExactForThePiecewiseLinearDrive) {
  // Reference: classical RK4 on y with 4000 steps per sample interval, the drive linear in between.
  const DuhemParams p{0.05, 0.1, 2e-6, 0.04, 3.0};
  const double dt = 1e-3;
  const auto u = Drive(600, dt);
  std::vector<double> y(u.size());
  SimulateDuhem(p, u, dt, y);
  auto f = [&](double v) { return p.c * v + p.c3 * v * v * v; };
  double yr = f(u[0]), worst = 0;
  const int M = 4000;
  for (size_t k = 1; k < u.size(); ++k) {
    const double s = (u[k] - u[k - 1]) / dt, h = dt / M;
    auto rhs = [&](double tau, double yy) {
      const double uu = u[k - 1] + s * tau;
      return p.alpha * std::abs(s) * (f(uu) - yy) + p.b * s + p.lambda * (f(uu) - yy);
    };
    for (int j = 0; j < M; ++j) {
      const double t = j * h;
      const double k1 = rhs(t, yr), k2 = rhs(t + h / 2, yr + h / 2 * k1),
                   k3 = rhs(t + h / 2, yr + h / 2 * k2), k4 = rhs(t + h, yr + h * k3);
      yr += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    }
    worst = std::max(worst, std::abs(yr - y[k]));
  }
  EXPECT_LT(worst, 1e-9);
  EXPECT_DOUBLE_EQ(y[0], 0.1 * 10 + 2e-6 * 1000);  // at rest on f(u0)
}

TEST(Duhem, BadParametersAreNamed) {
  using pz::testing::InputErrorOf;
  std::vector<double> u = {0, 1}, y(2);
  PZ_EXPECT_HAS(InputErrorOf([&] {
                  SimulateDuhem({-1, 0.1, 0, 0, 0}, u, 1e-3, y);
                }),
                "duhem.alpha = -1: must be >= 0");
  PZ_EXPECT_HAS(InputErrorOf([&] {
                  SimulateDuhem({0, 0.1, 0, 0, NAN}, u, 1e-3, y);
                }),
                "duhem.lambda = nan: must be finite");
  PZ_EXPECT_HAS(InputErrorOf([&] {
                  DuhemFromVector(std::vector<double>{1, 2});
                }),
                "2 parameters given, 5 expected");
}

}  // namespace
}  // namespace pz::model
