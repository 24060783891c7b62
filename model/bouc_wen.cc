#include "model/bouc_wen.h"

#include <cmath>

namespace pz::model {

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
    if (b.ZeroCrossing(&uc) && (uc - ua) * b.s > 0 && (ub - uc) * b.s > 0)
      b = StartBranch(p, uc, 0.0, b.s);
    zc = b.s == 0 ? zc : b.Z(ub);
    z[k + 1] = zc;
    if (!std::isfinite(zc)) return false;
  }
  return true;
}

}  // namespace pz::model
