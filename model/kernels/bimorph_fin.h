/* bimorph-fin (records/families.h, model/modal_simulator.h): the fin's modal path on the sampled
 * drive (u linear between samples), times the output gain. The same recursion as the --plant header
 * of the HGANN fin (controller/fin_plant.h pzf_advance: the one sample loop of fin_modal.h,
 * pzk_fin_sample, over the same helpers), over the block's arrays for any number of modes.
 * p = {mu, delta, alpha, beta, gamma, a1, a2, b1, b2_abs, gain, L_p[, L_e]} (b2 = -b2_abs);
 * n = modes; w = {1/L, omega_i^2 (n), tip_i g_u,i (n), tip_i g_z,i (n)}: the beam's modal data for
 * the geometry (L_p, L_e), computed by the library's FE assembly and eigen-decomposition when the
 * model is built (records/stepper.cc) and written as literals by the export;
 * c = per mode {omega2, c, l1, l2, re, im, complex, e11, e12, e21, e22, D_0..D_6} (18 n);
 * d = {x0 (n), x1 (n), u, z, theta, y}: from rest (x = 0, z = 0) at the first drive, as the
 * library's simulation starts. A state that became non-finite (not reached with parameters the
 * family accepts) holds the last output. */

#define PZK_FIN_C 18 /* constants per mode */

/* Mode i's poles and full-sample step, stored in / read from the block's constants. */
static inline void pzk_fin_store(double *c, const pzk_fin_poles *p, const pzk_fin_step_t *s) {
  int j;
  c[0] = p->omega2;
  c[1] = p->c;
  c[2] = p->l1;
  c[3] = p->l2;
  c[4] = p->re;
  c[5] = p->im;
  c[6] = p->complex_pair;
  c[7] = s->e11;
  c[8] = s->e12;
  c[9] = s->e21;
  c[10] = s->e22;
  for (j = 0; j < 7; ++j) c[11 + j] = s->d[j];
}
static inline pzk_fin_poles pzk_fin_poles_of(const double *c) {
  pzk_fin_poles p;
  p.omega2 = c[0];
  p.c = c[1];
  p.l1 = c[2];
  p.l2 = c[3];
  p.re = c[4];
  p.im = c[5];
  p.complex_pair = c[6] != 0;
  return p;
}
static inline pzk_fin_step_t pzk_fin_step_of(const double *c) {
  pzk_fin_step_t s;
  int j;
  s.e11 = c[7];
  s.e12 = c[8];
  s.e21 = c[9];
  s.e22 = c[10];
  for (j = 0; j < 7; ++j) s.d[j] = c[11 + j];
  return s;
}

/* One sub-step tau of every mode (x0, x1 in place), z held by the quintic Hermite of (zl, zr), u
 * linear from u_a with slope u_dot (modal_simulator.cc GeneralSubstep). Each mode's discretisation:
 * the constants' full sample when disc_tau == 0, else computed here for disc_tau. */
static inline void pzk_fin_substep(const pzk_block *b, const double *c, double *x0, double *x1,
                                   double tau, double disc_tau, pzk_fin_zdata zl, pzk_fin_zdata zr,
                                   double u_a, double u_dot) {
  const int n = b->n;
  const double *wu = b->w + 1 + n, *wz = b->w + 1 + 2 * n;
  double fz[6];
  int i;
  if (!(tau > 0)) return;
  pzk_fin_hermite(tau, zl, zr, fz);
  for (i = 0; i < n; ++i) {
    pzk_fin_step_t sp;
    if (disc_tau == 0) {
      sp = pzk_fin_step_of(c + PZK_FIN_C * i);
    } else {
      const pzk_fin_poles pl = pzk_fin_poles_of(c + PZK_FIN_C * i);
      pzk_fin_discretise(&pl, disc_tau, &sp);
    }
    pzk_fin_mode_update(&sp, wu[i], wz[i], fz, u_a, u_dot, tau, x0 + i, x1 + i);
  }
}

static inline double pzk_fin_init(const pzk_block *b, double *c, double *d, double v) {
  const int n = b->n;
  const double *p = b->p, *omega2 = b->w + 1;
  int i, finite;
  for (i = 0; i < n; ++i) {
    const pzk_fin_poles pl = pzk_fin_make_poles(omega2[i], p[0] + p[1] * omega2[i]);
    pzk_fin_step_t s;
    pzk_fin_discretise(&pl, b->dt, &s);
    pzk_fin_store(c + PZK_FIN_C * i, &pl, &s);
  }
  for (i = 0; i < 2 * n; ++i) d[i] = 0.0;
  d[2 * n] = v;
  d[2 * n + 1] = 0.0;
  d[2 * n + 2] = pzk_fin_angle(d, n, b->w[0], &finite);
  d[2 * n + 3] = pzk_fin_backlash(p[5], p[6], p[7], -p[8], d[2 * n + 2], 0.0);
  return p[9] * d[2 * n + 3];
}

/* pzk_fin_sample's sub-step over the block: a regular one with the constants' full sample (disc ==
 * 0, one sub-step per sample) or discretised for disc (the sample / nsub), a cut piece for its tau.
 */
typedef struct {
  const pzk_block *b;
  const double *c;
  double *x0, *x1;
  double disc;
} pzk_fin_walk;
static inline void pzk_fin_walk_substep(void *ctx, double tau, int regular, pzk_fin_zdata zl,
                                        pzk_fin_zdata zr, double u_a, double u_dot) {
  const pzk_fin_walk *w = (const pzk_fin_walk *)ctx;
  pzk_fin_substep(w->b, w->c, w->x0, w->x1, tau, regular ? w->disc : tau, zl, zr, u_a, u_dot);
}

/* One sample from the drive d[2n] to v (fin_modal.h pzk_fin_sample); returns gain * angle. */
static inline double pzk_fin_step(const pzk_block *b, const double *c, const double *d, double *o,
                                  double v) {
  const int n = b->n;
  const double *p = b->p;
  const double tau = b->dt, u0 = d[2 * n];
  const int nsub = pzk_fin_substeps(p[2] != 0.0, fabs(p[3]) + fabs(p[4]), (v - u0) / tau, tau);
  int i, finite;
  double z, theta;
  pzk_fin_walk w;
  if (o != d)
    for (i = 0; i < 2 * n + 4; ++i) o[i] = d[i];
  w.b = b;
  w.c = c;
  w.x0 = o;
  w.x1 = o + n;
  w.disc = nsub == 1 ? 0.0 : tau / nsub;
  z = pzk_fin_sample(p[2], p[3], p[4], u0, d[2 * n + 1], v, tau, nsub, pzk_fin_walk_substep, &w);
  theta = pzk_fin_angle(o, n, b->w[0], &finite);
  if (!finite) return p[9] * d[2 * n + 3];
  o[2 * n] = v;
  o[2 * n + 1] = z;
  o[2 * n + 2] = theta;
  o[2 * n + 3] = pzk_fin_backlash(p[5], p[6], p[7], -p[8], theta, d[2 * n + 3]);
  return p[9] * o[2 * n + 3];
}

/* The inverse's trial step (model/kernels/chain.h pzk_chain_inverse_fin): pzk_fin_step, its output
 * the angle pushed through the backlash: theta - a1 (dir > 0) or theta + a2 (dir < 0), within the
 * saturations [b2, b1]. */
static inline double pzk_fin_step_through(const pzk_block *b, const double *c, const double *d,
                                          double *o, double v, int dir) {
  const int n = b->n;
  const double *p = b->p;
  pzk_fin_step(b, c, d, o, v);
  return p[9] * pzk_clamp(dir > 0 ? o[2 * n + 2] - p[5] : o[2 * n + 2] + p[6], -p[8], p[7]);
}
