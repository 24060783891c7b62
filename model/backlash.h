// Asymmetric backlash (play) operator of the paper's Appendix A, on a sampled sequence:
//
//   y_k = min(b1, max(b2, max(θ_k − a1, min(θ_k + a2, y_{k−1})))),   y_{−1} = y0 (default 0)
//
// a1 ≥ 0 [deg] threshold on the rising branch, a2 ≥ 0 [deg] on the falling branch,
// b1 > 0 and b2 < 0 [deg] the saturations.
#pragma once

#include <algorithm>
#include <span>

namespace pz::model {

struct BacklashParams {
  double a1 = 0.0;  ///< rising threshold [deg], ≥ 0
  double a2 = 0.0;  ///< falling threshold [deg], ≥ 0
  double b1 = 1.0;  ///< upper saturation [deg], > 0
  double b2 = -1.0; ///< lower saturation [deg], < 0
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

/// Applies the operator to theta (deg) into y (same length; may alias theta).
inline void ApplyBacklash(const BacklashParams& p, std::span<const double> theta, std::span<double> y,
                          double y0 = 0.0) {
  double prev = y0;
  for (size_t k = 0; k < theta.size(); ++k) prev = y[k] = BacklashStep(p, theta[k], prev);
}

}  // namespace pz::model
