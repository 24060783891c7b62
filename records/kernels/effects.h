/* Effect kernels (records/model.h): each block has init (constants c, dynamic state d, at rest
 * under the value v it receives; u_raw the raw drive at rest) returning its output at rest, and
 * step (reads d, writes the next state to o, which may be d) returning its output. */

/* First-order low-pass tau x' = v - x, exact for v linear between samples (from rest). */
static inline int pzk_lowpass_on(double tau, double dt) { return tau > 1e-12 * dt; }
static inline void pzk_lowpass_consts(double tau, double dt, double *c) {
  double a = exp(-dt / tau);
  c[0] = a;
  c[1] = 1 - tau * (1 - a) / dt;
}
static inline double pzk_lowpass_filter(const double *c, const double *d, double *o, double v) {
  double x = c[0] * d[0] + (1 - c[0]) * d[1] + (v - d[1]) * c[1];
  o[0] = x;
  o[1] = v;
  return x;
}

/* driver-lowpass: c = {on, a, c}, d = {x, prev}. */
static inline double pzk_driver_lowpass_init(const pzk_block *b, double *c, double *d, double v, double u_raw) {
  (void)u_raw;
  c[0] = pzk_lowpass_on(b->p[0], b->dt);
  if (c[0] != 0) pzk_lowpass_consts(b->p[0], b->dt, c + 1);
  d[0] = v;
  d[1] = v;
  return v;
}
static inline double pzk_driver_lowpass_step(const double *c, const double *d, double *o, double v) {
  if (c[0] == 0) return v;
  return pzk_lowpass_filter(c + 1, d, o, v);
}

/* quadratic-drive: v + c2 v^2, memoryless. */
static inline double pzk_quadratic_step(const pzk_block *b, double v) { return v + b->p[0] * v * v; }

/* creep: x = LPF_tau_c[k_c (v - v0)], v + x, at rest at its own first input v0 (as the effect
 * library's Creep::ApplyDrive); c = {on, filter on, a, c, v0}, d = {x, prev}. */
static inline double pzk_creep_init(const pzk_block *b, double *c, double *d, double v) {
  c[0] = b->p[0] != 0;
  c[1] = pzk_lowpass_on(b->p[1], b->dt);
  if (c[1] != 0) pzk_lowpass_consts(b->p[1], b->dt, c + 2);
  c[4] = v;
  d[0] = 0;
  d[1] = 0;
  return v;
}
static inline double pzk_creep_step(const pzk_block *b, const double *c, const double *d, double *o, double v) {
  double x;
  if (c[0] == 0) return v;
  x = b->p[0] * (v - c[4]);
  if (c[1] != 0) x = pzk_lowpass_filter(c + 2, d, o, x);
  return v + x;
}

/* delay: v(t - tau_d) by linear interpolation of the samples (the first before the start).
 * c = {shift = tau_d/dt, capacity}, d = {k, ring[capacity]} (the last `capacity` inputs).
 * A delay cannot be undone: the inverse skips this block (pzk_chain_inverse). It only ever
 * steps in place. */
static inline int pzk_delay_capacity(const pzk_block *b) {
  double shift = b->p[0] / b->dt;
  return shift > 0 ? (int)shift + 2 : 1;
}
static inline double pzk_delay_init(const pzk_block *b, double *c, double *d, double v) {
  int i, cap = pzk_delay_capacity(b);
  c[0] = b->p[0] / b->dt;
  c[1] = cap;
  d[0] = 0;
  for (i = 0; i < cap; ++i) d[1 + i] = v;
  return v;
}
static inline double pzk_delay_step(const double *c, double *d, double v) {
  double shift = c[0], pos, f, a, b;
  long cap = (long)c[1], k, j;
  if (!(shift > 0)) return v;
  k = (long)d[0] + 1;
  d[0] = (double)k;
  d[1 + k % cap] = v;
  pos = (double)k - shift;
  if (pos <= 0) return d[1]; /* the first sample: slot 0 is only overwritten at k = cap > shift */
  j = (long)pos;
  f = pos - (double)j;
  a = d[1 + j % cap];
  b = d[1 + (j + 1) % cap];
  return a + f * (b - a);
}

/* rate-dependence: the play of half-width lambda = r_m tanh(tau_r |v'| / r_m) on the drive, v' =
 * (3 v - 4 v_1 + v_2) / (2 dt) (the second-order backward difference, at rest at its first input
 * before it); where v' changes sign the play first passes the vertex v - v'^2 dt / (2 (v' - v'_1))
 * (lambda = 0 there); as the effect library's RateDependence::ApplyDrive. p = {r_m, tau_r},
 * d = {v_1, v_2, z, v'_1}. */
static inline double pzk_rate_dependence_init(double *d, double v) {
  d[0] = v;
  d[1] = v;
  d[2] = v;
  d[3] = 0;
  return v;
}
/* Below its knee the play is a lag of tau_r (z = v - tau_r v'): solved for the drive one sample at a
 * time it carries a difference of the past drives forward, unstably once tau_r > dt / 4
 * (records/stepper.h rate_dependence_inverse_gain), and the compensator then plans two samples
 * (pzk_chain_inverse_fin). */
static inline int pzk_rate_dependence_plans(const pzk_block *b) { return b->p[0] > 0 && b->p[1] > 0.25 * b->dt; }
static inline double pzk_rate_dependence_step(const pzk_block *b, const double *d, double *o, double v) {
  double rate, lambda, z, r_m = b->p[0];
  if (!(r_m > 0)) return v;
  rate = (3 * v - 4 * d[0] + d[1]) / (2 * b->dt);
  z = rate * d[3] < 0 ? v - rate * rate * b->dt / (2 * (rate - d[3])) : d[2];
  lambda = r_m * tanh(b->p[1] * fabs(rate) / r_m);
  z = pzk_play(v, lambda, z);
  o[3] = rate;
  o[2] = z;
  o[1] = d[0];
  o[0] = v;
  return z;
}

/* creep-spectrum: v - sum_i p_i (e - x_i), e = v - v0, tau_i x_i' = e - x_i (first-order hold, from
 * rest), v0 the output at rest (as the effect library's CreepSpectrum::ApplyOutput); n = relaxations,
 * w = their times. c = {v0, a_0, c_0, a_1, c_1, ...}, d = {e_prev, x_0, x_1, ...}. */
static inline double pzk_creep_spectrum_init(const pzk_block *b, double *c, double *d, double v) {
  int i;
  c[0] = v;
  d[0] = 0;
  for (i = 0; i < b->n; ++i) {
    pzk_lowpass_consts(b->w[i], b->dt, c + 1 + 2 * i);
    d[1 + i] = 0;
  }
  return v;
}
static inline double pzk_creep_spectrum_step(const pzk_block *b, const double *c, const double *d, double *o,
                                             double v) {
  double e = v - c[0], prev = d[0], corr = 0, x;
  int i;
  for (i = 0; i < b->n; ++i) {
    x = c[1 + 2 * i] * d[1 + i] + (1 - c[1 + 2 * i]) * prev + (e - prev) * c[2 + 2 * i];
    o[1 + i] = x;
    corr += b->p[i] * (e - x);
  }
  o[0] = e;
  return v - corr;
}

/* friction: the play of half-width r on the output; d = {z}. */
static inline double pzk_friction_init(double *d, double v) {
  d[0] = v;
  return v;
}
static inline double pzk_friction_step(const pzk_block *b, const double *d, double *o, double v) {
  double r = b->p[0] > 0 ? b->p[0] : 0.0, z;
  if (r == 0) return v;
  z = pzk_play(v, r, d[0]);
  o[0] = z;
  return z;
}

/* stiffening: v - k3 Y ((v - y0)/Y)^3, y0 the output at rest; c = {y0}. */
static inline double pzk_stiffening_step(const pzk_block *b, const double *c, double v) {
  double Y = b->y_half, x = (v - c[0]) / Y;
  return v - b->p[0] * Y * x * x * x;
}

/* drift: v + rate (t - t_init); d = {k}. */
static inline double pzk_drift_step(const pzk_block *b, const double *d, double *o, double v) {
  double k = d[0] + 1;
  o[0] = k;
  return v + b->p[0] * k * b->dt;
}
