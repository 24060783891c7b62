/* The chain (last part of the kernels): sizes, init, one step forward, one step inverse. A model
 * is an array of blocks in the order drive effects, family, output effects, PZK_AFFINE. Its state
 * is three double arrays: constants c (derived at init), dynamic state d, and scratch t (the same
 * layout as d: the inverse's trial steps write there), plus a pzk_ctl. A new kind adds its kernel
 * file, its entry in pzk_kinds (the table of the kinds' operations) and its pzk_kind_slots. */

typedef struct {
  double u_lo, u_hi;     /* drive limits (the training records' range unless changed) */
  double u_last, y_last; /* the last drive applied / computed and the model's output for it */
  double du_last;        /* the last change of the drive (the inverse's first stride) */
  long saturated;        /* samples whose drive was clipped to a limit */
  double max_clip;       /* largest clipping: drive units (forward), response units (inverse) */
} pzk_ctl;

/* The operations of a block kind, one entry per kind of common.h's enum in the table below:
 * constants and dynamic doubles (nc, nd; sizes when they depend on the block), the state at rest
 * under the drive v (init; u_raw: the drive before the drive effects), one step from state d to o
 * (step; o may be d), and, where the compensator's one-step map differs from the step, that map
 * (inverse) and the step with the fin's angle pushed through its backlash (through, dir = +-1).
 * A missing operation: nothing to set (init returns v), the step itself. */
typedef struct {
  int kind;         /* PZK_* */
  const char *name; /* "PZK_*": what an exported header writes for the kind */
  int nc, nd;
  void (*sizes)(const pzk_block *b, int *nc, int *nd);
  double (*init)(const pzk_block *b, double *c, double *d, double v, double u_raw);
  double (*step)(const pzk_block *b, const double *c, const double *d, double *o, double v);
  double (*inverse)(const pzk_block *b, const double *c, const double *d, double *o, double v);
  double (*through)(const pzk_block *b, const double *c, const double *d, double *o, double v,
                    int dir);
} pzk_kind_ops;

/* The kernels' functions in the table's signatures: PZK_OP_INIT(X, call) defines pzk_op_X_init,
 * PZK_OP_STEP(X, call) pzk_op_X (a step or a compensator's map), PZK_OP_SIZES(X, nc, nd)
 * pzk_op_X_sizes, each returning what `call` (or nc, nd) gives of the table's arguments: the block
 * b, its constants c, its state d, the next state o, the input v (u_raw: the drive, for init). */
#define PZK_OP_INIT(x, call)                                                                 \
  static inline double pzk_op_##x##_init(const pzk_block *b, double *c, double *d, double v, \
                                         double u_raw) {                                     \
    (void)b, (void)c, (void)d, (void)u_raw;                                                  \
    return call;                                                                             \
  }
#define PZK_OP_STEP(x, call)                                                                       \
  static inline double pzk_op_##x(const pzk_block *b, const double *c, const double *d, double *o, \
                                  double v) {                                                      \
    (void)b, (void)c, (void)d, (void)o;                                                            \
    return call;                                                                                   \
  }
#define PZK_OP_SIZES(x, n_c, n_d)                                               \
  static inline void pzk_op_##x##_sizes(const pzk_block *b, int *nc, int *nd) { \
    *nc = n_c;                                                                  \
    *nd = n_d;                                                                  \
  }
PZK_OP_INIT(quadratic, pzk_quadratic_step(b, v))
PZK_OP_INIT(creep, pzk_creep_init(b, c, d, v))
PZK_OP_INIT(delay, pzk_delay_init(b, c, d, v))
PZK_OP_INIT(rate_dependence, pzk_rate_dependence_init(d, v))
PZK_OP_INIT(stack_bw, pzk_stack_bw_init(b, c, d, v))
PZK_OP_INIT(backlash, pzk_backlash_init(b, d, v))
PZK_OP_INIT(duhem, pzk_duhem_init(b, d, v))
PZK_OP_INIT(pi, pzk_pi_init(b, c, d, v))
PZK_OP_INIT(bw_osc, pzk_bw_osc_init(b, c, d, v))
PZK_OP_INIT(preisach, pzk_preisach_init(b, c, d, v))
PZK_OP_INIT(asym_pi, pzk_asym_pi_init(b, c, d, v))
PZK_OP_INIT(fin, pzk_fin_init(b, c, d, v))
PZK_OP_INIT(friction, pzk_friction_init(d, v))
PZK_OP_INIT(stiffening, c[0] = v)
PZK_OP_INIT(drift, (d[0] = 0, v))
PZK_OP_INIT(creep_spectrum, pzk_creep_spectrum_init(b, c, d, v))
PZK_OP_INIT(resonance, pzk_resonance_init(b, c, d, v))
PZK_OP_INIT(affine, b->p[0] * v + b->p[1])
PZK_OP_STEP(lowpass_step, pzk_driver_lowpass_step(c, d, o, v))
PZK_OP_STEP(quadratic_step, pzk_quadratic_step(b, v))
PZK_OP_STEP(delay_step, pzk_delay_step(c, o, v)) /* in place only (o == d) */
PZK_OP_STEP(delay_inverse, pzk_delay_inverse_step(c, d, o, v))
PZK_OP_STEP(rate_dependence_step, pzk_rate_dependence_step(b, d, o, v))
PZK_OP_STEP(backlash_step, pzk_backlash_step(b, d, o, v))
PZK_OP_STEP(duhem_step, pzk_duhem_step(b, d, o, v))
PZK_OP_STEP(friction_step, pzk_friction_step(b, d, o, v))
PZK_OP_STEP(stiffening_step, pzk_stiffening_step(b, c, v))
PZK_OP_STEP(drift_step, pzk_drift_step(b, d, o, v))
PZK_OP_STEP(resonance_step, pzk_resonance_step(c, d, o, v))
PZK_OP_STEP(resonance_inverse, pzk_resonance_inverse_step(c, d, o, v))
PZK_OP_STEP(affine_step, b->p[0] * v + b->p[1])
PZK_OP_SIZES(delay, 3, 1 + pzk_delay_capacity(b) + pzk_delay_inverse_size(pzk_delay_horizon(b)))
PZK_OP_SIZES(pi, b->n, b->n)
PZK_OP_SIZES(asym_pi, b->n + b->m, b->n)
PZK_OP_SIZES(preisach, 1 + 2 * b->n + b->n * (b->n + 1) / 2, b->n)
PZK_OP_SIZES(fin, PZK_FIN_C * b->n, 2 * b->n + 4)
PZK_OP_SIZES(creep_spectrum, 1 + 2 * b->n, 1 + b->n)
#undef PZK_OP_INIT
#undef PZK_OP_STEP
#undef PZK_OP_SIZES

/* One entry per kind, in increasing kind order (tests/model/kernel_forms_test.cc checks the order
 * and that every kind of the enum has its entry). */
#define PZK_KIND(k) .kind = k, .name = #k
static const pzk_kind_ops pzk_kinds[] = {
    {PZK_KIND(PZK_LOWPASS), .nc = 3, .nd = 2, .init = pzk_driver_lowpass_init,
     .step = pzk_op_lowpass_step},
    {PZK_KIND(PZK_QUADRATIC), .init = pzk_op_quadratic_init, .step = pzk_op_quadratic_step},
    {PZK_KIND(PZK_CREEP), .nc = 5, .nd = 2, .init = pzk_op_creep_init, .step = pzk_creep_step},
    {PZK_KIND(PZK_DELAY), .sizes = pzk_op_delay_sizes, .init = pzk_op_delay_init,
     .step = pzk_op_delay_step, .inverse = pzk_op_delay_inverse},
    {PZK_KIND(PZK_RATE_DEPENDENCE), .nd = 4, .init = pzk_op_rate_dependence_init,
     .step = pzk_op_rate_dependence_step},
    {PZK_KIND(PZK_STACK_BOUC_WEN), .nc = 4, .nd = 4, .init = pzk_op_stack_bw_init,
     .step = pzk_stack_bw_step},
    {PZK_KIND(PZK_BACKLASH_LIKE), .nd = 2, .init = pzk_op_backlash_init,
     .step = pzk_op_backlash_step},
    {PZK_KIND(PZK_DUHEM), .nd = 2, .init = pzk_op_duhem_init, .step = pzk_op_duhem_step},
    {PZK_KIND(PZK_PRANDTL_ISHLINSKII), .sizes = pzk_op_pi_sizes, .init = pzk_op_pi_init,
     .step = pzk_pi_step},
    {PZK_KIND(PZK_BW_OSCILLATOR), .nc = 6, .nd = 4, .init = pzk_op_bw_osc_init,
     .step = pzk_bw_osc_step},
    {PZK_KIND(PZK_PREISACH), .sizes = pzk_op_preisach_sizes, .init = pzk_op_preisach_init,
     .step = pzk_preisach_step},
    {PZK_KIND(PZK_ASYMMETRIC_PI), .sizes = pzk_op_asym_pi_sizes, .init = pzk_op_asym_pi_init,
     .step = pzk_asym_pi_step},
    {PZK_KIND(PZK_BIMORPH_FIN), .sizes = pzk_op_fin_sizes, .init = pzk_op_fin_init,
     .step = pzk_fin_step, .through = pzk_fin_step_through},
    {PZK_KIND(PZK_FRICTION), .nd = 1, .init = pzk_op_friction_init, .step = pzk_op_friction_step},
    {PZK_KIND(PZK_STIFFENING), .nc = 1, .init = pzk_op_stiffening_init,
     .step = pzk_op_stiffening_step},
    {PZK_KIND(PZK_DRIFT), .nd = 1, .init = pzk_op_drift_init, .step = pzk_op_drift_step},
    {PZK_KIND(PZK_CREEP_SPECTRUM), .sizes = pzk_op_creep_spectrum_sizes,
     .init = pzk_op_creep_spectrum_init, .step = pzk_creep_spectrum_step},
    {PZK_KIND(PZK_RESONANCE), .nc = 10, .nd = 3, .init = pzk_op_resonance_init,
     .step = pzk_op_resonance_step, .inverse = pzk_op_resonance_inverse},
    {PZK_KIND(PZK_AFFINE), .init = pzk_op_affine_init, .step = pzk_op_affine_step},
};
#undef PZK_KIND
static inline int pzk_num_kinds(void) { return (int)(sizeof pzk_kinds / sizeof pzk_kinds[0]); }

/* Each id's entry in pzk_kinds (-1: none), so that a block's operations are one load away (a
 * search of the table made a chain of light blocks 1.5 times slower than a switch; this, 0.9
 * times); tests/model/kernel_forms_test.cc checks it against the table and the enum. */
static const signed char pzk_kind_slots[PZK_AFFINE + 1] = {
    -1, 0,  1,  2,  3,  4,  -1, -1, -1, -1, /* 0 - 9: drive effects 1 - 5 */
    5,  6,  7,  8,  9,  10, 11, 12, -1, -1, /* 10 - 19: families 10 - 17 */
    -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, /* 20 - 29 */
    13, 14, 15, 16, 17, -1, -1, -1, -1, -1, /* 30 - 39: output effects 30 - 34 */
    18                                      /* 40: PZK_AFFINE */
};

/* The table's entry of a kind; 0 for an unknown one. */
static inline const pzk_kind_ops *pzk_kind_of(int kind) {
  return kind >= 0 && kind <= PZK_AFFINE && pzk_kind_slots[kind] >= 0
             ? &pzk_kinds[pzk_kind_slots[kind]]
             : 0;
}

/* Constants and dynamic doubles a block needs; -1 for an unknown kind. */
static inline int pzk_block_sizes(const pzk_block *b, int *nc, int *nd) {
  const pzk_kind_ops *k = pzk_kind_of(b->kind);
  *nc = 0;
  *nd = 0;
  if (!k) return -1;
  if (k->sizes) {
    k->sizes(b, nc, nd);
  } else {
    *nc = k->nc;
    *nd = k->nd;
  }
  return 0;
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

static inline double pzk_block_init(const pzk_block *b, double *c, double *d, double v,
                                    double u_raw) {
  const pzk_kind_ops *k = pzk_kind_of(b->kind);
  return k && k->init ? k->init(b, c, d, v, u_raw) : v;
}

/* One block's step: reads its state in d, writes the next one to o (o may be d). */
static inline double pzk_block_step(const pzk_block *b, const double *c, const double *d, double *o,
                                    double v) {
  const pzk_kind_ops *k = pzk_kind_of(b->kind);
  return k ? k->step(b, c, d, o, v) : v;
}

/* At rest under the drive u0 (every block at equilibrium); returns the output there. */
static inline double pzk_chain_init(const pzk_block *b, int nb, double *c, double *d, pzk_ctl *ctl,
                                    double u0) {
  double v = u0;
  int i;
  for (i = 0; i < nb; ++i) v = pzk_block_init(&b[i], c + b[i].c_off, d + b[i].d_off, v, u0);
  for (i = 0; i < nb; ++i) /* a delay's horizon: the blocks after it at rest with this output */
    if (b[i].kind == PZK_DELAY && c[b[i].c_off + 2] > 0)
      d[b[i].d_off + 1 + (long)c[b[i].c_off + 1] + 2] = v;
  ctl->u_last = u0;
  ctl->y_last = v;
  ctl->du_last = 0;
  ctl->saturated = 0;
  ctl->max_clip = 0;
  return v;
}

/* How pzk_chain_eval runs the chain: forward; the compensator's one-step map (the delay blocks
 * stepping what remains of their delay once the reference is read ahead: pzk_delay_inverse_step;
 * a resonance block in every mode but forward giving its virtual plant,
 * pzk_resonance_inverse_step);
 * that with the fin's angle pushed up or down through its backlash (pzk_fin_step_through); the
 * delay blocks passing their input on (what a lasting change of the drive meets: a replay's local
 * gain). */
enum {
  PZK_EVAL_FORWARD = 0,
  PZK_EVAL_INVERSE,
  PZK_EVAL_PUSH_UP,
  PZK_EVAL_PUSH_DOWN,
  PZK_EVAL_UNDELAYED
};

/* The output for drive u from state d, the next state written to o (o == d: a step; o the
 * scratch: a trial, which needs a mode other than PZK_EVAL_FORWARD). */
static inline double pzk_chain_eval(const pzk_block *b, int nb, const double *c, const double *d,
                                    double *o, double u, int mode) {
  double v = u;
  int i;
  for (i = 0; i < nb; ++i) {
    const pzk_kind_ops *k = pzk_kind_of(b[i].kind);
    const double *ci = c + b[i].c_off, *di = d + b[i].d_off;
    double *oi = o + b[i].d_off;
    if (!k || (b[i].kind == PZK_DELAY && mode == PZK_EVAL_UNDELAYED)) continue;
    if (k->through && (mode == PZK_EVAL_PUSH_UP || mode == PZK_EVAL_PUSH_DOWN))
      v = k->through(&b[i], ci, di, oi, v, mode == PZK_EVAL_PUSH_UP ? 1 : -1);
    else if (k->inverse && mode != PZK_EVAL_FORWARD)
      v = k->inverse(&b[i], ci, di, oi, v);
    else
      v = k->step(&b[i], ci, di, oi, v);
  }
  return v;
}

/* Forward step: the drive clipped to [u_lo, u_hi] (counted), the model's output. */
static inline double pzk_chain_step(const pzk_block *b, int nb, const double *c, double *d,
                                    pzk_ctl *ctl, double u) {
  double clipped = pzk_clamp(u, ctl->u_lo, ctl->u_hi);
  if (clipped != u) {
    double excess = fabs(u - clipped);
    ++ctl->saturated;
    if (excess > ctl->max_clip) ctl->max_clip = excess;
  }
  ctl->du_last = clipped - ctl->u_last;
  ctl->u_last = clipped;
  ctl->y_last = pzk_chain_eval(b, nb, c, d, d, clipped, PZK_EVAL_FORWARD);
  return ctl->y_last;
}

/* Samples ahead of the drive it computes that the compensator wants the reference: each delay's
 * pzk_delay_preview, one more when it plans two samples (pzk_chain_inverse_fin). */
static inline int pzk_chain_plans(const pzk_block *b, int nb) {
  int i;
  for (i = 0; i < nb; ++i)
    if (b[i].kind == PZK_BIMORPH_FIN ||
        (b[i].kind == PZK_RATE_DEPENDENCE && pzk_rate_dependence_plans(&b[i])))
      return 1;
  return 0;
}
static inline long pzk_chain_preview(const pzk_block *b, int nb, const double *c) {
  long preview = pzk_chain_plans(b, nb);
  int i;
  for (i = 0; i < nb; ++i)
    if (b[i].kind == PZK_DELAY) preview += pzk_delay_preview(c + b[i].c_off);
  return preview;
}

/* The two-sample compensator of a chain that one sample cannot invert: the bimorph fin's (a chain
 * holding a PZK_BIMORPH_FIN block), after the HGANN fin plant's header (controller/export_fin_c.h
 * pzf_inverse_step), and a chain whose rate-dependence lags over a quarter sample
 * (pzk_rate_dependence_plans: its one-step inverse is unstable; planned, the drive stays within a
 * few tenths of a volt of a model's own on the rate sets of docs/deploy.md). It plans two samples:
 * the drive goes to u at the next sample and keeps its slope from the last drive one more (clipped
 * to the limits), and u is solved so that the output two samples ahead is y_desired: give it the
 * reference one sample ahead (preview), else it follows with a lag of one sample. One sample would
 * not do: the drive's linear hold gives the sampled modes a zero outside the unit circle (the
 * second sample's response to a drive step is several times the first's), and an exact one-step
 * inverse makes the drive oscillate. The backlash is passed through: where the angle must rise
 * (fall) to reach y_desired, the trials give the fin's output as theta - a1 (theta + a2), the angle
 * it reaches once theta has crossed the dead band, so that a target beyond the band drives theta
 * across it rather than holding (an angle that must stay: the trials are the model's). The map u ->
 * y need not be monotone (at small drives the Bouc-Wen force can outweigh the drive's moment): the
 * bracket is searched on both sides of the last drive with steps growing 4-fold from 1e-3 of the
 * drive range, the sign change nearest to it taken, and closed by the Illinois method until the
 * output is y_desired to 1e-13 of its magnitude (at least 1e-13) or the bracket is two adjacent
 * doubles: at most 100 plans of two steps. Not reached within the limits: the drive that came
 * nearest, counted in saturated (max_clip: the largest shortfall). What it reaches is not exact:
 * the plan is greedy, and a reference whose state came by another path (the Bouc-Wen force
 * remembers it) can be out of reach for some samples (docs/deploy.md has the figures). */
typedef struct {
  const pzk_block *b;
  int nb, mode;
  const double *c, *d;
  double *t, u_prev, lo, hi, y_desired;
} pzk_fin_plan;
/* The output two samples ahead less y_desired: the drive u at the next sample, its slope kept one
 * more (clipped), from state d on the scratch t (the compensator's chain; PZK_EVAL_PUSH_UP / DOWN:
 * the fin pushed through). */
static inline double pzk_fin_plan_miss(void *ctx, double u) {
  const pzk_fin_plan *p = (const pzk_fin_plan *)ctx;
  pzk_chain_eval(p->b, p->nb, p->c, p->d, p->t, u, p->mode);
  return pzk_chain_eval(p->b, p->nb, p->c, p->t, p->t, pzk_clamp(u + (u - p->u_prev), p->lo, p->hi),
                        p->mode) -
         p->y_desired;
}
static inline double pzk_chain_inverse_fin(const pzk_block *b, int nb, const double *c, double *d,
                                           double *t, pzk_ctl *ctl, double y_desired) {
  pzk_fin_plan plan;
  double s_out = 1, u;
  int i, after = 0;
  /* The direction the fin's angle must move: the output's against the last, times the sign of the
   * output per angle (the gain, and the polarity; the output effects rise with their input). */
  for (i = 0; i < nb; ++i) {
    if (b[i].kind == PZK_BIMORPH_FIN) {
      after = 1;
      s_out = b[i].p[9] < 0 ? -1 : 1;
    } else if (after && b[i].kind == PZK_AFFINE && b[i].p[0] < 0) {
      s_out = -s_out;
    }
  }
  plan.b = b;
  plan.nb = nb;
  plan.c = c;
  plan.d = d;
  plan.t = t;
  plan.u_prev = ctl->u_last;
  plan.lo = ctl->u_lo;
  plan.hi = ctl->u_hi;
  plan.y_desired = y_desired;
  plan.mode = (y_desired - ctl->y_last) * s_out > 0   ? PZK_EVAL_PUSH_UP
              : (y_desired - ctl->y_last) * s_out < 0 ? PZK_EVAL_PUSH_DOWN
                                                      : PZK_EVAL_INVERSE;
  if (!pzk_fin_nearest_root(pzk_fin_plan_miss, &plan, pzk_clamp(ctl->u_last, plan.lo, plan.hi),
                            plan.lo, plan.hi, 1e-13 * (fabs(y_desired) > 1 ? fabs(y_desired) : 1),
                            100, &u)) {
    const double miss = fabs(pzk_fin_plan_miss(&plan, u));
    ++ctl->saturated;
    if (miss > ctl->max_clip) ctl->max_clip = miss;
  }
  ctl->du_last = u - ctl->u_last;
  ctl->u_last = u;
  ctl->y_last = pzk_chain_eval(b, nb, c, d, d, u, PZK_EVAL_INVERSE);
  return u;
}

/* The one-step inverse (pzk_chain_inverse without a delay's horizon): the drive u in [u_lo, u_hi]
 * whose one-step output from the present state is y_desired, then the state advanced with it. The
 * one-step map u -> y is evaluated on the scratch t. From the last drive, the search walks in the
 * direction the map must move (by its local slope's sign; where it is flat, by its sign over the
 * limits), with a stride of 1.5 times the last drive change, doubled until the reference is passed;
 * then the bracket is closed by regula falsi with the Illinois rule and a bisection every fourth
 * step, until the output is the reference to 1e-15 of the outputs' magnitude or the bracket is two
 * adjacent doubles (about 5 to 10 evaluations of the map per sample; at most 200): the nearest
 * drive with that output. Exact for the families monotone on each step: Prandtl-Ishlinskii,
 * asymmetric PI and Preisach with weights >= 0, backlash-like with alpha >= 0 and B1 >= c/2 > 0
 * (its slope after a reversal is at least 2 B1 - c). For the rate-dependent ones (Bouc-Wen, Duhem,
 * oscillator, the filters) the one-step map is continuous and the root found is the one nearest the
 * last drive. A reference the limits cannot reach gives the limit, counted in saturated, the
 * shortfall in max_clip. The bimorph fin and a rate-dependence lag over a quarter sample plan two
 * samples (pzk_chain_inverse_fin). A delay's fraction up to a half stays in the map solved
 * (pzk_delay_inverse_step). */
static inline double pzk_chain_solve(const pzk_block *b, int nb, const double *c, double *d,
                                     double *t, pzk_ctl *ctl, double y_desired) {
  const double lo = ctl->u_lo, hi = ctl->u_hi, span = hi - lo;
  double u0 = pzk_clamp(ctl->u_last, lo, hi), f0, f1, sign, ref, u, eps = 1e-9 * span;
  if (pzk_chain_plans(b, nb)) return pzk_chain_inverse_fin(b, nb, c, d, t, ctl, y_desired);
  f0 = pzk_chain_eval(b, nb, c, d, t, u0, PZK_EVAL_INVERSE);
  if (u0 + eps < hi) {
    f1 = pzk_chain_eval(b, nb, c, d, t, u0 + eps, PZK_EVAL_INVERSE);
    sign = f1 > f0 ? 1.0 : (f1 < f0 ? -1.0 : 0.0);
  } else {
    f1 = pzk_chain_eval(b, nb, c, d, t, u0 - eps, PZK_EVAL_INVERSE);
    sign = f1 < f0 ? 1.0 : (f1 > f0 ? -1.0 : 0.0);
  }
  if (sign == 0)
    sign = pzk_chain_eval(b, nb, c, d, t, hi, PZK_EVAL_INVERSE) >=
                   pzk_chain_eval(b, nb, c, d, t, lo, PZK_EVAL_INVERSE)
               ? 1.0
               : -1.0;
  ref = sign * y_desired; /* work on the rising map sign * f */
  f0 *= sign;
  if (f0 == ref) {
    u = u0;
  } else {
    /* Walk from u0 towards the reference: up when the output must rise, else down. g = dir (f -
     * ref) is < 0 at the near end a of the bracket and >= 0 at its far end e. */
    const double dir = ref > f0 ? 1.0 : -1.0, limit = dir > 0 ? hi : lo;
    double a = u0, fa = f0, e, fe, stride = 1.5 * fabs(ctl->du_last), tol;
    if (stride < 1e-6 * span) stride = 1e-6 * span;
    for (;;) {
      e = a + dir * stride;
      if (dir > 0 ? !(e < hi) : !(e > lo)) e = limit;
      fe = sign * pzk_chain_eval(b, nb, c, d, t, e, PZK_EVAL_INVERSE);
      if (dir * (fe - ref) >= 0 || e == limit) break;
      a = e;
      fa = fe;
      stride *= 2;
    }
    if (dir * (fe - ref) < 0) { /* the limit cannot reach the reference (by more than rounding) */
      u = limit;
      if (dir * (ref - fe) > 1e-13 * (fabs(fe) + fabs(ref))) {
        ++ctl->saturated;
        if (dir * (ref - fe) > ctl->max_clip) ctl->max_clip = dir * (ref - fe);
      }
    } else {
      double ga = dir * (fa - ref), ge = dir * (fe - ref);
      int it, side = 0;
      tol = 1e-15 * (fabs(fa) + fabs(fe) + fabs(ref));
      for (it = 0; it < 200 && dir * (fe - ref) > tol; ++it) {
        double x = a - ga * (e - a) / (ge - ga), fx, gx;
        if (it % 4 == 3 || !((x - a) * (e - x) > 0)) x = a + 0.5 * (e - a);
        if (!((x - a) * (e - x) > 0)) break; /* adjacent doubles */
        fx = sign * pzk_chain_eval(b, nb, c, d, t, x, PZK_EVAL_INVERSE);
        gx = dir * (fx - ref);
        if (gx < 0) {
          if (-gx <= tol) {
            e = x;
            fe = fx;
            ge = -gx;
            break;
          }
          a = x;
          fa = fx;
          ga = gx;
          if (side == -1) ge *= 0.5; /* Illinois: the far end kept twice */
          side = -1;
        } else {
          e = x;
          fe = fx;
          ge = gx;
          if (side == 1) ga *= 0.5;
          side = 1;
        }
      }
      u = fabs(fe - ref) <= fabs(ref - fa) ? e : a;
    }
  }
  ctl->du_last = u - ctl->u_last;
  ctl->u_last = u;
  ctl->y_last = pzk_chain_eval(b, nb, c, d, d, u, PZK_EVAL_INVERSE);
  return u;
}

/* The compensator with a delay whose fraction is over a half (its horizon L > 0, model/kernels/
 * effects.h): the blocks after the delay solved one step for its output w, n + L samples ahead of
 * the drive (their own limits, last drive and output kept in the delay's state: the drive's limits,
 * widened by their span on both sides when drive effects come before the delay, which may take
 * their output beyond it); the delay undone backwards over the horizon (pzk_delay_anticausal); the
 * blocks before it solved one step for that input x (none: x is the drive, clipped to the limits).
 * A sample either stage clips counts once in saturated; max_clip takes the shortfall of the stage
 * after the delay (response units). The blocks after the delay follow the solved w, not a clipped
 * drive's. */
static inline double pzk_chain_solve_after(const pzk_block *b, int nb, int id, const double *c,
                                           double *d, double *t, const pzk_ctl *ctl,
                                           double y_desired, pzk_ctl *post) {
  double *q =
      d + b[id].d_off + 1 + (long)c[b[id].c_off + 1]; /* head, w_last, y_last, dw_last, ... */
  const double widen = id > 0 ? ctl->u_hi - ctl->u_lo : 0;
  double w;
  post->u_lo = ctl->u_lo - widen;
  post->u_hi = ctl->u_hi + widen;
  post->u_last = q[1];
  post->y_last = q[2];
  post->du_last = q[3];
  post->saturated = 0;
  post->max_clip = 0;
  w = pzk_chain_solve(b + id + 1, nb - id - 1, c, d, t, post, y_desired);
  q[1] = post->u_last;
  q[2] = post->y_last;
  q[3] = post->du_last;
  return w;
}
static inline double pzk_chain_inverse_split(const pzk_block *b, int nb, int id, const double *c,
                                             double *d, double *t, pzk_ctl *ctl, double y_desired) {
  const double span = ctl->u_hi - ctl->u_lo, max_clip = ctl->max_clip;
  const long saturated = ctl->saturated;
  pzk_ctl post;
  double x, u;
  int clipped;
  x = pzk_chain_solve_after(b, nb, id, c, d, t, ctl, y_desired, &post);
  x = pzk_delay_anticausal(c + b[id].c_off, d + b[id].d_off, x);
  if (id > 0) {
    u = pzk_chain_solve(b, id, c, d, t, ctl, x);
    clipped = ctl->saturated != saturated;
  } else { /* rounding of the sum at a limit is no clipping */
    u = pzk_clamp(x, ctl->u_lo, ctl->u_hi);
    clipped = fabs(u - x) > 1e-12 * span;
    ctl->du_last = u - ctl->u_last;
    ctl->u_last = u;
  }
  ctl->saturated = saturated + (clipped || post.saturated > 0 ? 1 : 0);
  ctl->max_clip = post.max_clip > max_clip ? post.max_clip : max_clip;
  ctl->y_last = post.y_last;
  return u;
}

/* The references a delay's horizon wants before the first inverse step after init (0 without one):
 * those of the L samples before the first step's, in order (pzk_chain_inverse_prime). */
static inline int pzk_chain_prime_samples(const pzk_block *b, int nb, const double *c) {
  int i;
  for (i = 0; i < nb; ++i)
    if (b[i].kind == PZK_DELAY && c[b[i].c_off + 2] > 0) return (int)c[b[i].c_off + 2];
  return 0;
}
/* One of them: the blocks after the delay solved for it (as a step does; a reference out of reach
 * counted). Returns 0, or -1 when no more is wanted (no horizon, all given, or a step taken); not
 * given, the blocks after the delay take those samples at rest. */
static inline int pzk_chain_inverse_prime(const pzk_block *b, int nb, const double *c, double *d,
                                          double *t, pzk_ctl *ctl, double y_desired) {
  pzk_ctl post;
  double w;
  int id;
  for (id = 0; id < nb; ++id)
    if (b[id].kind == PZK_DELAY && c[b[id].c_off + 2] > 0) break;
  if (id == nb || d[b[id].d_off + 1 + (long)c[b[id].c_off + 1] + 4] >= c[b[id].c_off + 2])
    return -1;
  w = pzk_chain_solve_after(b, nb, id, c, d, t, ctl, y_desired, &post);
  if (post.saturated > 0) ++ctl->saturated;
  if (post.max_clip > ctl->max_clip) ctl->max_clip = post.max_clip;
  return pzk_delay_prime(c + b[id].c_off, d + b[id].d_off, w);
}

/* Inverse step (the compensator): the drive u in [u_lo, u_hi] for the desired output y_desired,
 * then the state advanced with it. A delay cannot be undone by a causal step: give the compensator
 * the reference pzk_chain_preview samples ahead (a delay's whole samples and its horizon; one more
 * with a two-sample plan). A delay's fraction up to a half stays in the one-step map solved
 * (pzk_chain_solve); over a half the delay is undone backwards over its horizon
 * (pzk_chain_inverse_split). */
static inline double pzk_chain_inverse(const pzk_block *b, int nb, const double *c, double *d,
                                       double *t, pzk_ctl *ctl, double y_desired) {
  long lead = 0;
  int i;
  /* A drift after a delay: its clock is that of the output solved, the delays' preview ahead of the
   * drive (set at the first step after init, where it is 0; it only grows after). */
  for (i = 0; i < nb; ++i) {
    if (b[i].kind == PZK_DELAY) lead += pzk_delay_preview(c + b[i].c_off);
    if (b[i].kind == PZK_DRIFT && d[b[i].d_off] == 0) d[b[i].d_off] = (double)lead;
  }
  for (i = 0; i < nb; ++i)
    if (b[i].kind == PZK_DELAY && c[b[i].c_off + 2] > 0)
      return pzk_chain_inverse_split(b, nb, i, c, d, t, ctl, y_desired);
  return pzk_chain_solve(b, nb, c, d, t, ctl, y_desired);
}
