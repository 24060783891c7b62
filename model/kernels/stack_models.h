/* Stack families (model/stack_models.h, model/duhem.h): the same operations in the same order as
 * the library's simulations, one sample at a time. */

/* backlash-like: p = {alpha, c, B1}; w = c u - y; d = {w, u_prev}. */
/* The exact update of w over a straight piece of drive du (BacklashLikeStateStep). */
static inline double pzk_backlash_state_step(const pzk_block *b, double w, double du) {
  double as = du >= 0 ? b->p[0] : -b->p[0];
  return w + ((b->p[1] - b->p[2]) - as * w) * du * pzk_phi(as * du);
}
/* At rest in the block's initial state: w after a rise by the data's range 2 u_half from w = 0 and
 * a fall back (descended), or the mirror (ascended); 0 centred (StackRestState). */
static inline double pzk_backlash_init(const pzk_block *b, double *d, double v) {
  int state = pzk_rest_state(b, v);
  double first = state == PZK_DESCENDED ? 2 * b->u_half : -2 * b->u_half;
  d[0] = state == PZK_CENTRED
             ? 0.0
             : pzk_backlash_state_step(b, pzk_backlash_state_step(b, 0.0, first), -first);
  d[1] = v;
  return b->p[1] * v - d[0];
}
static inline double pzk_backlash_step(const pzk_block *b, const double *d, double *o, double v) {
  double alpha = b->p[0], cc = b->p[1], g = cc - b->p[2];
  double du = v - d[1], as = du >= 0 ? alpha : -alpha;
  double w = d[0] + (g - as * d[0]) * du * pzk_phi(as * du);
  o[0] = w;
  o[1] = v;
  return cc * v - w;
}

/* The exact Bouc-Wen state update over a straight piece of drive du (BoucWenStateStep). */
static inline double pzk_bouc_wen_state_step(double h, double du, double alpha, double beta,
                                             double gamma) {
  double s, k, h1, z, v0, rest, k2;
  int positive;
  if (du == 0) return h;
  s = du > 0 ? 1.0 : -1.0;
  positive = h > 0 || (h == 0 && alpha * du >= 0);
  k = beta * s + (positive ? gamma : -gamma);
  h1 = h + (alpha - k * h) * du * pzk_phi(k * du);
  if (h == 0 || alpha == 0) return h1;
  if ((h > 0 && h1 >= 0) || (h < 0 && h1 <= 0)) return h1;
  z = -k * h / alpha;
  v0 = (-h / alpha) * pzk_log_ratio(z);
  rest = du - v0;
  if (!(rest * du > 0)) return 0.0;
  k2 = beta * s + (positive ? -gamma : gamma);
  return alpha * rest * pzk_phi(k2 * rest);
}

/* stack-bouc-wen: p = {alpha, beta, gamma, d, fc_Hz}, n sub-steps; c = {a, b0, b1, inv_m};
 * d = {h, x, y, u_prev}. */
static inline double pzk_stack_bw_init(const pzk_block *b, double *c, double *d, double v) {
  const double pi = 3.14159265358979323846;
  double wt = 2 * pi * b->p[4] * b->dt / b->n;
  double one_minus_a = -expm1(-wt), a = 1.0 - one_minus_a, q = pzk_phi(wt);
  c[0] = a;
  c[1] = q - a;
  c[2] = 1.0 - q;
  c[3] = 1.0 / b->n;
  d[0] = 0.0; /* centred; else h after a rise by 2 u_half and a fall back (StackRestState) */
  if (pzk_rest_state(b, v) != PZK_CENTRED) {
    double first = pzk_rest_state(b, v) == PZK_DESCENDED ? 2 * b->u_half : -2 * b->u_half;
    d[0] = pzk_bouc_wen_state_step(pzk_bouc_wen_state_step(0.0, first, b->p[0], b->p[1], b->p[2]),
                                   -first, b->p[0], b->p[1], b->p[2]);
  }
  d[1] = b->p[3] * (v - d[0]);
  d[2] = d[1];
  d[3] = v;
  return d[2];
}
static inline double pzk_stack_bw_step(const pzk_block *b, const double *c, const double *d,
                                       double *o, double v) {
  const double alpha = b->p[0], beta = b->p[1], gamma = b->p[2], dd = b->p[3];
  const int m = b->n;
  double h = d[0], x = d[1], y = d[2], u0 = d[3];
  double du = (v - u0) * c[3], s = du >= 0 ? 1.0 : -1.0;
  double kp = beta * s + gamma, kn = beta * s - gamma, php = 0, phn = 0;
  int have_p = 0, have_n = 0, j;
  for (j = 1; j <= m; ++j) {
    double uj = (j == m) ? v : u0 + j * du, x1;
    if (du != 0) {
      int positive = h > 0 || (h == 0 && alpha * du >= 0);
      double h1;
      if (positive) {
        if (!have_p) php = pzk_phi(kp * du), have_p = 1;
        h1 = h + (alpha - kp * h) * du * php;
      } else {
        if (!have_n) phn = pzk_phi(kn * du), have_n = 1;
        h1 = h + (alpha - kn * h) * du * phn;
      }
      if ((h > 0 && h1 < 0) || (h < 0 && h1 > 0))
        h1 = pzk_bouc_wen_state_step(h, du, alpha, beta, gamma);
      h = h1;
    }
    x1 = dd * (uj - h);
    y = c[0] * y + c[1] * x + c[2] * x1;
    x = x1;
  }
  o[0] = h;
  o[1] = x;
  o[2] = y;
  o[3] = v;
  return y;
}

/* phi_1, phi_2, phi_3 of z (model/duhem.cc). */
static inline void pzk_phi123(double z, double *p1, double *p2, double *p3) {
  if (fabs(z) < 0.1) {
    double t1 = 1, t2 = 0.5, t3 = 1.0 / 6;
    int j;
    *p1 = *p2 = *p3 = 0;
    for (j = 0; j < 10; ++j) {
      *p1 += t1;
      *p2 += t2;
      *p3 += t3;
      t1 *= z / (j + 2);
      t2 *= z / (j + 3);
      t3 *= z / (j + 4);
    }
    return;
  } else {
    double em1 = expm1(z);
    *p1 = em1 / z;
    *p2 = (em1 - z) / (z * z);
    *p3 = (em1 - z - z * z / 2) / (z * z * z);
  }
}

/* duhem: p = {alpha, c, c3, b, lambda}; d = {w, u_prev}, w = f(u) - y. */
static inline double pzk_duhem_f(const pzk_block *b, double v) {
  return b->p[1] * v + b->p[2] * v * v * v;
}
static inline double pzk_duhem_init(const pzk_block *b, double *d, double v) {
  d[0] = 0;
  d[1] = v;
  return pzk_duhem_f(b, v);
}
static inline double pzk_duhem_step(const pzk_block *b, const double *d, double *o, double v) {
  const double alpha = b->p[0], cc = b->p[1], c3 = b->p[2], bb = b->p[3], lambda = b->p[4],
               dt = b->dt;
  double u0 = d[1], s = (v - u0) / dt, kk = alpha * fabs(s) + lambda;
  double g0 = s * (cc - bb + 3 * c3 * u0 * u0), g1 = 6 * c3 * s * s * u0, g2 = 6 * c3 * s * s * s;
  double p1, p2, p3, z = -kk * dt, w;
  pzk_phi123(z, &p1, &p2, &p3);
  w = exp(z) * d[0] + dt * p1 * g0 + dt * dt * p2 * g1 + dt * dt * dt * p3 * g2;
  o[0] = w;
  o[1] = v;
  return pzk_duhem_f(b, v) - w;
}
