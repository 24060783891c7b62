// Closed-form Bouc–Wen hysteresis with exponent 1 (spec "bimorph-fin model", §2):
//
//   ż = α u̇ − β |u̇| z − γ u̇ |z|,    z(0) = 0
//
// z depends on the path of u alone. On a stretch where s = sgn(u̇) and σ = sgn(z) are fixed,
//
//   dz/du = α − κ z,   κ = β s + γ σ,   z(u) = z₀ + (κ z₀ − α) · expm1(−κ (u − u₀)) / κ
//
// (z₀ + α (u − u₀) when κ = 0). Branches end at the reversals of u and at the zero crossings of z.
// For α > 0 the loop is bounded for every input iff β + γ > 0 and β − γ ≥ 0 (the spec's rule,
// BimorphParams::HysteresisBounded()); the model is symmetric under (α, γ, z) → (−α, −γ, −z), so
// for α < 0 the rule reads β − γ > 0 and β + γ ≥ 0 — the same open region, other boundary lines.
#pragma once

#include <cmath>
#include <span>

namespace pz::model {

/// e^x − 1 by its Taylor series to x⁴: FastExpm1's branch for |x| < 1e-3, and the modal simulator's
/// batched z (model/modal_simulator.cc ZBatch).
inline double Expm1Taylor4(double x) {
  return x * (1.0 + x * (0.5 + x * (1.0 / 6 + x * (1.0 / 24))));
}

/// e^x − 1 with an absolute error of a few ulps of 1 (relative too for |x| < 1e-3), cheaper than
/// std::expm1. Branch values are z₀ + gain·(e^x − 1), so the absolute error is what counts.
inline double FastExpm1(double x) {
  if (std::abs(x) < 1e-3) return Expm1Taylor4(x);  // x⁵/120 < 1e-17
  return std::exp(x) - 1.0;
}

/// The three Bouc–Wen parameters.
struct BoucWenParams {
  double alpha = 0;  ///< α, input gain [N/V], finite
  double beta = 0;   ///< β [1/V], finite
  double gamma = 0;  ///< γ [1/V], finite
};

/// One branch of the closed-form solution: z as a function of u while s and σ stay fixed.
struct BoucWenBranch {
  double alpha = 0;  ///< α [N/V]
  double kappa = 0;  ///< κ = β s + γ σ [1/V]
  double u0 = 0;     ///< input at the start of the branch [V]
  double z0 = 0;     ///< z at the start of the branch [N]
  int s = 0;         ///< direction of u on the branch: +1, −1, or 0 (u constant: z frozen)
  int sigma = 0;     ///< sign of z on the branch (0 only when z stays 0)

  double gain = 0;  ///< (κ z₀ − α)/κ [N] (unused when κ = 0); set by StartBranch

  /// z [N] at input u [V] (exact on the branch; the formula extends smoothly past its ends).
  double Z(double u) const {
    const double du = u - u0;
    return kappa == 0.0 ? z0 + alpha * du : z0 + gain * FastExpm1(-kappa * du);
  }
  /// dz/du [N/V] at z [N].
  double Slope(double z) const { return alpha - kappa * z; }
  /// The input at which z reaches 0 while u moves in direction s, if it does (before the branch's
  /// fixed point α/κ): writes it to *u_cross and returns true.
  bool ZeroCrossing(double* u_cross) const {
    // z moves towards 0 iff dz = α du at z = 0 points back at the side z is on: α s σ < 0.
    if (z0 == 0.0 || alpha == 0.0 || s == 0 || alpha * s * sigma >= 0) return false;
    // z(u) = 0  ⇔  u − u₀ = log1p(y)/κ with y = −κ z₀/α; no crossing when 1 + y ≤ 0 (z stops at
    // α/κ).
    const double y = -kappa * z0 / alpha;
    if (!(y > -1.0)) return false;
    const double ratio = std::abs(y) < 1e-12 ? 1.0 - 0.5 * y : std::log1p(y) / y;
    const double du = (-z0 / alpha) * ratio;
    if (!std::isfinite(du)) return false;
    *u_cross = u0 + du;
    return true;
  }
};

/// Starts a branch at (u0, z0) with u moving in direction s (sign taken; 0 freezes z). At z0 = 0
/// the sign σ is that of α s, the way z leaves zero. Inline, as ZeroCrossing: the fin's sampled
/// path starts a branch at every sample (model/modal_simulator.cc).
inline BoucWenBranch StartBranch(const BoucWenParams& p, double u0, double z0, double s) {
  const auto sign = [](double x) { return (x > 0) - (x < 0); };
  BoucWenBranch b;
  b.alpha = p.alpha;
  b.u0 = u0;
  b.z0 = z0;
  b.s = sign(s);
  b.sigma = z0 != 0.0 ? sign(z0) : sign(p.alpha) * b.s;
  b.kappa = p.beta * b.s + p.gamma * b.sigma;
  b.gain = b.kappa != 0.0 ? (b.kappa * z0 - p.alpha) / b.kappa : 0.0;
  return b;
}

/// z along a piecewise-linear input path u_0, u_1, … (exact: z depends on the path of u only), from
/// z(u_0) = z_init. z.size() must equal u.size(); returns false (and leaves z partly filled) if a
/// value becomes non-finite, as it does for unbounded parameters driven far enough.
bool BoucWenAlongPath(const BoucWenParams& p, std::span<const double> u, std::span<double> z,
                      double z_init = 0.0);

}  // namespace pz::model
