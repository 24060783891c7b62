#include "client/export_fin_c.h"

#include <cmath>
#include <cstdio>
#include <numbers>
#include <sstream>

namespace pz::client {
namespace {

// The C text of the plant with "pzf_" / "PZF_" for the header's name and prefix, and @TABLES@ for
// the plant's constants. Each function names the C++ it mirrors; keep them in step.
constexpr const char* kPlant = R"C(
/* ======================================================================================== */
/* The fin plant: ModalSimulator's sampled-drive recursion (u linear between samples), one   */
/* sample period PZF_DT at a time.                                                           */
/* ======================================================================================== */

/* Status bits: returned by pzf_params / pzf_init, accumulated in state.status. */
#define PZF_OK 0
#define PZF_AMPLITUDE_OUT_OF_RANGE 1   /* amplitude outside the training range: p extrapolated */
#define PZF_FREQUENCY_OUT_OF_RANGE 2   /* frequency outside the training range: p extrapolated */
#define PZF_INVALID_INPUT 4            /* a non-finite input (ignored: the drive is held) */
#define PZF_INVALID_PARAMETERS 8       /* init: a parameter non-finite or out of its physical range */
#define PZF_UNBOUNDED_HYSTERESIS 16    /* init: alpha != 0 and not (beta + gamma > 0, beta - gamma >= 0) */
#define PZF_NOT_FINITE 32              /* the state became non-finite (the step was not taken) */
#define PZF_UNREACHABLE 64             /* inverse: the desired angle was not reachable in one step */

@TABLES@
typedef struct { double re, im; } pzf_cx;
typedef struct { double omega2, c, l1, l2, re, im; int complex_pair; } pzf_poles;
typedef struct { double e11, e12, e21, e22, d[7]; } pzf_mode_step;
typedef struct { double alpha, kappa, u0, z0, gain; int s, sigma; } pzf_branch;
typedef struct { double z, zd, zdd; } pzf_zdata;

/* What one sample changes (saved and restored by the inverse's trial steps). */
typedef struct {
  double x0[PZF_MODES_PADDED], x1[PZF_MODES_PADDED]; /* modal states scaled by tip_i: w_tip = sum x0 */
  double u;      /* drive at the last sample [V] */
  double z;      /* Bouc-Wen force [N] */
  double theta;  /* linear fin angle atan(w_tip / L) [deg] */
  double y;      /* fin angle after the backlash [deg] */
} pzf_dynamic;

typedef struct {
  double mu, delta, alpha, beta, gamma, a1, a2, b1, b2, kappa_max;
  double u_min, u_max;         /* drive limits [V] (PZF_U_MIN, PZF_U_MAX; may be narrowed after init) */
  pzf_poles poles[PZF_MODES];
  pzf_mode_step full[PZF_MODES];  /* discretisation over PZF_DT */
  pzf_mode_step sub[PZF_MODES];   /* over PZF_DT / sub_n, cached */
  int sub_n;
  pzf_dynamic d;
  long samples;                /* steps taken */
  long saturations;            /* drives clipped to [u_min, u_max] */
  long unreachable;            /* inverse steps whose desired angle was out of reach (clipped) */
  long trials;                 /* the inverse's trials (PZF_INVERSE_HORIZON steps each) */
  int status;                  /* PZF_* bits seen since init */
} pzf_state;

static inline double pzf_min(double a, double b) { return (b < a) ? b : a; } /* std::min */
static inline double pzf_max(double a, double b) { return (a < b) ? b : a; } /* std::max */
static inline int pzf_sign(double x) { return (x > 0) - (x < 0); }

/* 1/n!, n = 0 ... 24 (modal_discretise.cc kInvFact). */
static inline const double* pzf_inv_fact(void) {
  static const double f[25] = {1.0, 1.0, 1.0 / 2, 1.0 / 6, 1.0 / 24, 1.0 / 120, 1.0 / 720, 1.0 / 5040,
      1.0 / 40320, 1.0 / 362880, 1.0 / 3628800, 1.0 / 39916800, 1.0 / 479001600, 1.0 / 6227020800.0,
      1.0 / 87178291200.0, 1.0 / 1307674368000.0, 1.0 / 20922789888000.0, 1.0 / 355687428096000.0,
      1.0 / 6402373705728000.0, 1.0 / 121645100408832000.0, 1.0 / 2432902008176640000.0,
      1.0 / 51090942171709440000.0, 1.0 / 1124000727777607680000.0, 1.0 / 25852016738884976640000.0,
      1.0 / 620448401733239439360000.0};
  return f;
}

static inline pzf_cx pzf_cmul(pzf_cx a, pzf_cx b) {
  pzf_cx r;
  r.re = a.re * b.re - a.im * b.im;
  r.im = a.re * b.im + a.im * b.re;
  return r;
}

/* phi_0 ... phi_6 at a real x (modal::PhiReal). */
static inline void pzf_phi_real(double x, double* phi) {
  const double* f = pzf_inv_fact();
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

/* phi_0 ... phi_6 at a complex x (modal_discretise.cc PhiComplex). */
static inline void pzf_phi_complex(pzf_cx x, pzf_cx* phi) {
  const double* f = pzf_inv_fact();
  const double r2 = x.re * x.re + x.im * x.im;
  int j, m;
  if (r2 < 1.0) {
    pzf_cx p;
    p.re = f[6 + 16];
    p.im = 0.0;
    for (m = 15; m >= 0; --m) {
      p = pzf_cmul(p, x);
      p.re += f[m + 6];
    }
    phi[6] = p;
    for (j = 6; j >= 1; --j) {
      pzf_cx q = pzf_cmul(x, phi[j]);
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
    pzf_cx inv;
    inv.re = x.re / n;
    inv.im = -x.im / n;
    for (j = 1; j <= 6; ++j) {
      pzf_cx q = phi[j - 1];
      q.re -= f[j - 1];
      phi[j] = pzf_cmul(q, inv);
    }
  }
}

/* Roots of l^2 + c l + omega2 = 0 (modal::MakePoles). */
static inline pzf_poles pzf_make_poles(double omega2, double c) {
  pzf_poles p;
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

/* Small |tau lambda| (modal_discretise.cc SeriesRegime). */
static inline void pzf_series(const pzf_poles* p, double tau, pzf_mode_step* out) {
  const double* f = pzf_inv_fact();
  const double ts = -p->c * tau, tp = p->omega2 * tau * tau;
  double km2 = 0.0, km1 = 1.0, s6 = 0.0, s5 = 0.0;
  double* d = out->d;
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

/* One mode over a step tau: E = e^{tau A} and the divided differences D_0 ... D_6 (modal::Discretise). */
static inline void pzf_discretise(const pzf_poles* p, double tau, pzf_mode_step* out) {
  double* d = out->d;
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
    pzf_series(p, tau, out);
    return;
  }
  gap = p->complex_pair ? 2 * tau * p->im : tau * (p->l2 - p->l1);
  if (gap >= 0.5) {
    if (p->complex_pair) {
      pzf_cx phi[7], x, lam, e, ec;
      double inv;
      x.re = tau * p->re;
      x.im = tau * p->im;
      pzf_phi_complex(x, phi);
      inv = 1.0 / p->im;
      for (j = 0; j <= 6; ++j) d[j] = phi[j].im * inv;
      lam.re = p->re;
      lam.im = p->im;
      e = phi[0];
      ec.re = e.re;
      ec.im = -e.im;
      out->e11 = pzf_cmul(lam, ec).im * inv;
      out->e22 = pzf_cmul(lam, e).im * inv;
    } else {
      double f1[7], f2[7], inv;
      pzf_phi_real(tau * p->l1, f1);
      pzf_phi_real(tau * p->l2, f2);
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
    pzf_cx phi[7], x;
    C = cos(y);
    S = y > 0 ? sin(y) / y : 1.0;
    x.re = tau * p->re;
    x.im = tau * p->im;
    pzf_phi_complex(x, phi);
    for (j = 0; j <= 6; ++j) avg[j] = phi[j].re;
  } else {
    double f1[7], f2[7];
    C = cosh(y);
    S = y > 0 ? sinh(y) / y : 1.0;
    pzf_phi_real(tau * p->l1, f1);
    pzf_phi_real(tau * p->l2, f2);
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

/* Bouc-Wen branch (model/bouc_wen.h StartBranch, BoucWenBranch::Z, ::ZeroCrossing). */
static inline pzf_branch pzf_start_branch(const pzf_state* st, double u0, double z0, double s) {
  pzf_branch b;
  b.alpha = st->alpha;
  b.u0 = u0;
  b.z0 = z0;
  b.s = pzf_sign(s);
  b.sigma = z0 != 0.0 ? pzf_sign(z0) : pzf_sign(st->alpha) * b.s;
  b.kappa = st->beta * b.s + st->gamma * b.sigma;
  b.gain = b.kappa != 0.0 ? (b.kappa * z0 - st->alpha) / b.kappa : 0.0;
  return b;
}

static inline double pzf_expm1(double x) { /* FastExpm1 */
  if (fabs(x) < 1e-3) return x * (1.0 + x * (0.5 + x * (1.0 / 6 + x * (1.0 / 24))));
  return exp(x) - 1.0;
}

static inline double pzf_branch_z(const pzf_branch* b, double u) {
  const double du = u - b->u0;
  return b->kappa == 0.0 ? b->z0 + b->alpha * du : b->z0 + b->gain * pzf_expm1(-b->kappa * du);
}

static inline int pzf_zero_crossing(const pzf_branch* b, double* u_cross) {
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

/* z, dz/dt, d2z/dt2 on a branch at input u moving at ud (modal_simulator.cc EvalZ; ramp: u'' = 0). */
static inline pzf_zdata pzf_eval_z(const pzf_state* st, const pzf_branch* b, double u, double ud) {
  pzf_zdata r;
  if (st->alpha == 0.0) {
    r.z = r.zd = r.zdd = 0.0;
    return r;
  }
  r.z = pzf_branch_z(b, u);
  {
    const double sl = b->alpha - b->kappa * r.z;
    r.zd = sl * ud;
    r.zdd = sl * (0.0 - b->kappa * ud * ud);
  }
  return r;
}

/* One sub-step tau of every mode, z held by the quintic Hermite of (zl, zr), u linear from u_a with
 * slope u_dot (modal_simulator.cc GeneralSubstep). steps == 0: discretised here for tau. */
static inline void pzf_substep(pzf_state* st, const pzf_mode_step* steps, double tau, pzf_zdata zl,
                               pzf_zdata zr, double u_a, double u_dot) {
  static const double hermite[6][6] = {{1, 0, 0, 0, 0, 0},           {0, 1, 0, 0, 0, 0},
                                       {0, 0, 0.5, 0, 0, 0},         {-10, -6, -1.5, 10, -4, 0.5},
                                       {15, 8, 1.5, -15, 7, -1},     {-6, -3, -0.5, 6, -3, 0.5}};
  static const double fact[6] = {1, 1, 2, 6, 24, 120};
  const double* wu = pzf_tip_gain_u();
  const double* wz = pzf_tip_gain_z();
  pzf_mode_step local[PZF_MODES];
  double dat[6], fz[6], fu0, fu1;
  int i, j, c;
  if (!(tau > 0)) return;
  if (!steps) {
    for (i = 0; i < PZF_MODES; ++i) pzf_discretise(&st->poles[i], tau, &local[i]);
    steps = local;
  }
  dat[0] = zl.z;
  dat[1] = tau * zl.zd;
  dat[2] = tau * tau * zl.zdd;
  dat[3] = zr.z;
  dat[4] = tau * zr.zd;
  dat[5] = tau * tau * zr.zdd;
  for (j = 0; j < 6; ++j) {
    double a = 0;
    for (c = 0; c < 6; ++c) a += hermite[j][c] * dat[c];
    fz[j] = a * fact[j];
  }
  fu0 = u_a;
  fu1 = u_dot * tau;
  for (i = 0; i < PZF_MODES; ++i) {
    const pzf_mode_step* sp = steps + i;
    double f[6], s0 = 0, s1 = 0, a, b;
    for (j = 0; j < 6; ++j) f[j] = -wz[i] * fz[j];
    f[0] += wu[i] * fu0;
    f[1] += wu[i] * fu1;
    for (j = 0; j < 6; ++j) {
      s0 += f[j] * sp->d[j + 1];
      s1 += f[j] * sp->d[j];
    }
    a = st->d.x0[i];
    b = st->d.x1[i];
    st->d.x0[i] = sp->e11 * a + sp->e12 * b + tau * s0;
    st->d.x1[i] = sp->e21 * a + sp->e22 * b + s1;
  }
}

/* Fin angle [deg] of the state (modal_simulator.cc SumModes, Degrees / FastAtan / AtanSeries). */
static inline double pzf_degrees(const pzf_state* st, int* finite) {
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0, w, x;
  int i;
  for (i = 0; i < PZF_MODES_PADDED; i += 4) {
    s0 += st->d.x0[i];
    s1 += st->d.x0[i + 1];
    s2 += st->d.x0[i + 2];
    s3 += st->d.x0[i + 3];
  }
  w = (s0 + s1) + (s2 + s3);
  *finite = isfinite(w);
  x = w * PZF_INV_LENGTH;
  if (fabs(x) < 0.125) {
    static const double k[10] = {1.0, -1.0 / 3, 1.0 / 5, -1.0 / 7, 1.0 / 9,
                                 -1.0 / 11, 1.0 / 13, -1.0 / 15, 1.0 / 17, -1.0 / 19};
    const double x2 = x * x, x4 = x2 * x2, x8 = x4 * x4, x16 = x8 * x8;
    const double p01 = k[0] + k[1] * x2, p23 = k[2] + k[3] * x2, p45 = k[4] + k[5] * x2;
    const double p67 = k[6] + k[7] * x2, p89 = k[8] + k[9] * x2;
    const double p = (p01 + p23 * x4) + (p45 + p67 * x4) * x8 + p89 * x16;
    return x * p * PZF_DEG_PER_RAD;
  }
  return atan(x) * PZF_DEG_PER_RAD;
}

/* The backlash step (model/backlash.h BacklashStep). */
static inline double pzf_backlash(const pzf_state* st, double theta, double y_prev) {
  const double a = pzf_min(st->b1, pzf_max(st->b2, theta - st->a1));
  const double b = pzf_min(st->b1, theta + st->a2);
  return pzf_max(a, pzf_min(b, y_prev));
}

/* One sample from the drive d.u to u1 (ModalSimulator::RunSampled's loop body); returns the angle. */
static inline double pzf_advance(pzf_state* st, double u1) {
  const double tau = PZF_DT, u0 = st->d.u;
  const double r = (u1 - u0) / tau;
  const int hyst = st->alpha != 0.0;
  int nsub = 1, q, finite;
  double ts, eps, sa = 0.0, theta;
  const pzf_mode_step* cached;
  pzf_branch br;
  pzf_zdata dcur;
  pzf_dynamic before = st->d;
  if (hyst) { /* SubstepsFor */
    const double arg = st->kappa_max * fabs(r) * tau;
    if (arg > 0.5) {
      const double m = ceil(arg / 0.5);
      nsub = m >= 1000 ? 1000 : (int)m;
    }
  }
  ts = tau / nsub;
  if (nsub == 1) {
    cached = st->full;
  } else {
    if (st->sub_n != nsub) {
      int i;
      for (i = 0; i < PZF_MODES; ++i) pzf_discretise(&st->poles[i], ts, &st->sub[i]);
      st->sub_n = nsub;
    }
    cached = st->sub;
  }
  eps = 1e-9 * ts;
  br = pzf_start_branch(st, u0, st->d.z, r);
  dcur = pzf_eval_z(st, &br, u0, r);
  for (q = 0; q < nsub; ++q) {
    const int last = q + 1 == nsub;
    const double sb = last ? tau : (q + 1) * ts;
    const double ub = last ? u1 : u0 + r * sb;
    int split = 0;
    double uc;
    pzf_zdata dr;
    if (hyst && pzf_zero_crossing(&br, &uc)) {
      const double sc = (uc - u0) / r;
      if (sc < sb - eps) {
        if (sc > sa + eps) {
          pzf_substep(st, 0, sc - sa, dcur, pzf_eval_z(st, &br, uc, r), u0 + r * sa, r);
          split = 1;
          sa = sc;
        }
        br = pzf_start_branch(st, uc, 0.0, r);
        dcur = pzf_eval_z(st, &br, uc, r);
      }
    }
    dr = pzf_eval_z(st, &br, ub, r);
    pzf_substep(st, split ? 0 : cached, sb - sa, dcur, dr, u0 + r * sa, r);
    dcur = dr;
    sa = sb;
  }
  theta = pzf_degrees(st, &finite);
  if (!finite) { /* the step is not taken */
    st->d = before;
    st->status |= PZF_NOT_FINITE;
    return st->d.y;
  }
  st->d.z = dcur.z;
  st->d.u = u1;
  st->d.theta = theta;
  st->d.y = pzf_backlash(st, theta, st->d.y);
  ++st->samples;
  return st->d.y;
}

/* The drive u clipped to [u_min, u_max] (counted); a non-finite u holds the last drive. */
static inline double pzf_clip(pzf_state* st, double u) {
  if (!isfinite(u)) {
    st->status |= PZF_INVALID_INPUT;
    return st->d.u;
  }
  if (u > st->u_max) {
    ++st->saturations;
    return st->u_max;
  }
  if (u < st->u_min) {
    ++st->saturations;
    return st->u_min;
  }
  return u;
}

/* theta PZF_INVERSE_HORIZON samples ahead when the drive goes to u at the next sample and keeps its
 * slope (clipped to the limits) after it; the state is left as it was. */
static inline double pzf_trial(pzf_state* st, double u) {
  const pzf_dynamic saved = st->d;
  const long n = st->samples;
  const double u0 = st->d.u;
  double th;
  int q;
  ++st->trials;
  for (q = 0; q < PZF_INVERSE_HORIZON; ++q) {
    double v = u + q * (u - u0);
    v = v > st->u_max ? st->u_max : (v < st->u_min ? st->u_min : v);
    pzf_advance(st, v);
  }
  th = st->d.theta;
  st->d = saved;
  st->samples = n;
  return th;
}

/* p[7] = the network's parameters for a drive amplitude_v sin(2 pi frequency_hz t); returns PZF_OK,
 * or PZF_AMPLITUDE_OUT_OF_RANGE | PZF_FREQUENCY_OUT_OF_RANGE when an input lies outside the training
 * range [PZF_AMPLITUDE_LO, PZF_AMPLITUDE_HI] x [PZF_FREQUENCY_LO, PZF_FREQUENCY_HI] (p is then the
 * network's extrapolation: do not trust it without checking), PZF_INVALID_INPUT for a non-finite
 * input (p untouched). */
static inline int pzf_params(double amplitude_v, double frequency_hz, double p[7]) {
  int status = PZF_OK;
  if (!isfinite(amplitude_v) || !isfinite(frequency_hz)) return PZF_INVALID_INPUT;
  if (!(amplitude_v >= PZF_AMPLITUDE_LO && amplitude_v <= PZF_AMPLITUDE_HI)) status |= PZF_AMPLITUDE_OUT_OF_RANGE;
  if (!(frequency_hz >= PZF_FREQUENCY_LO && frequency_hz <= PZF_FREQUENCY_HI)) status |= PZF_FREQUENCY_OUT_OF_RANGE;
  @NAME@(amplitude_v, frequency_hz, p);
  return status;
}

/* The state at rest (x = 0, z = 0) with the drive at u0 (clipped to the limits) and the fin's
 * saturations b1 > 0 > b2 [deg], for the parameters p (from pzf_params). Returns PZF_OK, or
 * PZF_INVALID_PARAMETERS / PZF_UNBOUNDED_HYSTERESIS (then pzf_step and pzf_inverse_step do nothing
 * and return the angle 0). The first angle (at u0) is pzf_angle(st). */
static inline int pzf_init(pzf_state* st, const double p[7], double b1, double b2, double u0) {
  const double* omega2 = pzf_omega2();
  int i, k, finite;
  for (i = 0; i < PZF_MODES_PADDED; ++i) st->d.x0[i] = st->d.x1[i] = 0.0;
  st->d.u = st->d.z = st->d.theta = st->d.y = 0.0;
  st->samples = st->saturations = st->unreachable = st->trials = 0;
  st->sub_n = 0;
  st->u_min = PZF_U_MIN;
  st->u_max = PZF_U_MAX;
  st->status = PZF_OK;
  st->mu = p[0];
  st->delta = p[1];
  st->alpha = p[2];
  st->beta = p[3];
  st->gamma = p[4];
  st->a1 = p[5];
  st->a2 = p[6];
  st->b1 = b1;
  st->b2 = b2;
  st->kappa_max = fabs(st->beta) + fabs(st->gamma);
  for (k = 0; k < 7; ++k)
    if (!isfinite(p[k])) st->status = PZF_INVALID_PARAMETERS;
  if (!isfinite(b1) || !isfinite(b2) || !isfinite(u0) || st->mu < 0 || st->delta < 0 || st->a1 < 0 ||
      st->a2 < 0 || !(b1 > 0) || !(b2 < 0))
    st->status = PZF_INVALID_PARAMETERS;
  if (st->status == PZF_OK && !(st->alpha == 0.0 || (st->beta + st->gamma > 0.0 && st->beta - st->gamma >= 0.0)))
    st->status = PZF_UNBOUNDED_HYSTERESIS;
  if (st->status != PZF_OK) return st->status;
  for (i = 0; i < PZF_MODES; ++i) {
    st->poles[i] = pzf_make_poles(omega2[i], st->mu + st->delta * omega2[i]);
    pzf_discretise(&st->poles[i], PZF_DT, &st->full[i]);
  }
  st->d.u = pzf_clip(st, u0);
  st->d.theta = pzf_degrees(st, &finite);
  st->d.y = pzf_backlash(st, st->d.theta, 0.0);
  return st->status;
}

/* The angle at the last sample [deg]. */
static inline double pzf_angle(const pzf_state* st) { return st->d.y; }

/* Forward: the drive u [V] at the next sample (clipped to [u_min, u_max]) -> the angle there [deg]. */
static inline double pzf_step(pzf_state* st, double u) {
  if (st->status & (PZF_INVALID_PARAMETERS | PZF_UNBOUNDED_HYSTERESIS)) return 0.0;
  return pzf_advance(st, pzf_clip(st, u));
}


/* Inverse: the drive u for the next sample that brings the angle to angle_desired PZF_INVERSE_HORIZON
 * samples after the current one, and the step taken with it (the state advances as pzf_step(st, u)
 * would; call it again at the next sample: receding horizon). Give it the reference that far ahead
 * if the controller knows it (preview); the reference at the next sample otherwise, with a lag of
 * PZF_INVERSE_HORIZON - 1 samples.
 *   The backlash is inverted exactly: moving up needs theta = y + a1, moving down theta = y - a2;
 * inside the dead band (angle_desired = the current angle) the theta nearest its course is kept.
 * theta(u) = target is solved on the horizon's map (drive ramped to u at the next sample, then
 * continuing its slope) by a bracket search on both sides of the last drive (the root nearest to
 * it) and the Illinois method: at most PZF_INVERSE_ITERATIONS trials of PZF_INVERSE_HORIZON steps
 * each, until theta is within 1e-13 deg (relative above 1 deg) or the bracket is two adjacent doubles.
 *   What it cannot do. It undoes no dynamics beyond its horizon: the drive's linear hold between
 * samples gives the sampled plant a zero outside the unit circle (the second sample's response to a
 * drive step is several times the first's), so an exact one-step inverse (horizon 1) makes the drive
 * oscillate; a horizon of 2 plans the next two samples and follows a reachable reference to a small
 * fraction of the dead band, not exactly (errors where the reference leaves the dead band or turns).
 * The plan is greedy: where the reference's state was reached by a path the plan did not take (the
 * Bouc-Wen force remembers it) a target can be out of reach for a few samples, and theta(u) need not
 * be monotone. docs/deploy.md has the figures. A target out of reach within [u_min, u_max], or an
 * angle outside [b2, b1], is clipped: the drive that came nearest is applied, and the step is
 * counted in st->unreachable (bit PZF_UNREACHABLE). */
static inline double pzf_inverse_step(pzf_state* st, double angle_desired) {
  double yd = angle_desired, th, a, b, ga, gb, lo, hi, glo, ghi, h, best_u, best_g;
  int it, side = 0, reached = 1, found;
  if (st->status & (PZF_INVALID_PARAMETERS | PZF_UNBOUNDED_HYSTERESIS)) return 0.0;
  if (!isfinite(yd)) {
    st->status |= PZF_INVALID_INPUT;
    pzf_advance(st, st->d.u);
    return st->d.u;
  }
  if (yd > st->b1 || yd < st->b2) {
    yd = yd > st->b1 ? st->b1 : st->b2;
    reached = 0;
  }
  /* The backlash inverted: the theta that gives yd after y. Inside the dead band (and at a
   * saturation) any theta of [yd - a2, yd + a1] does; the one nearest its course with the drive held
   * is taken, which keeps theta at the band's edge, ready to move. */
  if (yd > st->d.y) {
    th = yd + st->a1;
  } else if (yd < st->d.y) {
    th = yd - st->a2;
  } else {
    th = pzf_trial(st, st->d.u);
    th = th < yd - st->a2 ? yd - st->a2 : (th > yd + st->a1 ? yd + st->a1 : th);
  }
  /* g(u) = theta(u) - th need not be monotone (at small drives the Bouc-Wen force can outweigh
   * the drive's moment): the bracket is searched on both sides of the last drive, with steps growing
   * 4-fold, and the sign change nearest to it is taken. */
  best_u = a = b = lo = hi = st->d.u;
  best_g = ga = gb = glo = ghi = pzf_trial(st, best_u) - th;
  found = best_g == 0;
  h = 1e-3 * (st->u_max - st->u_min);
  for (it = 1; !found && it < PZF_INVERSE_ITERATIONS && (lo > st->u_min || hi < st->u_max); h *= 4) {
    int left;
    for (left = 0; left < 2 && !found; ++left) {
      const double from = left ? lo : hi, gfrom = left ? glo : ghi;
      double to, gto;
      if (left ? from <= st->u_min : from >= st->u_max) continue;
      to = left ? from - h : from + h;
      to = to > st->u_max ? st->u_max : (to < st->u_min ? st->u_min : to);
      gto = pzf_trial(st, to) - th;
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
        lo = to;
        glo = gto;
      } else {
        hi = to;
        ghi = gto;
      }
    }
  }
  if (!found) {
    reached = 0; /* out of reach: the drive that came nearest */
  } else {
    const double tol = 1e-13 * (fabs(th) > 1 ? fabs(th) : 1);
    for (; it < PZF_INVERSE_ITERATIONS && fabs(best_g) > tol; ++it) { /* Illinois on [a, b] */
      double c = (a * gb - b * ga) / (gb - ga), gc;
      const double l = a < b ? a : b, r = a < b ? b : a;
      if (!(c > l && c < r)) c = 0.5 * (a + b);
      if (!(c > l && c < r)) break; /* the bracket is two adjacent doubles */
      gc = pzf_trial(st, c) - th;
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
  if (!reached) {
    ++st->unreachable;
    st->status |= PZF_UNREACHABLE;
  }
  pzf_advance(st, best_u);
  return best_u;
}
)C";

void Replace(std::string& s, const std::string& from, const std::string& to) {
  for (size_t at = s.find(from); at != std::string::npos; at = s.find(from, at + to.size())) s.replace(at, from.size(), to);
}

/// A table of the plant's constants as a function returning it (no globals), hex literals with the
/// decimal values in a comment.
void WriteTable(std::ostream& o, const std::string& fn, const char* what, std::span<const double> v) {
  o << "/* " << what << " */\nstatic inline const double* pzf_" << fn << "(void) {\n  static const double v[PZF_MODES] = {";
  for (size_t i = 0; i < v.size(); ++i) o << (i ? ", " : "") << CHexLiteral(v[i]);
  o << "};\n  /* ";
  for (size_t i = 0; i < v.size(); ++i) o << (i ? " " : "") << CDecimal(v[i]);
  o << " */\n  return v;\n}\n";
}

}  // namespace

Status FinPlantToC(const model::ModalSimulator& sim, const model::Network& network, const FinPlantExport& options,
                   const std::string& name, std::string* text) {
  if (!(std::isfinite(options.sample_rate_hz) && options.sample_rate_hz > 0))
    return InvalidArgument(FieldError("--sample-rate", options.sample_rate_hz, "must be finite and > 0 [Hz]"));
  if (!(std::isfinite(options.drive_limit_v) && options.drive_limit_v >= 0))
    return InvalidArgument(FieldError("--drive-limit", options.drive_limit_v, "must be finite and >= 0 [V] (0: the training range)"));
  if (!(options.inverse_horizon >= 1 && options.inverse_horizon <= 100))
    return InvalidArgument(FieldError("--inverse-horizon", options.inverse_horizon, "must be in [1, 100] [samples]"));
  const auto& norm = network.normalization;
  const double limit = options.drive_limit_v > 0 ? options.drive_limit_v : std::max(std::abs(norm.amplitude_lo_v), std::abs(norm.amplitude_hi_v));
  if (!(limit > 0))
    return InvalidArgument(FieldError("--drive-limit", limit, "must be > 0 [V] (the training amplitudes are all 0)"));
  const int n = sim.num_modes();
  const double dt = 1.0 / options.sample_rate_hz;
  std::ostringstream t;
  t << "/* The plant: " << n << " modes of the beam (those visible at the tip), fin length L = "
    << CDecimal(sim.length_m()) << " m, sampled at " << CDecimal(options.sample_rate_hz) << " Hz.";
  if (!options.note.empty()) {  // wrapped at about 100 columns, "*/" kept out of the comment
    std::string note = options.note;
    Replace(note, "*/", "* /");
    t << "\n *";
    size_t col = 2;
    std::istringstream words(note);
    for (std::string w; words >> w; col += w.size() + 1) {
      if (col + w.size() > 100) t << "\n *", col = 2;
      t << " " << w;
    }
  }
  t << " */\n"
    << "#define PZF_MODES " << n << "\n#define PZF_MODES_PADDED " << (n + 3) / 4 * 4 << "\n"
    << "#define PZF_DT " << CHexLiteral(dt) << " /* " << CDecimal(dt) << " s */\n"
    << "#define PZF_INV_LENGTH " << CHexLiteral(1.0 / sim.length_m()) << " /* 1/L = " << CDecimal(1.0 / sim.length_m()) << " 1/m */\n"
    << "#define PZF_DEG_PER_RAD " << CHexLiteral(180.0 / std::numbers::pi) << " /* 180/pi */\n"
    << "#define PZF_U_MIN " << CHexLiteral(-limit) << " /* " << CDecimal(-limit) << " V: drive limits */\n"
    << "#define PZF_U_MAX " << CHexLiteral(limit) << " /* " << CDecimal(limit) << " V */\n"
    << "#define PZF_AMPLITUDE_LO " << CHexLiteral(norm.amplitude_lo_v) << " /* " << CDecimal(norm.amplitude_lo_v) << " V: training range */\n"
    << "#define PZF_AMPLITUDE_HI " << CHexLiteral(norm.amplitude_hi_v) << " /* " << CDecimal(norm.amplitude_hi_v) << " V */\n"
    << "#define PZF_FREQUENCY_LO " << CHexLiteral(norm.frequency_lo_hz) << " /* " << CDecimal(norm.frequency_lo_hz) << " Hz */\n"
    << "#define PZF_FREQUENCY_HI " << CHexLiteral(norm.frequency_hi_hz) << " /* " << CDecimal(norm.frequency_hi_hz) << " Hz */\n"
    << "#define PZF_INVERSE_ITERATIONS 100 /* trials of one pzf_inverse_step, at most */\n"
    << "#define PZF_INVERSE_HORIZON " << options.inverse_horizon << " /* samples */\n";
  WriteTable(t, "omega2", "omega_i^2 [1/s^2]", sim.omega2());
  WriteTable(t, "tip_gain_u", "tip_i g_u,i: drive to tip deflection, per unit modal acceleration [m/V]", sim.tip_gain_u());
  WriteTable(t, "tip_gain_z", "tip_i g_z,i: Bouc-Wen force to tip deflection", sim.tip_gain_z());
  std::string s = kPlant;
  Replace(s, "@TABLES@", t.str());
  Replace(s, "@NAME@", name);
  Replace(s, "pzf_", name + "_");
  Replace(s, "PZF_", CUpper(name) + "_");
  *text = std::move(s);
  return Status::Ok();
}

}  // namespace pz::client
