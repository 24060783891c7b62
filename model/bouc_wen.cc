#include "model/bouc_wen.h"

#include <cmath>

namespace pz::model {

namespace {
int Sign(double x) { return (x > 0) - (x < 0); }
}  // namespace

bool BoucWenBranch::ZeroCrossing(double* u_cross) const {
  // z moves towards 0 iff dz = α du at z = 0 points back at the side z is on: α s σ < 0.
  if (z0 == 0.0 || alpha == 0.0 || s == 0 || alpha * s * sigma >= 0) return false;
  // z(u) = 0  ⇔  u − u₀ = log1p(y)/κ with y = −κ z₀/α; no crossing when 1 + y ≤ 0 (z stops at α/κ).
  const double y = -kappa * z0 / alpha;
  if (!(y > -1.0)) return false;
  const double ratio = std::abs(y) < 1e-12 ? 1.0 - 0.5 * y : std::log1p(y) / y;
  const double du = (-z0 / alpha) * ratio;
  if (!std::isfinite(du)) return false;
  *u_cross = u0 + du;
  return true;
}

BoucWenBranch StartBranch(const BoucWenParams& p, double u0, double z0, double s) {
  BoucWenBranch b;
  b.alpha = p.alpha;
  b.u0 = u0;
  b.z0 = z0;
  b.s = Sign(s);
  b.sigma = z0 != 0.0 ? Sign(z0) : Sign(p.alpha) * b.s;
  b.kappa = p.beta * b.s + p.gamma * b.sigma;
  b.gain = b.kappa != 0.0 ? (b.kappa * z0 - p.alpha) / b.kappa : 0.0;
  return b;
}

bool BoucWenAlongPath(const BoucWenParams& p, std::span<const double> u, std::span<double> z,
                      double z_init) {
  if (u.size() != z.size() || u.empty()) return u.size() == z.size();
  double zc = z_init;
  z[0] = zc;
  for (size_t k = 0; k + 1 < u.size(); ++k) {
    const double ua = u[k], ub = u[k + 1];
    BoucWenBranch b = StartBranch(p, ua, zc, ub - ua);
    double uc;
    // At most one crossing per monotone segment: after it, z moves away from 0.
    if (b.ZeroCrossing(&uc) && (uc - ua) * b.s > 0 && (ub - uc) * b.s > 0) b = StartBranch(p, uc, 0.0, b.s);
    zc = b.s == 0 ? zc : b.Z(ub);
    z[k + 1] = zc;
    if (!std::isfinite(zc)) return false;
  }
  return true;
}

}  // namespace pz::model
