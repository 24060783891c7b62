// Asymmetric backlash (play) operator of the paper's Appendix A, on a sampled sequence:
//
//   y_k = min(b1, max(b2, max(θ_k − a1, min(θ_k + a2, y_{k−1})))),   y_{−1} = y0 (default 0)
//
// a1 ≥ 0 [deg] threshold on the rising branch, a2 ≥ 0 [deg] on the falling branch,
// b1 > 0 and b2 < 0 [deg] the saturations.
#pragma once

#include <algorithm>
#include <limits>
#include <span>

namespace pz::model {

struct BacklashParams {
  double a1 = 0.0;   ///< rising threshold [deg], ≥ 0
  double a2 = 0.0;   ///< falling threshold [deg], ≥ 0
  double b1 = 1.0;   ///< upper saturation [deg], > 0
  double b2 = -1.0;  ///< lower saturation [deg], < 0
};

/// One step of the operator. The formula above, rearranged so that y_{k−1} meets two operations
/// instead of four (this is the serial chain of a simulation's output): max(b2, max(lo, v)) =
/// max(max(b2, lo), v), and min(b1, max(L, v)) = max(min(b1, L), min(b1, v)) (min distributes over
/// max), so y_k = max(A, min(B, y_{k−1})) with A = min(b1, max(b2, θ − a1)), B = min(b1, θ + a2).
/// min and max are exact: the same value for every finite input (a zero may change its sign).
inline double BacklashStep(const BacklashParams& p, double theta, double y_prev) {
  const double a = std::min(p.b1, std::max(p.b2, theta - p.a1));
  const double b = std::min(p.b1, theta + p.a2);
  return std::max(a, std::min(b, y_prev));
}

/// The operator over theta[0, n) into y[0, n) (may alias theta), from y_{−1} = y_prev; returns
/// y_{n−1} (y_prev when n = 0). The same values as n BacklashSteps in a row, with a quarter of
/// their serial chain: the steps' maps y ↦ max(A, min(B, y)) compose into one of the same form,
///   f_k ∘ f = y ↦ max(max(A_k, min(B_k, A)), min(min(B_k, B), y))   (min distributes over max),
/// so each of the first three quarters is reduced to one map (giving where the next quarter
/// starts), then the four quarters run side by side. Only min and max touch the chain: exact.
inline double BacklashRun(const BacklashParams& p, const double* theta, double* y, long n,
                          double y_prev) {
  constexpr int kParts = 4;
  const long len = n / kParts;  // the first three parts; the last takes the remainder too
  if (len < 4) {
    for (long k = 0; k < n; ++k) y_prev = y[k] = BacklashStep(p, theta[k], y_prev);
    return y_prev;
  }
  auto bounds = [&p](double th, double* a, double* b) {
    *a = std::min(p.b1, std::max(p.b2, th - p.a1));
    *b = std::min(p.b1, th + p.a2);
  };
  constexpr double kInf = std::numeric_limits<double>::infinity();
  double fa[kParts - 1], fb[kParts - 1];  // the maps of parts 0 … kParts − 2
  for (int q = 0; q < kParts - 1; ++q) fa[q] = -kInf, fb[q] = kInf;
  for (long i = 0; i < len; ++i) {
    for (int q = 0; q < kParts - 1; ++q) {
      double a, b;
      bounds(theta[q * len + i], &a, &b);
      fa[q] = std::max(a, std::min(b, fa[q]));
      fb[q] = std::min(b, fb[q]);
    }
  }
  double ys[kParts];
  ys[0] = y_prev;
  for (int q = 0; q + 1 < kParts; ++q) ys[q + 1] = std::max(fa[q], std::min(fb[q], ys[q]));
  for (long i = 0; i < len; ++i) {
    for (int q = 0; q < kParts; ++q)
      ys[q] = y[q * len + i] = BacklashStep(p, theta[q * len + i], ys[q]);
  }
  double last = ys[kParts - 1];
  for (long k = kParts * len; k < n; ++k) last = y[k] = BacklashStep(p, theta[k], last);
  return last;
}

/// Applies the operator to theta (deg) into y (same length; may alias theta).
inline void ApplyBacklash(const BacklashParams& p, std::span<const double> theta,
                          std::span<double> y, double y0 = 0.0) {
  BacklashRun(p, theta.data(), y.data(), static_cast<long>(theta.size()), y0);
}

}  // namespace pz::model
