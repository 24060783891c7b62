/* The chain (last part of the kernels): sizes, init, one step forward, one step inverse. A model
 * is an array of blocks in the order drive effects, family, output effects, PZK_AFFINE. Its state
 * is three double arrays: constants c (derived at init), dynamic state d, and scratch t (the same
 * layout as d: the inverse's trial steps write there), plus a pzk_ctl. A new family adds its
 * kernel file and one case in pzk_block_sizes, pzk_block_init and pzk_block_step. */

typedef struct {
  double u_lo, u_hi;      /* drive limits (the training records' range unless changed) */
  double u_last, y_last;  /* the last drive applied / computed and the model's output for it */
  long saturated;         /* samples whose drive was clipped to a limit */
  double max_clip;        /* largest clipping: drive units (forward), response units (inverse) */
} pzk_ctl;

/* Constants and dynamic doubles a block needs; -1 for an unknown kind. */
static inline int pzk_block_sizes(const pzk_block *b, int *nc, int *nd) {
  int n = b->n;
  *nc = 0;
  *nd = 0;
  switch (b->kind) {
    case PZK_LOWPASS: *nc = 3; *nd = 2; return 0;
    case PZK_QUADRATIC: return 0;
    case PZK_CREEP: *nc = 5; *nd = 2; return 0;
    case PZK_DELAY: *nc = 2; *nd = 1 + pzk_delay_capacity(b); return 0;
    case PZK_STACK_BOUC_WEN: *nc = 4; *nd = 4; return 0;
    case PZK_BACKLASH_LIKE: *nd = 2; return 0;
    case PZK_DUHEM: *nd = 2; return 0;
    case PZK_PRANDTL_ISHLINSKII: *nc = n; *nd = n; return 0;
    case PZK_ASYMMETRIC_PI: *nc = n + b->m; *nd = n; return 0;
    case PZK_PREISACH: *nc = 1 + 2 * n + n * (n + 1) / 2; *nd = n; return 0;
    case PZK_BW_OSCILLATOR: *nc = 6; *nd = 4; return 0;
    case PZK_FRICTION: *nd = 1; return 0;
    case PZK_STIFFENING: *nc = 1; return 0;
    case PZK_DRIFT: *nd = 1; return 0;
    case PZK_AFFINE: return 0;
    default: return -1;
  }
}

/* Sets c_off / d_off of every block; returns 0, or -1 - i for an unknown kind at block i. */
static inline int pzk_layout(pzk_block *b, int nb, int *nc_total, int *nd_total) {
  int i, nc, nd;
  *nc_total = 0;
  *nd_total = 0;
  for (i = 0; i < nb; ++i) {
    if (pzk_block_sizes(&b[i], &nc, &nd) != 0) return -1 - i;
    b[i].c_off = *nc_total;
    b[i].d_off = *nd_total;
    *nc_total += nc;
    *nd_total += nd;
  }
  return 0;
}

static inline double pzk_block_init(const pzk_block *b, double *c, double *d, double v, double u_raw) {
  switch (b->kind) {
    case PZK_LOWPASS: return pzk_driver_lowpass_init(b, c, d, v, u_raw);
    case PZK_QUADRATIC: return pzk_quadratic_step(b, v);
    case PZK_CREEP: return pzk_creep_init(b, c, d, v, u_raw);
    case PZK_DELAY: return pzk_delay_init(b, c, d, v);
    case PZK_STACK_BOUC_WEN: return pzk_stack_bw_init(b, c, d, v);
    case PZK_BACKLASH_LIKE: return pzk_backlash_init(b, d, v);
    case PZK_DUHEM: return pzk_duhem_init(b, d, v);
    case PZK_PRANDTL_ISHLINSKII: return pzk_pi_init(b, c, d, v);
    case PZK_ASYMMETRIC_PI: return pzk_asym_pi_init(b, c, d, v);
    case PZK_PREISACH: return pzk_preisach_init(b, c, d, v);
    case PZK_BW_OSCILLATOR: return pzk_bw_osc_init(b, c, d, v);
    case PZK_FRICTION: return pzk_friction_init(d, v);
    case PZK_STIFFENING: c[0] = v; return v;
    case PZK_DRIFT: d[0] = 0; return v;
    case PZK_AFFINE: return b->p[0] * v + b->p[1];
    default: return v;
  }
}

/* One block's step: reads its state in d, writes the next one to o (o may be d). */
static inline double pzk_block_step(const pzk_block *b, const double *c, const double *d, double *o, double v) {
  switch (b->kind) {
    case PZK_LOWPASS: return pzk_driver_lowpass_step(c, d, o, v);
    case PZK_QUADRATIC: return pzk_quadratic_step(b, v);
    case PZK_CREEP: return pzk_creep_step(b, c, d, o, v);
    case PZK_DELAY: return pzk_delay_step(c, o, v); /* in place only (o == d) */
    case PZK_STACK_BOUC_WEN: return pzk_stack_bw_step(b, c, d, o, v);
    case PZK_BACKLASH_LIKE: return pzk_backlash_step(b, d, o, v);
    case PZK_DUHEM: return pzk_duhem_step(b, d, o, v);
    case PZK_PRANDTL_ISHLINSKII: return pzk_pi_step(b, c, d, o, v);
    case PZK_ASYMMETRIC_PI: return pzk_asym_pi_step(b, c, d, o, v);
    case PZK_PREISACH: return pzk_preisach_step(b, c, d, o, v);
    case PZK_BW_OSCILLATOR: return pzk_bw_osc_step(b, c, d, o, v);
    case PZK_FRICTION: return pzk_friction_step(b, d, o, v);
    case PZK_STIFFENING: return pzk_stiffening_step(b, c, v);
    case PZK_DRIFT: return pzk_drift_step(b, d, o, v);
    case PZK_AFFINE: return b->p[0] * v + b->p[1];
    default: return v;
  }
}

/* At rest under the drive u0 (every block at equilibrium); returns the output there. */
static inline double pzk_chain_init(const pzk_block *b, int nb, double *c, double *d, pzk_ctl *ctl, double u0) {
  double v = u0;
  int i;
  for (i = 0; i < nb; ++i) v = pzk_block_init(&b[i], c + b[i].c_off, d + b[i].d_off, v, u0);
  ctl->u_last = u0;
  ctl->y_last = v;
  ctl->saturated = 0;
  ctl->max_clip = 0;
  return v;
}

/* The output for drive u from state d, the next state written to o (o == d: a step; o the
 * scratch: a trial, which needs skip_delay). skip_delay: the delay blocks pass their input on. */
static inline double pzk_chain_eval(const pzk_block *b, int nb, const double *c, const double *d, double *o, double u,
                                    int skip_delay) {
  double v = u;
  int i;
  for (i = 0; i < nb; ++i) {
    if (b[i].kind == PZK_DELAY && skip_delay) continue;
    v = pzk_block_step(&b[i], c + b[i].c_off, d + b[i].d_off, o + b[i].d_off, v);
  }
  return v;
}

/* Forward step: the drive clipped to [u_lo, u_hi] (counted), the model's output. */
static inline double pzk_chain_step(const pzk_block *b, int nb, const double *c, double *d, pzk_ctl *ctl, double u) {
  double clipped = pzk_clamp(u, ctl->u_lo, ctl->u_hi);
  if (clipped != u) {
    double excess = fabs(u - clipped);
    ++ctl->saturated;
    if (excess > ctl->max_clip) ctl->max_clip = excess;
  }
  ctl->u_last = clipped;
  ctl->y_last = pzk_chain_eval(b, nb, c, d, d, clipped, 0);
  return ctl->y_last;
}

/* Inverse step (the compensator): the drive u in [u_lo, u_hi] whose one-step output from the
 * present state is y_desired, then the state advanced with it. The one-step map u -> y is evaluated
 * on the scratch t. From the last drive, the search walks in the direction the map must move (its
 * local slope's sign; where it is flat, the sign over the limits), doubling its stride (from 1/1000
 * of the limits' span) until the reference is passed, then bisects that bracket down to adjacent
 * doubles (at most 2100 halvings, about 50 in practice): the nearest drive with that output.
 * Exact for the families monotone on each step: Prandtl-Ishlinskii, asymmetric PI and Preisach
 * with weights >= 0, backlash-like with alpha >= 0 and B1 >= c/2 > 0 (its slope after a reversal
 * is at least 2 B1 - c). For the rate-dependent ones (Bouc-Wen, Duhem, oscillator, the filters)
 * the one-step map is continuous and the root found is the one nearest the last drive. A
 * reference the limits cannot reach gives the limit, counted in saturated, the shortfall in
 * max_clip. A delay cannot be undone: its block is skipped (the compensator drives the model
 * without its delay; give it the reference tau_d ahead where the reference is known: preview). */
static inline double pzk_chain_inverse(const pzk_block *b, int nb, const double *c, double *d, double *t, pzk_ctl *ctl,
                                       double y_desired) {
  const double lo = ctl->u_lo, hi = ctl->u_hi, span = hi - lo;
  double u0 = pzk_clamp(ctl->u_last, lo, hi), f0, sign, ref, a, fa, bb, fb, stride, u, eps = 1e-9 * span;
  int it;
  f0 = pzk_chain_eval(b, nb, c, d, t, u0, 1);
  fa = pzk_chain_eval(b, nb, c, d, t, u0 + eps < hi ? u0 + eps : hi, 1);
  fb = pzk_chain_eval(b, nb, c, d, t, u0 - eps > lo ? u0 - eps : lo, 1);
  if (fa == fb) {
    fa = pzk_chain_eval(b, nb, c, d, t, hi, 1);
    fb = pzk_chain_eval(b, nb, c, d, t, lo, 1);
  }
  sign = fa >= fb ? 1.0 : -1.0; /* work on the rising map sign * f */
  ref = sign * y_desired;
  f0 *= sign;
  if (f0 == ref) {
    u = u0;
  } else {
    /* Walk from u0 towards the reference: up when the output must rise, else down. */
    double dir = ref > f0 ? 1.0 : -1.0, limit = dir > 0 ? hi : lo;
    a = u0;
    fa = f0;
    stride = 1e-3 * span;
    for (;;) {
      bb = a + dir * stride;
      if (dir > 0 ? !(bb < hi) : !(bb > lo)) bb = limit;
      fb = sign * pzk_chain_eval(b, nb, c, d, t, bb, 1);
      if (dir * (fb - ref) >= 0 || bb == limit) break;
      a = bb;
      fa = fb;
      stride *= 2;
    }
    if (dir * (fb - ref) < 0) { /* the limit cannot reach the reference */
      u = limit;
      ++ctl->saturated;
      if (dir * (ref - fb) > ctl->max_clip) ctl->max_clip = dir * (ref - fb);
    } else {
      /* fa on the near side of ref, fb on (or at) the far side: bisect [a, bb]. */
      for (it = 0; it < 2100; ++it) {
        double mid = a + 0.5 * (bb - a), fm;
        if (!(mid != a && mid != bb)) break;
        fm = sign * pzk_chain_eval(b, nb, c, d, t, mid, 1);
        if (fm == ref) {
          a = bb = mid;
          fa = fb = fm;
          break;
        }
        if (dir * (fm - ref) < 0) {
          a = mid;
          fa = fm;
        } else {
          bb = mid;
          fb = fm;
        }
      }
      u = fabs(fb - ref) <= fabs(ref - fa) ? bb : a;
    }
  }
  ctl->u_last = u;
  ctl->y_last = pzk_chain_eval(b, nb, c, d, d, u, 1);
  return u;
}
