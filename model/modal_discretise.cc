#include "model/modal_discretise.h"

#include <cmath>

#include "model/fast_exp.h"

namespace pz::model::modal {
namespace {

// φ_0 … φ_6 at x by e^x and the upward recurrence φ_j = (φ_{j−1} − 1/(j−1)!)/x, as pzk_fin_phi_real
// for |x| ≥ 1 without its branch. e^x by ExpReduced (within 2 ulp of std::exp), and 0 below x =
// −700, where pzk_fin_phi_real's e^x < 1e-304 leaves nothing in the recurrence. The caller selects
// it for |x| ≥ 1. f: 1/n! (the kernel's pzk_fin_inv_fact).
inline void PhiUpward(double x, const double* __restrict f, double* up) {
  const double inv = 1.0 / x;
  const double e = ExpReduced(x < -700.0 ? -700.0 : x);
  up[0] = x < -700.0 ? 0.0 : e;
  for (int j = 1; j <= kMaxPhi; ++j) up[j] = (up[j - 1] - f[j - 1]) * inv;
}

// φ_0 … φ_6 at xs[0 … n) into phi[j · stride + i] for |x| ≥ 1 (PhiUpward).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void PhiRealLargeBatch(int n, const double* __restrict xs, double* __restrict phi, int stride) {
  const double* __restrict f = pzk::pzk_fin_inv_fact();
  for (int i = 0; i < n; ++i) {
    double up[kMaxPhi + 1];
    PhiUpward(xs[i], f, up);
    for (int j = 0; j <= kMaxPhi; ++j) phi[j * stride + i] = up[j];
  }
}

// The same for x of any size, as pzk_fin_phi_real without its branches: for |x| < 1 the Taylor
// series of φ_6 to x^14 and the downward recurrence, otherwise PhiUpward; both computed, one
// selected.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void PhiRealBatch(int n, const double* __restrict xs, double* __restrict phi, int stride) {
  const double* __restrict f = pzk::pzk_fin_inv_fact();
  for (int i = 0; i < n; ++i) {
    const double x = xs[i];
    const bool small = (x < 1.0) & (x > -1.0);
    double p = f[kMaxPhi + 14];
    for (int m = 13; m >= 0; --m) p = p * x + f[m + kMaxPhi];
    double down[kMaxPhi + 1];
    down[kMaxPhi] = p;
    for (int j = kMaxPhi; j >= 1; --j) down[j - 1] = x * down[j] + f[j - 1];
    double up[kMaxPhi + 1];
    PhiUpward(small ? 2.0 : x, f, up);  // any |x| ≥ 1 keeps the unselected lanes finite
    for (int j = 0; j <= kMaxPhi; ++j) phi[j * stride + i] = small ? down[j] : up[j];
  }
}

}  // namespace

void DiscretiseBatch(int n, const ModePoles* poles, double tau, ModeStep* out, double* scratch,
                     int* idx) {
  // The batch: real roots, τ|λ₁| > 1, gap ≥ 0.5 (pzk_fin_discretise's "well separated" real
  // branch). Its
  // modes' indices go to `idx`, τλ₁ and τλ₂ side by side to `xs`.
  double* xs = scratch;  // 2n: τλ₁ of the batch, then τλ₂
  int nb = 0;
  for (int i = 0; i < n; ++i) {
    const ModePoles& p = poles[i];
    const bool batch = !p.complex_pair && -tau * p.l1 > 1.0 && tau * (p.l2 - p.l1) >= 0.5;
    if (batch) {
      idx[nb++] = i;
    } else {
      pzk::pzk_fin_discretise(&p, tau, &out[i]);
    }
  }
  if (nb == 0) return;
  for (int b = 0; b < nb; ++b) {
    xs[b] = tau * poles[idx[b]].l1;
    xs[nb + b] = tau * poles[idx[b]].l2;
  }
  double* phi = scratch + 2 * n;                // 7 rows of 2 nb
  PhiRealLargeBatch(nb, xs, phi, 2 * nb);       // τ|λ₁| > 1 in the batch
  PhiRealBatch(nb, xs + nb, phi + nb, 2 * nb);  // τλ₂ of any size
  const int s = 2 * nb;
  for (int b = 0; b < nb; ++b) {
    const ModePoles& p = poles[idx[b]];
    ModeStep& o = out[idx[b]];
    const double inv = 1.0 / (p.l1 - p.l2);
    for (int j = 0; j <= kMaxPhi; ++j) o.d[j] = (phi[j * s + b] - phi[j * s + nb + b]) * inv;
    const double f10 = phi[b], f20 = phi[nb + b];
    o.e11 = (p.l1 * f20 - p.l2 * f10) * inv;
    o.e22 = (p.l1 * f10 - p.l2 * f20) * inv;
    o.e12 = o.d[0];
    o.e21 = -p.omega2 * o.d[0];
  }
}

}  // namespace pz::model::modal
