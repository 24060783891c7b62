#include "model/modal_discretise.h"

#include <cmath>

#include "model/fast_exp.h"

namespace pz::model::modal {
namespace {

// 1/n! for n = 0 … 24.
constexpr double kInvFact[25] = {
    1.0,
    1.0,
    1.0 / 2,
    1.0 / 6,
    1.0 / 24,
    1.0 / 120,
    1.0 / 720,
    1.0 / 5040,
    1.0 / 40320,
    1.0 / 362880,
    1.0 / 3628800,
    1.0 / 39916800,
    1.0 / 479001600,
    1.0 / 6227020800.0,
    1.0 / 87178291200.0,
    1.0 / 1307674368000.0,
    1.0 / 20922789888000.0,
    1.0 / 355687428096000.0,
    1.0 / 6402373705728000.0,
    1.0 / 121645100408832000.0,
    1.0 / 2432902008176640000.0,
    1.0 / 51090942171709440000.0,
    1.0 / 1124000727777607680000.0,
    1.0 / 25852016738884976640000.0,
    1.0 / 620448401733239439360000.0,
};

// Minimal complex arithmetic (std::complex multiplication goes through __muldc3 without
// -ffast-math; the values here are always finite).
struct Cx {
  double re, im;
};
inline Cx Mul(Cx a, Cx b) { return {a.re * b.re - a.im * b.im, a.re * b.im + a.im * b.re}; }
inline Cx Inv(Cx a) {
  const double n = a.re * a.re + a.im * a.im;
  return {a.re / n, -a.im / n};
}

// φ_0 … φ_6 at a complex x. |x| < 1: Taylor series of φ_6, then the stable downward recurrence
// φ_{j−1} = x φ_j + 1/(j−1)!; otherwise upward from e^x (error factor 1/|x| ≤ 1 per step).
void PhiComplex(Cx x, Cx* phi) {
  const double r2 = x.re * x.re + x.im * x.im;
  if (r2 < 1.0) {
    Cx p{kInvFact[kMaxPhi + 16], 0.0};
    for (int m = 15; m >= 0; --m) {
      p = Mul(p, x);
      p.re += kInvFact[m + kMaxPhi];
    }
    phi[kMaxPhi] = p;
    for (int j = kMaxPhi; j >= 1; --j) {
      Cx q = Mul(x, phi[j]);
      q.re += kInvFact[j - 1];
      phi[j - 1] = q;
    }
    return;
  }
  if (x.re > -745.0) {
    const double e = std::exp(x.re);
    phi[0] = {e * std::cos(x.im), e * std::sin(x.im)};
  } else {
    phi[0] = {0.0, 0.0};
  }
  const Cx inv = Inv(x);
  for (int j = 1; j <= kMaxPhi; ++j) {
    Cx q = phi[j - 1];
    q.re -= kInvFact[j - 1];
    phi[j] = Mul(q, inv);
  }
}

// Small |τλ| (ρ ≤ 1): D_j = τ Σ_m k_m / (m + 1 + j)!, k_m = τ^m h_m with the complete homogeneous
// polynomials h_m(λ₁, λ₂) = s h_{m−1} − p h_{m−2} (s = λ₁ + λ₂ = −c, p = λ₁λ₂ = ω²) — all real.
// D_6, D_5 from the series, the rest by the stable downward recurrence of φ_j(τA) b.
void SeriesRegime(const ModePoles& p, double tau, ModeStep& out) {
  const double ts = -p.c * tau, tp = p.omega2 * tau * tau;
  double km2 = 0.0, km1 = 1.0;  // k_{m−2}, k_{m−1}; start with k_0 = 1
  double s6 = 0.0, s5 = 0.0;
  for (int m = 0; m <= 17; ++m) {
    const double k = m == 0 ? 1.0 : ts * km1 - tp * km2;
    if (m > 0) {
      km2 = km1;
      km1 = k;
    }
    s6 += k * kInvFact[m + 1 + kMaxPhi];
    s5 += k * kInvFact[m + kMaxPhi];
  }
  double* d = out.d;
  d[kMaxPhi] = tau * s6;
  d[kMaxPhi - 1] = tau * s5;
  for (int j = kMaxPhi - 1; j >= 1; --j)
    d[j - 1] = tau * kInvFact[j] - p.c * tau * d[j] - tp * d[j + 1];
  out.e11 = 1.0 - p.omega2 * tau * d[1];
  out.e12 = d[0];
  out.e21 = -p.omega2 * d[0];
  out.e22 = out.e11 - p.c * d[0];
}

}  // namespace

void PhiReal(double x, double* phi) {
  const double ax = std::abs(x);
  if (ax < 1.0) {
    // Taylor terms of φ_6 up to x^N with |x|^{N+1} 6!/(N+7)! < 2^-53: N = 7, 9, 14 for |x| ≤ 1/16,
    // 1/4, 1.
    const int top = ax <= 0.0625 ? 7 : (ax <= 0.25 ? 9 : 14);
    double p = kInvFact[kMaxPhi + top];
    for (int m = top - 1; m >= 0; --m) p = p * x + kInvFact[m + kMaxPhi];
    phi[kMaxPhi] = p;
    for (int j = kMaxPhi; j >= 1; --j) phi[j - 1] = x * phi[j] + kInvFact[j - 1];
    return;
  }
  phi[0] =
      x > -745.0 ? std::exp(x) : 0.0;  // below −745 e^x underflows (and exp() takes a slow path)
  const double inv = 1.0 / x;
  for (int j = 1; j <= kMaxPhi; ++j) phi[j] = (phi[j - 1] - kInvFact[j - 1]) * inv;
}

ModePoles MakePoles(double omega2, double c) {
  ModePoles p;
  p.omega2 = omega2;
  p.c = c;
  const double w = std::sqrt(omega2);
  const double disc = (c - 2 * w) * (c + 2 * w);  // c² − 4ω² without cancellation of the squares
  if (disc < 0) {
    p.complex = true;
    p.re = -0.5 * c;
    p.im = 0.5 * std::sqrt(-disc);
  } else {
    p.l1 = -0.5 * (c + std::sqrt(disc));       // the larger magnitude root, no cancellation
    p.l2 = p.l1 != 0.0 ? omega2 / p.l1 : 0.0;  // λ₁λ₂ = ω²
  }
  return p;
}

void Discretise(const ModePoles& p, double tau, ModeStep& out) {
  if (!(tau > 0)) {
    out = ModeStep{};
    return;
  }
  const double rho = p.complex ? tau * std::sqrt(p.omega2) : -tau * p.l1;  // τ max|λ|
  if (rho <= 1.0) {
    SeriesRegime(p, tau, out);
    return;
  }
  double* d = out.d;
  const double gap = p.complex ? 2 * tau * p.im : tau * (p.l2 - p.l1);  // τ |λ₁ − λ₂|
  if (gap >= 0.5) {
    // Well separated: D_j = (φ_j(τλ₁) − φ_j(τλ₂)) / (λ₁ − λ₂); cancellation is bounded by the gap.
    if (p.complex) {
      Cx phi[kMaxPhi + 1];
      PhiComplex({tau * p.re, tau * p.im}, phi);
      const double inv = 1.0 / p.im;
      for (int j = 0; j <= kMaxPhi; ++j) d[j] = phi[j].im * inv;
      const Cx lam{p.re, p.im}, e = phi[0];
      out.e11 = Mul(lam, Cx{e.re, -e.im}).im * inv;
      out.e22 = Mul(lam, e).im * inv;
    } else {
      double f1[kMaxPhi + 1], f2[kMaxPhi + 1];
      PhiReal(tau * p.l1, f1);
      PhiReal(tau * p.l2, f2);
      const double inv = 1.0 / (p.l1 - p.l2);
      for (int j = 0; j <= kMaxPhi; ++j) d[j] = (f1[j] - f2[j]) * inv;
      out.e11 = (p.l1 * f2[0] - p.l2 * f1[0]) * inv;
      out.e22 = (p.l1 * f1[0] - p.l2 * f2[0]) * inv;
    }
    out.e12 = d[0];
    out.e21 = -p.omega2 * d[0];
    return;
  }
  // Close roots away from the origin (near-critical damping, |τ m| > 0.75 with m = −c/2):
  // e^{τA} = e^{τm} (C I + S τ (A − m I)), C = cosh(τ g/2), S = sinh(τ g/2)/(τ g/2) (cos / sinc
  // when complex), and the upward recurrence D_j = (D_{j−1}/τ − avg_j)/m, avg_j = (φ_j(τλ₁) +
  // φ_j(τλ₂))/2, from (λ φ_j(τλ))[λ₁, λ₂] = m D_j + avg_j; its error factor 1/|τm| is < 4/3.
  const double m = -0.5 * p.c;
  const double y = 0.5 * gap;
  const double em = tau * m > -745.0 ? std::exp(tau * m) : 0.0;
  double C, S;
  double avg[kMaxPhi + 1];
  if (p.complex) {
    C = std::cos(y);
    S = y > 0 ? std::sin(y) / y : 1.0;
    Cx phi[kMaxPhi + 1];
    PhiComplex({tau * p.re, tau * p.im}, phi);
    for (int j = 0; j <= kMaxPhi; ++j) avg[j] = phi[j].re;
  } else {
    C = std::cosh(y);
    S = y > 0 ? std::sinh(y) / y : 1.0;
    double f1[kMaxPhi + 1], f2[kMaxPhi + 1];
    PhiReal(tau * p.l1, f1);
    PhiReal(tau * p.l2, f2);
    for (int j = 0; j <= kMaxPhi; ++j) avg[j] = 0.5 * (f1[j] + f2[j]);
  }
  d[0] = tau * em * S;
  out.e11 = em * (C - tau * m * S);
  out.e22 = em * (C + tau * m * S);
  out.e12 = d[0];
  out.e21 = -p.omega2 * d[0];
  const double inv_m = 1.0 / m, inv_tau = 1.0 / tau;
  for (int j = 1; j <= kMaxPhi; ++j) d[j] = (d[j - 1] * inv_tau - avg[j]) * inv_m;
}

namespace {

// φ_0 … φ_6 at x by e^x and the upward recurrence φ_j = (φ_{j−1} − 1/(j−1)!)/x, as PhiReal for
// |x| ≥ 1 without its branch. e^x by ExpReduced (within 2 ulp of std::exp), and 0 below x = −700,
// where PhiReal's e^x < 1e-304 leaves nothing in the recurrence. The caller selects it for |x| ≥ 1.
inline void PhiUpward(double x, double* up) {
  const double inv = 1.0 / x;
  const double e = ExpReduced(x < -700.0 ? -700.0 : x);
  up[0] = x < -700.0 ? 0.0 : e;
  for (int j = 1; j <= kMaxPhi; ++j) up[j] = (up[j - 1] - kInvFact[j - 1]) * inv;
}

// φ_0 … φ_6 at xs[0 … n) into phi[j · stride + i] for |x| ≥ 1 (PhiUpward).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void PhiRealLargeBatch(int n, const double* __restrict xs, double* __restrict phi, int stride) {
  for (int i = 0; i < n; ++i) {
    double up[kMaxPhi + 1];
    PhiUpward(xs[i], up);
    for (int j = 0; j <= kMaxPhi; ++j) phi[j * stride + i] = up[j];
  }
}

// The same for x of any size, as PhiReal without its branches: for |x| < 1 the Taylor series of φ_6
// to x^14 and the downward recurrence, otherwise PhiUpward; both computed, one selected.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void PhiRealBatch(int n, const double* __restrict xs, double* __restrict phi, int stride) {
  for (int i = 0; i < n; ++i) {
    const double x = xs[i];
    const bool small = (x < 1.0) & (x > -1.0);
    double p = kInvFact[kMaxPhi + 14];
    for (int m = 13; m >= 0; --m) p = p * x + kInvFact[m + kMaxPhi];
    double down[kMaxPhi + 1];
    down[kMaxPhi] = p;
    for (int j = kMaxPhi; j >= 1; --j) down[j - 1] = x * down[j] + kInvFact[j - 1];
    double up[kMaxPhi + 1];
    PhiUpward(small ? 2.0 : x, up);  // any |x| ≥ 1 keeps the unselected lanes finite
    for (int j = 0; j <= kMaxPhi; ++j) phi[j * stride + i] = small ? down[j] : up[j];
  }
}

}  // namespace

void DiscretiseBatch(int n, const ModePoles* poles, double tau, ModeStep* out, double* scratch,
                     int* idx) {
  // The batch: real roots, τ|λ₁| > 1, gap ≥ 0.5 (Discretise's "well separated" real branch). Its
  // modes' indices go to `idx`, τλ₁ and τλ₂ side by side to `xs`.
  double* xs = scratch;  // 2n: τλ₁ of the batch, then τλ₂
  int nb = 0;
  for (int i = 0; i < n; ++i) {
    const ModePoles& p = poles[i];
    const bool batch = !p.complex && -tau * p.l1 > 1.0 && tau * (p.l2 - p.l1) >= 0.5;
    if (batch) {
      idx[nb++] = i;
    } else {
      Discretise(p, tau, out[i]);
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
