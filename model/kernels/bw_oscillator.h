/* bw-oscillator (records/families.h, model/bw_oscillator.h): m y'' + c y' + k y + z = u,
 * z' = alpha y' - bg |y'| z - bd y' |z| (nu = 1), classical RK4 with n steps per sample on the
 * drive linear between samples (the fit's interpolation), from rest at k y = u_0. p = {K, fn_Hz,
 * zeta, share, beta_gamma, beta_delta} (scaled) or {m, c, k, alpha, bg, bd} (m = 1: physical); c =
 * {inv_m, c, k, alpha, bg, bd}; d = {y, v, z, u_prev}. */
static inline void pzk_bw_osc_params(const pzk_block *b, double *c) {
  const double *p = b->p;
  double m, cc, k, alpha;
  if (b->m) {
    m = p[0];
    cc = p[1];
    k = p[2];
    alpha = p[3];
  } else {
    const double pi = 3.14159265358979323846;
    double ktot = 1.0 / p[0], wn = 2 * pi * p[1];
    k = (1 - p[3]) * ktot;
    alpha = p[3] * ktot;
    m = ktot / (wn * wn);
    cc = 2 * p[2] * sqrt(ktot * m);
  }
  c[0] = 1.0 / m;
  c[1] = cc;
  c[2] = k;
  c[3] = alpha;
  c[4] = 1.0 * p[4]; /* beta = 1: beta * gamma */
  c[5] = 1.0 * p[5];
}
static inline double pzk_bw_osc_init(const pzk_block *b, double *c, double *d, double v) {
  pzk_bw_osc_params(b, c);
  d[0] = c[2] != 0 ? v / c[2] : 0.0;
  d[1] = 0;
  d[2] = 0;
  d[3] = v;
  return d[0];
}
static inline double pzk_bw_osc_zdot(const double *c, double v, double z) {
  return c[3] * v - c[4] * fabs(v) * z - c[5] * v * fabs(z);
}
/* One classical RK4 step of length h (h2 = h / 2, h6 = h / 6) from s = {y, v, z} on the drive u0,
 * u1, u2 at its start, middle and end: the oscillator's arithmetic, which the library's SimulateBw
 * runs too (model/bw_oscillator.cc). */
static inline void pzk_bw_osc_rk4(const double *c, double h, double h2, double h6, double u0,
                                  double u1, double u2, double *s) {
  const double inv_m = c[0], cc = c[1], k = c[2];
  const double Y = s[0], V = s[1], Z = s[2];
  double a1 = (u0 - cc * V - k * Y - Z) * inv_m, z1 = pzk_bw_osc_zdot(c, V, Z);
  double y2 = Y + h2 * V, v2 = V + h2 * a1, w2 = Z + h2 * z1;
  double a2 = (u1 - cc * v2 - k * y2 - w2) * inv_m, z2 = pzk_bw_osc_zdot(c, v2, w2);
  double y3 = Y + h2 * v2, v3 = V + h2 * a2, w3 = Z + h2 * z2;
  double a3 = (u1 - cc * v3 - k * y3 - w3) * inv_m, z3 = pzk_bw_osc_zdot(c, v3, w3);
  double y4 = Y + h * v3, v4 = V + h * a3, w4 = Z + h * z3;
  double a4 = (u2 - cc * v4 - k * y4 - w4) * inv_m, z4 = pzk_bw_osc_zdot(c, v4, w4);
  s[0] = Y + h6 * (V + 2 * (v2 + v3) + v4);
  s[1] = V + h6 * (a1 + 2 * (a2 + a3) + a4);
  s[2] = Z + h6 * (z1 + 2 * (z2 + z3) + z4);
}
static inline double pzk_bw_osc_step(const pzk_block *b, const double *c, const double *d,
                                     double *o, double u) {
  const int S = b->n, L = 2 * S;
  const double h = 1.0 / ((1.0 / b->dt) * S), h2 = 0.5 * h, h6 = h / 6.0, up = d[3];
  double st[3];
  int s;
  st[0] = d[0];
  st[1] = d[1];
  st[2] = d[2];
  for (s = 0; s < S; ++s) {
    int r = 2 * s;
    double u0 = up + (u - up) * ((double)r / (double)L);
    double u1 = up + (u - up) * ((double)(r + 1) / (double)L);
    double u2 = r + 2 == L ? u : up + (u - up) * ((double)(r + 2) / (double)L);
    pzk_bw_osc_rk4(c, h, h2, h6, u0, u1, u2, st);
  }
  o[0] = st[0];
  o[1] = st[1];
  o[2] = st[2];
  o[3] = u;
  return st[0];
}
