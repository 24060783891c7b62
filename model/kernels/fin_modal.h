/* The bimorph fin's modal recursion (spec "bimorph-fin model" section 6): each mode's exact
 * discretisation, the closed-form Bouc-Wen branches and their zero crossings, the quintic Hermite
 * hold of z, one mode's update, the walk of one sample, the atan series and the backlash step. The
 * one source of the fin's step: model/modal_simulator.cc runs it (its sampled path's walk and
 * sub-steps, both paths' discretisation), as do the records family's kernel (bimorph_fin.h) and the
 * HGANN fin plant of `piezoid export --plant` (controller/fin_plant.h, after this file in its
 * header). Guarded, so that both kinds of header can be included in one translation unit.
 *
 * The discretisation. Mode i is  eta'' + c eta' + omega^2 eta = f(t),  x = [eta, eta']^T,
 * x' = A x + b f,  A = [[0, 1], [-omega^2, -c]],  b = [0, 1]^T. Over a step tau with a polynomial
 * input f(t0 + s) = sum_j f_j s^j / j!,
 *   x(tau) = E x(0) + sum_j f_j tau^{j+1} phi_{j+1}(tau A) b,   E = e^{tau A},
 *   tau^{j+1} phi_{j+1}(tau A) b = [tau^{j+1} D_{j+1}, tau^j D_j]^T,
 * D_j = phi_j(tau .)[l1, l2] (the divided difference), phi_0(z) = e^z, phi_j(z) = sum_m z^m /
 * (m + j)!, l1, l2 the roots of l^2 + c l + omega^2 = 0. The D_j and E are computed without
 * cancellation in every regime the plant reaches: underdamped (delta = 0, nearly undamped upper
 * modes), overdamped with a huge root ratio (delta > 0: l1 ~ -delta omega^2 down to -1e10 1/s,
 * l2 ~ -1/delta), near-critical (l1 ~ l2) and tiny steps (|tau l| << 1): a few ulps of the
 * entries' scale (tests/model/golden_test.cc holds them to the spec's golden vectors). */
#ifndef PZK_FIN_MODAL_H_
#define PZK_FIN_MODAL_H_
typedef struct {
  double re, im;
} pzk_fin_cx;
typedef struct {
  double omega2, c, l1, l2, re, im;
  int complex_pair;
} pzk_fin_poles;
typedef struct {
  double e11, e12, e21, e22, d[7];
} pzk_fin_step_t;
typedef struct {
  double alpha, kappa, u0, z0, gain;
  int s, sigma;
} pzk_fin_branch;
typedef struct {
  double z, zd, zdd;
} pzk_fin_zdata;

static inline int pzk_fin_sign(double x) { return (x > 0) - (x < 0); }
static inline double pzk_fin_min(double a, double b) { return (b < a) ? b : a; }
static inline double pzk_fin_max(double a, double b) { return (a < b) ? b : a; }

/* 1/n!, n = 0 ... 24. */
static inline const double *pzk_fin_inv_fact(void) {
  static const double f[25] = {1.0,
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
                               1.0 / 620448401733239439360000.0};
  return f;
}

static inline pzk_fin_cx pzk_fin_cmul(pzk_fin_cx a, pzk_fin_cx b) {
  pzk_fin_cx r;
  r.re = a.re * b.re - a.im * b.im;
  r.im = a.re * b.im + a.im * b.re;
  return r;
}

/* phi_0 ... phi_6 at a real x. |x| < 1: the Taylor terms of phi_6 up to x^N with |x|^{N+1} 6! /
 * (N+7)! < 2^-53 (N = 7, 9, 14 for |x| <= 1/16, 1/4, 1), then the stable downward recurrence
 * phi_{j-1} = x phi_j + 1/(j-1)!; otherwise upward from e^x (0 below -745, where it underflows). */
static inline void pzk_fin_phi_real(double x, double *phi) {
  const double *f = pzk_fin_inv_fact();
  const double ax = fabs(x);
  int j, m;
  if (ax < 1.0) {
    const int top = ax <= 0.0625 ? 7 : (ax <= 0.25 ? 9 : 14);
    double p = f[6 + top];
    for (m = top - 1; m >= 0; --m) p = p * x + f[m + 6];
    phi[6] = p;
    for (j = 6; j >= 1; --j) phi[j - 1] = x * phi[j] + f[j - 1];
    return;
  }
  phi[0] = x > -745.0 ? exp(x) : 0.0;
  {
    const double inv = 1.0 / x;
    for (j = 1; j <= 6; ++j) phi[j] = (phi[j - 1] - f[j - 1]) * inv;
  }
}

/* phi_0 ... phi_6 at a complex x: |x| < 1 the series of phi_6 and the downward recurrence,
 * otherwise upward from e^x (error factor 1/|x| <= 1 per step). */
static inline void pzk_fin_phi_complex(pzk_fin_cx x, pzk_fin_cx *phi) {
  const double *f = pzk_fin_inv_fact();
  const double r2 = x.re * x.re + x.im * x.im;
  int j, m;
  if (r2 < 1.0) {
    pzk_fin_cx p;
    p.re = f[6 + 16];
    p.im = 0.0;
    for (m = 15; m >= 0; --m) {
      p = pzk_fin_cmul(p, x);
      p.re += f[m + 6];
    }
    phi[6] = p;
    for (j = 6; j >= 1; --j) {
      pzk_fin_cx q = pzk_fin_cmul(x, phi[j]);
      q.re += f[j - 1];
      phi[j - 1] = q;
    }
    return;
  }
  if (x.re > -745.0) {
    const double e = exp(x.re);
    phi[0].re = e * cos(x.im);
    phi[0].im = e * sin(x.im);
  } else {
    phi[0].re = 0.0;
    phi[0].im = 0.0;
  }
  {
    const double n = x.re * x.re + x.im * x.im;
    pzk_fin_cx inv;
    inv.re = x.re / n;
    inv.im = -x.im / n;
    for (j = 1; j <= 6; ++j) {
      pzk_fin_cx q = phi[j - 1];
      q.re -= f[j - 1];
      phi[j] = pzk_fin_cmul(q, inv);
    }
  }
}

/* Roots of l^2 + c l + omega2 = 0 for c >= 0, omega2 >= 0, without cancellation for c >> omega or
 * c ~ 2 omega: a complex pair re +- i im (im > 0), or real l1 <= l2 <= 0 (l1 the larger in
 * magnitude, l2 = omega2 / l1). */
static inline pzk_fin_poles pzk_fin_make_poles(double omega2, double c) {
  pzk_fin_poles p;
  const double w = sqrt(omega2);
  const double disc = (c - 2 * w) * (c + 2 * w);
  p.omega2 = omega2;
  p.c = c;
  p.l1 = p.l2 = p.re = p.im = 0.0;
  p.complex_pair = disc < 0;
  if (disc < 0) {
    p.re = -0.5 * c;
    p.im = 0.5 * sqrt(-disc);
  } else {
    p.l1 = -0.5 * (c + sqrt(disc));
    p.l2 = p.l1 != 0.0 ? omega2 / p.l1 : 0.0;
  }
  return p;
}

/* Small |tau lambda| (rho <= 1): D_j = tau sum_m k_m / (m + 1 + j)!, k_m = tau^m h_m with the
 * complete homogeneous polynomials h_m(l1, l2) = s h_{m-1} - p h_{m-2} (s = -c, p = omega2), all
 * real; D_6, D_5 from the series, the rest by the stable downward recurrence. */
static inline void pzk_fin_series(const pzk_fin_poles *p, double tau, pzk_fin_step_t *out) {
  const double *f = pzk_fin_inv_fact();
  const double ts = -p->c * tau, tp = p->omega2 * tau * tau;
  double km2 = 0.0, km1 = 1.0, s6 = 0.0, s5 = 0.0;
  double *d = out->d;
  int m, j;
  for (m = 0; m <= 17; ++m) {
    const double k = m == 0 ? 1.0 : ts * km1 - tp * km2;
    if (m > 0) {
      km2 = km1;
      km1 = k;
    }
    s6 += k * f[m + 1 + 6];
    s5 += k * f[m + 6];
  }
  d[6] = tau * s6;
  d[5] = tau * s5;
  for (j = 5; j >= 1; --j) d[j - 1] = tau * f[j] - p->c * tau * d[j] - tp * d[j + 1];
  out->e11 = 1.0 - p->omega2 * tau * d[1];
  out->e12 = d[0];
  out->e21 = -p->omega2 * d[0];
  out->e22 = out->e11 - p->c * d[0];
}

/* One mode over a step tau >= 0: E = e^{tau A} and the divided differences D_0 ... D_6. Well
 * separated roots (tau |l1 - l2| >= 0.5): D_j = (phi_j(tau l1) - phi_j(tau l2)) / (l1 - l2), the
 * cancellation bounded by the gap. Close roots away from the origin (near-critical damping,
 * m = -c/2): e^{tau A} = e^{tau m} (C I + S tau (A - m I)), C = cosh(tau g/2), S = sinh(tau g/2) /
 * (tau g/2) (cos / sinc when complex), and the upward recurrence D_j = (D_{j-1}/tau - avg_j)/m,
 * avg_j = (phi_j(tau l1) + phi_j(tau l2))/2; its error factor 1/|tau m| is < 4/3. */
static inline void pzk_fin_discretise(const pzk_fin_poles *p, double tau, pzk_fin_step_t *out) {
  double *d = out->d;
  double rho, gap, m, y, em, C, S, inv_m, inv_tau;
  double avg[7];
  int j;
  if (!(tau > 0)) {
    out->e11 = 1;
    out->e12 = out->e21 = 0;
    out->e22 = 1;
    for (j = 0; j <= 6; ++j) d[j] = 0;
    return;
  }
  rho = p->complex_pair ? tau * sqrt(p->omega2) : -tau * p->l1;
  if (rho <= 1.0) {
    pzk_fin_series(p, tau, out);
    return;
  }
  gap = p->complex_pair ? 2 * tau * p->im : tau * (p->l2 - p->l1);
  if (gap >= 0.5) {
    if (p->complex_pair) {
      pzk_fin_cx phi[7], x, lam, e, ec;
      double inv;
      x.re = tau * p->re;
      x.im = tau * p->im;
      pzk_fin_phi_complex(x, phi);
      inv = 1.0 / p->im;
      for (j = 0; j <= 6; ++j) d[j] = phi[j].im * inv;
      lam.re = p->re;
      lam.im = p->im;
      e = phi[0];
      ec.re = e.re;
      ec.im = -e.im;
      out->e11 = pzk_fin_cmul(lam, ec).im * inv;
      out->e22 = pzk_fin_cmul(lam, e).im * inv;
    } else {
      double f1[7], f2[7], inv;
      pzk_fin_phi_real(tau * p->l1, f1);
      pzk_fin_phi_real(tau * p->l2, f2);
      inv = 1.0 / (p->l1 - p->l2);
      for (j = 0; j <= 6; ++j) d[j] = (f1[j] - f2[j]) * inv;
      out->e11 = (p->l1 * f2[0] - p->l2 * f1[0]) * inv;
      out->e22 = (p->l1 * f1[0] - p->l2 * f2[0]) * inv;
    }
    out->e12 = d[0];
    out->e21 = -p->omega2 * d[0];
    return;
  }
  m = -0.5 * p->c;
  y = 0.5 * gap;
  em = tau * m > -745.0 ? exp(tau * m) : 0.0;
  if (p->complex_pair) {
    pzk_fin_cx phi[7], x;
    C = cos(y);
    S = y > 0 ? sin(y) / y : 1.0;
    x.re = tau * p->re;
    x.im = tau * p->im;
    pzk_fin_phi_complex(x, phi);
    for (j = 0; j <= 6; ++j) avg[j] = phi[j].re;
  } else {
    double f1[7], f2[7];
    C = cosh(y);
    S = y > 0 ? sinh(y) / y : 1.0;
    pzk_fin_phi_real(tau * p->l1, f1);
    pzk_fin_phi_real(tau * p->l2, f2);
    for (j = 0; j <= 6; ++j) avg[j] = 0.5 * (f1[j] + f2[j]);
  }
  d[0] = tau * em * S;
  out->e11 = em * (C - tau * m * S);
  out->e22 = em * (C + tau * m * S);
  out->e12 = d[0];
  out->e21 = -p->omega2 * d[0];
  inv_m = 1.0 / m;
  inv_tau = 1.0 / tau;
  for (j = 1; j <= 6; ++j) d[j] = (d[j - 1] * inv_tau - avg[j]) * inv_m;
}

/* Bouc-Wen branch from (u0, z0) moving in the direction of s (model/bouc_wen.h StartBranch,
 * BoucWenBranch::Z, ::ZeroCrossing). */
static inline pzk_fin_branch pzk_fin_start_branch(double alpha, double beta, double gamma,
                                                  double u0, double z0, double s) {
  pzk_fin_branch b;
  b.alpha = alpha;
  b.u0 = u0;
  b.z0 = z0;
  b.s = pzk_fin_sign(s);
  b.sigma = z0 != 0.0 ? pzk_fin_sign(z0) : pzk_fin_sign(alpha) * b.s;
  b.kappa = beta * b.s + gamma * b.sigma;
  b.gain = b.kappa != 0.0 ? (b.kappa * z0 - alpha) / b.kappa : 0.0;
  return b;
}

static inline double pzk_fin_expm1(double x) { /* FastExpm1 */
  if (fabs(x) < 1e-3) return x * (1.0 + x * (0.5 + x * (1.0 / 6 + x * (1.0 / 24))));
  return exp(x) - 1.0;
}

static inline double pzk_fin_branch_z(const pzk_fin_branch *b, double u) {
  const double du = u - b->u0;
  return b->kappa == 0.0 ? b->z0 + b->alpha * du : b->z0 + b->gain * pzk_fin_expm1(-b->kappa * du);
}

/* 0 when z provably does not reach 0 on branch b before the input ub: then pzk_fin_zero_crossing
 * would give a crossing beyond ub (or none), which pzk_fin_sample ignores, so it is skipped (its
 * log1p and three divisions at every sample of a branch heading for zero). The bound: with
 * y = -kappa z0 / alpha, |u_cross - u0| = |z0 / alpha| log1p(y) / y >= |z0| / (|alpha| (1 +
 * max(y, 0))) (log1p(y) >= y / (1 + y)); the reach asked is |ub - u0| with a margin (1e-6 of it and
 * 1e-12 of |u|) far above the roundings of the crossing and of the sub-step's ends. Not a number or
 * overflow: 1 (pzk_fin_zero_crossing decides). */
static inline int pzk_fin_crossing_may_lie(const pzk_fin_branch *b, double ub) {
  const double ay = -b->kappa * b->z0 * (b->alpha > 0 ? 1.0 : -1.0); /* |alpha| y */
  const double reach = fabs(ub - b->u0) * (1 + 1e-6) + 1e-12 * (fabs(b->u0) + fabs(ub));
  return !(fabs(b->z0) > (fabs(b->alpha) + pzk_fin_max(0.0, ay)) * reach);
}

static inline int pzk_fin_zero_crossing(const pzk_fin_branch *b, double *u_cross) {
  double y, ratio, du;
  if (b->z0 == 0.0 || b->alpha == 0.0 || b->s == 0 || b->alpha * b->s * b->sigma >= 0) return 0;
  y = -b->kappa * b->z0 / b->alpha;
  if (!(y > -1.0)) return 0;
  ratio = fabs(y) < 1e-12 ? 1.0 - 0.5 * y : log1p(y) / y;
  du = (-b->z0 / b->alpha) * ratio;
  if (!isfinite(du)) return 0;
  *u_cross = b->u0 + du;
  return 1;
}

/* z, dz/dt, d2z/dt2 on a branch at input u moving at ud (ramp: u'' = 0; modal_simulator.cc EvalZ
 * with a u''). */
static inline pzk_fin_zdata pzk_fin_eval_z(double alpha, const pzk_fin_branch *b, double u,
                                           double ud) {
  pzk_fin_zdata r;
  if (alpha == 0.0) {
    r.z = r.zd = r.zdd = 0.0;
    return r;
  }
  r.z = pzk_fin_branch_z(b, u);
  {
    const double sl = b->alpha - b->kappa * r.z;
    r.zd = sl * ud;
    r.zdd = sl * (0.0 - b->kappa * ud * ud);
  }
  return r;
}

/* Sub-steps of a sample whose drive moves at r (SubstepsFor): kappa_max |r| tau <= 0.5 each. */
static inline int pzk_fin_substeps(int hysteresis, double kappa_max, double r, double tau) {
  if (hysteresis) {
    const double arg = kappa_max * fabs(r) * tau;
    if (arg > 0.5) {
      const double m = ceil(arg / 0.5);
      return m >= 1000 ? 1000 : (int)m;
    }
  }
  return 1;
}

/* The force's Taylor coefficients over a sub-step tau: z held by the quintic Hermite of (zl, zr)
 * (a_j of p(s) = sum a_j s^j on [0, 1] from [z0, tau z0', tau^2 z0'', z1, tau z1', tau^2 z1''],
 * times j!: the discretisation's convention). */
static inline void pzk_fin_hermite(double tau, pzk_fin_zdata zl, pzk_fin_zdata zr, double *fz) {
  static const double hermite[6][6] = {{1, 0, 0, 0, 0, 0},       {0, 1, 0, 0, 0, 0},
                                       {0, 0, 0.5, 0, 0, 0},     {-10, -6, -1.5, 10, -4, 0.5},
                                       {15, 8, 1.5, -15, 7, -1}, {-6, -3, -0.5, 6, -3, 0.5}};
  static const double fact[6] = {1, 1, 2, 6, 24, 120};
  double dat[6];
  int j, k;
  dat[0] = zl.z;
  dat[1] = tau * zl.zd;
  dat[2] = tau * tau * zl.zdd;
  dat[3] = zr.z;
  dat[4] = tau * zr.zd;
  dat[5] = tau * tau * zr.zdd;
  for (j = 0; j < 6; ++j) {
    double a = 0;
    for (k = 0; k < 6; ++k) a += hermite[j][k] * dat[k];
    fz[j] = a * fact[j];
  }
}

/* One mode's state (x0, x1) over a sub-step tau with step sp, tip gains wu, wz, the force's
 * coefficients fz and the drive u_a + u_dot s. modal_simulator.cc SampledRun does it four modes a
 * vector, operation for operation (the same bits). */
static inline void pzk_fin_mode_update(const pzk_fin_step_t *sp, double wu, double wz,
                                       const double *fz, double u_a, double u_dot, double tau,
                                       double *x0, double *x1) {
  double f[6], s0 = 0, s1 = 0, a, b;
  int j;
  for (j = 0; j < 6; ++j) f[j] = -wz * fz[j];
  f[0] += wu * u_a;
  f[1] += wu * (u_dot * tau);
  for (j = 0; j < 6; ++j) {
    s0 += f[j] * sp->d[j + 1];
    s1 += f[j] * sp->d[j];
  }
  a = *x0;
  b = *x1;
  *x0 = sp->e11 * a + sp->e12 * b + tau * s0;
  *x1 = sp->e21 * a + sp->e22 * b + s1;
}

/* One sub-step of pzk_fin_sample's walk: tau long, the drive u_a + u_dot s, z held by the quintic
 * Hermite of (zl, zr). regular != 0: one of the sample's nsub equal sub-steps (tau = the sample /
 * nsub: a discretisation the caller holds); 0: a piece cut at a zero crossing of z (discretised for
 * tau). */
typedef void (*pzk_fin_substep_fn)(void *ctx, double tau, int regular, pzk_fin_zdata zl,
                                   pzk_fin_zdata zr, double u_a, double u_dot);

/* One sample of the fin's drive from u0 (Bouc-Wen force z0) to v over tau, u linear between them,
 * in nsub sub-steps (pzk_fin_substeps), each cut where z crosses zero: the modes advance through
 * `substep` (ctx its data); returns z at the sample's end. The one walk of ModalSimulator's sampled
 * path (its pass 1 lists the sub-steps), the records kernel (bimorph_fin.h pzk_fin_step) and the
 * HGANN fin header (controller/fin_plant.h pzf_advance). */
static inline double pzk_fin_sample(double alpha, double beta, double gamma, double u0, double z0,
                                    double v, double tau, int nsub, pzk_fin_substep_fn substep,
                                    void *ctx) {
  const double r = (v - u0) / tau, ts = tau / nsub, eps = 1e-9 * ts;
  const int hyst = alpha != 0.0;
  int q;
  double sa = 0.0;
  pzk_fin_branch br = pzk_fin_start_branch(alpha, beta, gamma, u0, z0, r);
  pzk_fin_zdata dcur = pzk_fin_eval_z(alpha, &br, u0, r);
  for (q = 0; q < nsub; ++q) {
    const int last = q + 1 == nsub;
    const double sb = last ? tau : (q + 1) * ts;
    const double ub = last ? v : u0 + r * sb;
    int split = 0;
    double uc;
    pzk_fin_zdata dr;
    if (hyst && pzk_fin_crossing_may_lie(&br, ub) && pzk_fin_zero_crossing(&br, &uc)) {
      const double sc = (uc - u0) / r;
      if (sc < sb - eps) {
        if (sc > sa + eps) {
          substep(ctx, sc - sa, 0, dcur, pzk_fin_eval_z(alpha, &br, uc, r), u0 + r * sa, r);
          split = 1;
          sa = sc;
        }
        br = pzk_fin_start_branch(alpha, beta, gamma, uc, 0.0, r);
        dcur = pzk_fin_eval_z(alpha, &br, uc, r);
      }
    }
    dr = pzk_fin_eval_z(alpha, &br, ub, r);
    substep(ctx, sb - sa, !split, dcur, dr, u0 + r * sa, r);
    dcur = dr;
    sa = sb;
  }
  return dcur.z;
}

/* Fin angle [deg] of the modal states x0 (scaled by tip_i: w_tip = their sum) for a fin of length
 * 1/inv_length (modal_simulator.cc SumModes in lanes of 4, Degrees / FastAtan / AtanSeries). */
static inline double pzk_fin_angle(const double *x0, int n, double inv_length, int *finite) {
  double s[4] = {0, 0, 0, 0}, w, x;
  int i;
  for (i = 0; i < n; ++i) s[i % 4] += x0[i];
  w = (s[0] + s[1]) + (s[2] + s[3]);
  *finite = isfinite(w);
  x = w * inv_length;
  if (fabs(x) < 0.125) {
    static const double k[10] = {1.0,       -1.0 / 3, 1.0 / 5,   -1.0 / 7, 1.0 / 9,
                                 -1.0 / 11, 1.0 / 13, -1.0 / 15, 1.0 / 17, -1.0 / 19};
    const double x2 = x * x, x4 = x2 * x2, x8 = x4 * x4, x16 = x8 * x8;
    const double p01 = k[0] + k[1] * x2, p23 = k[2] + k[3] * x2, p45 = k[4] + k[5] * x2;
    const double p67 = k[6] + k[7] * x2, p89 = k[8] + k[9] * x2;
    const double p = (p01 + p23 * x4) + (p45 + p67 * x4) * x8 + p89 * x16;
    return x * p * (180.0 / 3.14159265358979323846);
  }
  return atan(x) * (180.0 / 3.14159265358979323846);
}

/* The backlash step (model/backlash.h BacklashStep): dead band a1, a2, saturations b1 > 0 > b2. */
static inline double pzk_fin_backlash(double a1, double a2, double b1, double b2, double theta,
                                      double y_prev) {
  const double a = pzk_fin_min(b1, pzk_fin_max(b2, theta - a1));
  const double b = pzk_fin_min(b1, theta + a2);
  return pzk_fin_max(a, pzk_fin_min(b, y_prev));
}

/* The drive u in [lo, hi] with g(ctx, u) = 0 nearest to u0, g not necessarily monotone: the bracket
 * is searched on both sides of u0 with steps growing 4-fold from 1e-3 of the range, the first sign
 * change taken, then closed by the Illinois method until |g| <= tol or the bracket is two adjacent
 * doubles; at most max_trials evaluations of g. Returns 1 when bracketed (else the limits hold no
 * sign change); *u_best: the u of the smallest |g| seen. The fin's compensators (the records
 * chain's pzk_chain_inverse_fin and the HGANN fin header's inverse step) both use it. */
typedef double (*pzk_fin_map)(void *ctx, double u);
static inline int pzk_fin_nearest_root(pzk_fin_map g, void *ctx, double u0, double lo, double hi,
                                       double tol, int max_trials, double *u_best) {
  double a, b, ga, gb, l, r, gl, gr, step, best_u, best_g;
  int it, side = 0, found;
  best_u = a = b = l = r = u0;
  best_g = ga = gb = gl = gr = g(ctx, u0);
  found = best_g == 0;
  step = 1e-3 * (hi - lo);
  for (it = 1; !found && it < max_trials && (l > lo || r < hi); step *= 4) {
    int left;
    for (left = 0; left < 2 && !found; ++left) {
      const double from = left ? l : r, gfrom = left ? gl : gr;
      double to, gto;
      if (left ? from <= lo : from >= hi) continue;
      to = left ? from - step : from + step;
      to = to > hi ? hi : (to < lo ? lo : to);
      gto = g(ctx, to);
      ++it;
      if (fabs(gto) < fabs(best_g)) {
        best_u = to;
        best_g = gto;
      }
      if (gto == 0 || (gto < 0) != (gfrom < 0)) {
        a = from;
        ga = gfrom;
        b = to;
        gb = gto;
        found = 1;
      } else if (left) {
        l = to;
        gl = gto;
      } else {
        r = to;
        gr = gto;
      }
    }
  }
  if (found) {
    for (; it < max_trials && fabs(best_g) > tol; ++it) { /* Illinois on [a, b] */
      double c = (a * gb - b * ga) / (gb - ga), gc;
      const double cl = a < b ? a : b, cr = a < b ? b : a;
      if (!(c > cl && c < cr)) c = 0.5 * (a + b);
      if (!(c > cl && c < cr)) break; /* the bracket is two adjacent doubles */
      gc = g(ctx, c);
      if (fabs(gc) < fabs(best_g)) {
        best_u = c;
        best_g = gc;
      }
      if (gc == 0) break;
      if ((gc < 0) == (gb < 0)) {
        b = c;
        gb = gc;
        if (side == -1) ga *= 0.5;
        side = -1;
      } else {
        a = c;
        ga = gc;
        if (side == 1) gb *= 0.5;
        side = 1;
      }
    }
  }
  *u_best = best_u;
  return found;
}

#endif /* PZK_FIN_MODAL_H_ */
