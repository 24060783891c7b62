/* Play-operator families, linear in their weights (model/prandtl_ishlinskii.h, model/preisach.h).
 * The output is the regressors times the weights summed in order from 0, as RecordModel does.
 * The plays start at rest in the block's initial state (pzk_play_rest). */

/* prandtl-ishlinskii: n plays r_i = u_half (i+1)/(n+1); c = {r_1 .. r_n}; d = {z_1 .. z_n}. */
static inline double pzk_pi_step(const pzk_block *b, const double *c, const double *d, double *o,
                                 double v) {
  double acc = 0;
  int i;
  acc += v * b->w[0];
  for (i = 0; i < b->n; ++i) {
    double z = pzk_play(v, c[i], d[i]);
    o[i] = z;
    acc += z * b->w[1 + i];
  }
  return acc;
}
static inline double pzk_pi_init(const pzk_block *b, double *c, double *d, double v) {
  int i, state = pzk_rest_state(b, v);
  for (i = 0; i < b->n; ++i) {
    c[i] = b->u_half * (i + 1) / (b->n + 1);
    d[i] = pzk_play_rest(v, c[i], state);
  }
  return pzk_pi_step(b, c, d, d, v);
}

/* asymmetric-pi: n plays, m knots z_j = u_min + (u_max - u_min)(j+1)/(m+1);
 * c = {r_1 .. r_n, z_1 .. z_m}; d = {plays}. */
static inline double pzk_asym_pi_step(const pzk_block *b, const double *c, const double *d,
                                      double *o, double v) {
  const int n = b->n, K = b->m;
  double acc = 0;
  int i, j;
  acc += v * b->w[0];
  for (i = 0; i < n; ++i) {
    double z = pzk_play(v, c[i], d[i]);
    o[i] = z;
    acc += z * b->w[1 + i];
  }
  for (j = 0; j < K; ++j) {
    double e = v - c[n + j];
    acc += (e > 0.0 ? e : 0.0) * b->w[1 + n + j];
  }
  for (j = 0; j < K; ++j) {
    double e = v - c[n + j];
    acc += (e < 0.0 ? e : 0.0) * b->w[1 + n + K + j];
  }
  return acc;
}
static inline double pzk_asym_pi_init(const pzk_block *b, double *c, double *d, double v) {
  int i, j, state = pzk_rest_state(b, v);
  for (i = 0; i < b->n; ++i) {
    c[i] = b->u_half * (i + 1) / (b->n + 1);
    d[i] = pzk_play_rest(v, c[i], state);
  }
  for (j = 0; j < b->m; ++j) c[b->n + j] = b->u_min + (b->u_max - b->u_min) * (j + 1) / (b->m + 1);
  return pzk_asym_pi_step(b, c, d, d, v);
}

/* preisach: n levels, delta = (u_max - u_min)/n, widths r_i = 0.5 i delta, cells j = 0 .. n-1-i
 * with lower centres u_min + r_i + j delta, k_i = (u_min + r_i)/(n - i). c = {delta, r_0 ..
 * r_{n-1}, k_0 .. k_{n-1}, centres (n(n+1)/2)}; d = {plays (n)}. */
static inline double pzk_preisach_step(const pzk_block *b, const double *c, const double *d,
                                       double *o, double v) {
  const int n = b->n;
  const double delta = c[0], *r = c + 1, *k = c + 1 + n, *cen = c + 1 + 2 * n, *w = b->w;
  double acc = 0;
  int i, j, q = 0;
  for (i = 0; i < n; ++i) o[i] = pzk_play(v, r[i], d[i]); /* the plays first: a vector loop */
  for (i = 0; i < n; ++i) {
    const double p = o[i], ki = k[i];
    for (j = 0; j < n - i; ++j, ++q)
      acc += (pzk_clamp(p, cen[q], cen[q] + delta) - cen[q] + ki) * w[q];
  }
  return acc;
}
static inline double pzk_preisach_init(const pzk_block *b, double *c, double *d, double v) {
  const int n = b->n;
  double delta = (b->u_max - b->u_min) / n;
  int i, j, q = 0, state = pzk_rest_state(b, v);
  c[0] = delta;
  for (i = 0; i < n; ++i) {
    double r = 0.5 * i * delta;
    c[1 + i] = r;
    c[1 + n + i] = (b->u_min + r) / (n - i);
    for (j = 0; j < n - i; ++j, ++q) c[1 + 2 * n + q] = b->u_min + r + j * delta;
    d[i] = pzk_play_rest(v, r, state);
  }
  return pzk_preisach_step(b, c, d, d, v);
}
