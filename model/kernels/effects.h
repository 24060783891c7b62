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
static inline double pzk_driver_lowpass_init(const pzk_block *b, double *c, double *d, double v,
                                             double u_raw) {
  (void)u_raw;
  c[0] = pzk_lowpass_on(b->p[0], b->dt);
  if (c[0] != 0) pzk_lowpass_consts(b->p[0], b->dt, c + 1);
  d[0] = v;
  d[1] = v;
  return v;
}
static inline double pzk_driver_lowpass_step(const double *c, const double *d, double *o,
                                             double v) {
  if (c[0] == 0) return v;
  return pzk_lowpass_filter(c + 1, d, o, v);
}

/* quadratic-drive: v + c2 v^2, memoryless. */
static inline double pzk_quadratic_step(const pzk_block *b, double v) {
  return v + b->p[0] * v * v;
}

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
static inline double pzk_creep_step(const pzk_block *b, const double *c, const double *d, double *o,
                                    double v) {
  double x;
  if (c[0] == 0) return v;
  x = b->p[0] * (v - c[4]);
  if (c[1] != 0) x = pzk_lowpass_filter(c + 2, d, o, x);
  return v + x;
}

/* delay: v(t - tau_d) by linear interpolation of the samples (the first before the start).
 * With shift = tau_d/dt = n + s (n whole, 0 <= s < 1) the output is y_k = (1 - s) v_{k-n} + s
 * v_{k-n-1}. c = {shift, capacity, horizon}, d = {k, ring[capacity]} (the last `capacity` inputs),
 * and with a horizon L > 0 the compensator's {head, w_last, y_last, dw_last, primed, w[L + 1]}
 * after them (pzk_chain_inverse_split). Forward it only ever steps in place.
 *
 * The compensator (model/kernels/chain.h pzk_chain_inverse) reads the reference ahead; what remains
 * of the delay is w_k = (1 - s) x_k + s x_{k-1} (x its input at the compensator's sample k):
 *   s <= 1/2 (horizon 0): the reference n samples ahead, w kept in the one-step map solved
 *     (pzk_delay_inverse_step): exact; an error in x_{k-1} comes back times -s / (1 - s), which
 *     decays for s < 1/2 (at s = 1/2 it alternates without growing).
 *   s > 1/2 (horizon L >= 1): solved that way an error would grow s / (1 - s) times per sample (the
 *     zero of (1 - s) + s z^-1 lies outside the unit circle): the exact inverse is anti-causal. The
 *     reference n + L samples ahead; the blocks after the delay are solved for w there (they run
 *     n + L samples ahead of the drive), and x_j = (1/s) sum_{i<L} (-r)^i w_{j+n+1+i} + (-r)^L
 *     x^_{j+L}, r = (1 - s) / s < 1, with x^_{j+L} = w_{j+n+L} + s (w_{j+n+L} - w_{j+n+L-1}) (the
 *     delay's output extrapolated by s samples): its error, the drive's curvature, shrinks by r^L.
 *     L is the smallest with r^L <= 1e-13, at most PZK_DELAY_HORIZON_MAX (a fraction under 0.615
 *     keeps r^64 of the extrapolation's error). Then the blocks before the delay are solved for
 * x_j. Both amplify what the reference has at the Nyquist rate by 1 / |1 - 2 s| (the inverse of the
 * interpolation's gain there). */
#define PZK_DELAY_HORIZON_MAX 64
static inline int pzk_delay_capacity(const pzk_block *b) {
  double shift = b->p[0] / b->dt;
  return shift > 0 ? (int)shift + 2 : 1;
}
static inline int pzk_delay_horizon(const pzk_block *b) {
  double shift = b->p[0] / b->dt, s, r;
  int h;
  if (!(shift > 0)) return 0;
  s = shift - floor(shift);
  if (s <= 0.5) return 0;
  r = (1 - s) / s;
  if (!(r > 1e-13)) return 1;
  h = (int)ceil(log(1e-13) / log(r));
  return h < 1 ? 1 : (h > PZK_DELAY_HORIZON_MAX ? PZK_DELAY_HORIZON_MAX : h);
}
/* The compensator's doubles after the ring: head, w_last, y_last, dw_last, primed and the L + 1
 * outputs. */
static inline int pzk_delay_inverse_size(int horizon) { return horizon > 0 ? horizon + 6 : 0; }
static inline double pzk_delay_init(const pzk_block *b, double *c, double *d, double v) {
  int i, cap = pzk_delay_capacity(b), h = pzk_delay_horizon(b);
  double *w = d + 1 + cap;
  c[0] = b->p[0] / b->dt;
  c[1] = cap;
  c[2] = h;
  d[0] = 0;
  for (i = 0; i < cap; ++i) d[1 + i] = v;
  if (h > 0) {
    w[0] = 0;
    w[1] = v;
    w[2] = 0; /* the output at rest: pzk_chain_init */
    w[3] = 0;
    w[4] = 0;
    for (i = 0; i <= h; ++i) w[5 + i] = v;
  }
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
static inline double pzk_delay_fraction(const double *c) {
  return c[0] > 0 ? c[0] - floor(c[0]) : 0.0;
}
/* Samples of the reference ahead of the drive: n, plus the horizon. */
static inline long pzk_delay_preview(const double *c) {
  return c[0] > 0 ? (long)floor(c[0]) + (long)c[2] : 0;
}
/* The one-step compensator's delay (horizon 0): (1 - s) v + s v_prev, computed as pzk_delay_step
 * computes its output n samples later (the same operations: bit for bit the forward model's, so
 * that where the map is flat — a play's band — the last drive is still a root). Trials (o the
 * scratch) read d and write only k and the one slot the next trial on o reads. */
static inline double pzk_delay_inverse_step(const double *c, const double *d, double *o, double v) {
  double shift = c[0], pos, f, prev;
  long cap = (long)c[1], k, j;
  if (!(shift > 0)) return v;
  k = (long)d[0] + 1;
  prev = d[1 + (k - 1) % cap];
  o[0] = (double)k;
  o[1 + k % cap] = v;
  pos = (double)(k + (long)floor(shift)) - shift; /* the forward's k - shift at its sample k + n */
  j = (long)pos;
  f = pos - (double)j;
  return j >= k ? v : prev + f * (v - prev);
}
/* The horizon's outputs before the first step: w_{n+1} ... w_{n+L} in order (at init they are the
 * rest's, right for a reference that stays at rest that long). Returns 0, or -1 once L are in or a
 * step has been taken. */
static inline int pzk_delay_prime(const double *c, double *d, double w_new) {
  const long cap = (long)c[1], h = (long)c[2];
  double *q = d + 1 + cap, *w = q + 5;
  const long primed = (long)q[4];
  if (primed >= h) return -1;
  w[((long)q[0] + primed + 1) % (h + 1)] = w_new;
  q[4] = (double)(primed + 1);
  return 0;
}
/* The horizon's step (s > 1/2): pushes the delay's output w solved n + L samples ahead, returns
 * x_j. */
static inline double pzk_delay_anticausal(const double *c, double *d, double w_new) {
  const long cap = (long)c[1], h = (long)c[2];
  const double s = pzk_delay_fraction(c), r = (1 - s) / s;
  double *q = d + 1 + cap, *w = q + 5, sum = 0, gain = 1 / s, last, before;
  long head = ((long)q[0] + 1) % (h + 1), i;
  w[(head + h) % (h + 1)] = w_new; /* w_{j+n+i} at (head + i) mod (L + 1), i = 0..L */
  q[0] = (double)head;
  q[4] = (double)h; /* no priming after a step */
  for (i = 0; i < h; ++i) {
    sum += gain * w[(head + 1 + i) % (h + 1)];
    gain *= -r;
  }
  last = w[(head + h) % (h + 1)];
  before = w[(head + h - 1) % (h + 1)];
  return sum + gain * s * (last + s * (last - before));
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
/* Below its knee the play is a lag of tau_r (z = v - tau_r v'): solved for the drive one sample at
 * a time it carries a difference of the past drives forward, unstably once tau_r > dt / 4
 * (records/stepper.h rate_dependence_inverse_gain), and the compensator then plans two samples
 * (pzk_chain_inverse_fin). */
static inline int pzk_rate_dependence_plans(const pzk_block *b) {
  return b->p[0] > 0 && b->p[1] > 0.25 * b->dt;
}
static inline double pzk_rate_dependence_step(const pzk_block *b, const double *d, double *o,
                                              double v) {
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
 * rest), v0 the output at rest (as the effect library's CreepSpectrum::ApplyOutput); n =
 * relaxations, w = their times. c = {v0, a_0, c_0, a_1, c_1, ...}, d = {e_prev, x_0, x_1, ...}. */
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
static inline double pzk_creep_spectrum_step(const pzk_block *b, const double *c, const double *d,
                                             double *o, double v) {
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

/* resonance: a second-order mode after the hysteresis (Hammerstein), unit gain at DC:
 *   y = (1 - a) v + a q,   q'' + 2 zeta w q' + w^2 q = w^2 v,   w = 2 pi f_n,
 * p = {a (the mode's share of the output, 0..1), f_n [Hz], zeta}, at rest at its first input.
 * Discretised exactly for v linear between samples (the first-order hold of the library's other
 * filters): over a sample of slope r = (v - v_prev)/dt the deviation e = q - v obeys
 * e'' + 2 zeta w e' + w^2 e = -2 zeta w r, whose particular solution is the constant -2 zeta r / w,
 * so h = e + 2 zeta r / w rings freely: (h, h') <- Phi (h, h'), Phi = exp(A dt) of the free
 * oscillator in closed form (under-, critically or over-damped). No sampling error at any f_n dt.
 * c = {on, Phi11, Phi12, Phi21, Phi22, 2 zeta / w, 1/dt, a, q_c, g}, d = {q, q', v_prev}.
 *
 * The compensator (pzk_chain_eval in any mode but forward) does not invert the mode itself: the
 * exact inverse of a sampled mode with a full share has a zero outside the unit circle (the
 * linear hold's sampling zero near -3.7) and its one-step inverse oscillates without bound. In its
 * one-step map the block outputs instead the virtual plant P(s)/D(s) of the same state,
 *   q_c v + (1 - q_c) q + g q',   P(s) = q_c s^2 + 2 zeta_r sqrt(q_c) w s + w^2,
 * D(s) = s^2 + 2 zeta w s + w^2, zeta_r = 1/sqrt 2, g = 2 (zeta_r sqrt(q_c) - q_c zeta) / w,
 * q_c = max(1 - a, PZK_RESONANCE_QMIN, (f_n dt / PZK_RESONANCE_FMAX)^2); solving it for v applies
 * D/P to the reference: a second-order lead whose zeros cancel the mode's poles and whose poles are
 * a reference low-pass at f_n / sqrt(q_c) — 2 f_n for a full share, never above FMAX fs = 0.2 fs
 * (above it the linear hold's sampled map of P/D has a zero outside the unit circle, and its
 * one-step inverse diverges from f_n dt = 0.3) — damping zeta_r. The model then follows the
 * reference through N(s)/P(s) (N = (1 - a) s^2 + 2 (1 - a) zeta w s + w^2, the plant's own zeros):
 * for a full share the reference low-pass w^2 / P, for a small share 1 away from a shallow dip at
 * the plant's antiresonance f_n / sqrt(1 - a). Unit gain at DC, at most 1/q_c <= 1/QMIN at high
 * frequency, and no ringing to excite: the drive stays bounded (over f_n dt 0.01 ... 0.45, zeta
 * 0.003 ... 0.7 and any share: a step of the reference gives a drive of at most 3.9 x its DC step
 * that settles, the model's overshoot at most 6 %, tests/records/resonance_test.cc). */
#define PZK_RESONANCE_QMIN 0.25
#define PZK_RESONANCE_FMAX 0.2
static inline void pzk_resonance_consts(const pzk_block *b, double *c) {
  const double a = b->p[0], w = 2 * 3.14159265358979323846 * b->p[1], z = b->p[2], t = b->dt;
  const double sigma = z * w, e = exp(-sigma * t);
  double cs, sn; /* cos(w_d t) and sin(w_d t) / w_d, or their hyperbolic or critical forms */
  if (z < 1) {
    const double wd = w * sqrt(1 - z * z);
    cs = cos(wd * t);
    sn = sin(wd * t) / wd;
  } else if (z > 1) {
    const double wd = w * sqrt(z * z - 1);
    cs = cosh(wd * t);
    sn = sinh(wd * t) / wd;
  } else {
    cs = 1;
    sn = t;
  }
  c[0] = a != 0 && w > 0;
  c[1] = e * (cs + sigma * sn);
  c[2] = e * sn;
  c[3] = -e * w * w * sn;
  c[4] = e * (cs - sigma * sn);
  c[5] = w > 0 ? 2 * z / w : 0;
  c[6] = 1 / t;
  c[7] = a;
  c[8] = 1 - a > PZK_RESONANCE_QMIN ? 1 - a : PZK_RESONANCE_QMIN;
  if (b->p[1] * t / PZK_RESONANCE_FMAX * (b->p[1] * t / PZK_RESONANCE_FMAX) > c[8])
    c[8] = b->p[1] * t / PZK_RESONANCE_FMAX * (b->p[1] * t / PZK_RESONANCE_FMAX);
  c[9] = w > 0 ? 2 * (sqrt(0.5 * c[8]) - c[8] * z) / w : 0; /* zeta_r sqrt(q_c) = sqrt(q_c/2) */
}
static inline double pzk_resonance_init(const pzk_block *b, double *c, double *d, double v) {
  pzk_resonance_consts(b, c);
  d[0] = v;
  d[1] = 0;
  d[2] = v;
  return v;
}
/* The mode's state one sample on (to o; o may be d). */
static inline void pzk_resonance_advance(const double *c, const double *d, double *o, double v) {
  const double r = (v - d[2]) * c[6], h = d[0] - d[2] + c[5] * r, hd = d[1] - r;
  o[0] = v + c[1] * h + c[2] * hd - c[5] * r;
  o[1] = c[3] * h + c[4] * hd + r;
  o[2] = v;
}
static inline double pzk_resonance_step(const double *c, const double *d, double *o, double v) {
  if (c[0] == 0) return v;
  pzk_resonance_advance(c, d, o, v);
  return (1 - c[7]) * v + c[7] * o[0];
}
/* The compensator's one-step map: the virtual plant P/D on the same state (above). */
static inline double pzk_resonance_inverse_step(const double *c, const double *d, double *o,
                                                double v) {
  if (c[0] == 0) return v;
  pzk_resonance_advance(c, d, o, v);
  return c[8] * v + (1 - c[8]) * o[0] + c[9] * o[1];
}
