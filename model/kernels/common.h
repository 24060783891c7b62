/* piezoid step kernels, part 1 of the one source (model/kernels/pzk.h, docs/deploy.md): the block
 * descriptor and the exact-integration helpers. Plain C99 over double arrays, compiled into the
 * C++ stepper (records/stepper.cc) and copied verbatim into every header `piezoid export` writes.
 * Nothing here allocates, keeps a global or needs more than <math.h>. */

/* A block of the chain drive -> drive effects -> family -> output effects -> polarity/offset. */
enum {
  PZK_LOWPASS = 1,
  PZK_QUADRATIC,
  PZK_CREEP,
  PZK_DELAY,
  PZK_RATE_DEPENDENCE, /* drive effects (records/model.h order) */
  PZK_STACK_BOUC_WEN = 10,
  PZK_BACKLASH_LIKE,
  PZK_DUHEM,
  PZK_PRANDTL_ISHLINSKII,
  PZK_BW_OSCILLATOR,
  PZK_PREISACH,
  PZK_ASYMMETRIC_PI,
  PZK_BIMORPH_FIN, /* families */
  PZK_FRICTION = 30,
  PZK_STIFFENING,
  PZK_DRIFT,          /* output effects */
  PZK_CREEP_SPECTRUM, /* output effect (first of the output stage) */
  PZK_RESONANCE,      /* output effect (a second-order mode, after the creep spectrum) */
  PZK_AFFINE = 40     /* y = polarity * v + offset */
};

typedef struct {
  int kind;  /* PZK_* */
  int n;     /* plays (PI, asymmetric PI), grid levels (Preisach), sub-steps (stack Bouc-Wen),
                RK4 steps per sample (oscillator), knots (asymmetric PI: in m),
                modes (bimorph fin) */
  int m;     /* asymmetric PI: dead-zone knots; oscillator: 1 = physical parameters */
  double dt; /* sample step [s] */
  double u_min, u_max, u_half, y_half; /* the data scale the family was made for */
  const double *p; /* parameters (the family's, the effect's, or {polarity, offset}) */
  int np;
  const double *w; /* solved weights of a linear family; the bimorph fin's modal data; the creep
                      spectrum's relaxation times */
  int nw;
  int c_off, d_off; /* offsets of the block's constants and dynamic state (pzk_layout) */
  int init;         /* the family's memory at rest (model/prandtl_ishlinskii.h InitialState):
                       PZK_CENTRED, PZK_DESCENDED, PZK_ASCENDED or PZK_AUTO */
} pzk_block;

enum { PZK_CENTRED = 0, PZK_DESCENDED = 1, PZK_ASCENDED = 2, PZK_AUTO = 3 };

/* The block's state at rest under v: PZK_AUTO resolved on the data's drive range (descended within
 * 5 % of its bottom, ascended within 5 % of its top, else centred: ResolveInitialState). */
static inline int pzk_rest_state(const pzk_block *b, double v) {
  double margin;
  if (b->init != PZK_AUTO) return b->init;
  margin = 0.05 * (b->u_max - b->u_min);
  return v <= b->u_min + margin ? PZK_DESCENDED
                                : (v >= b->u_max - margin ? PZK_ASCENDED : PZK_CENTRED);
}

/* phi(z) = (1 - e^-z)/z, phi(0) = 1 (model/stack_models.cc). */
static inline double pzk_phi(double z) {
  if (fabs(z) < 3e-3) return 1.0 + z * (-0.5 + z * (1.0 / 6.0 - z * (1.0 / 24.0)));
  return -expm1(-z) / z;
}

/* L(z) = log1p(z)/z, L(0) = 1. */
static inline double pzk_log_ratio(double z) {
  if (fabs(z) < 1e-8) return 1.0 - 0.5 * z;
  return log1p(z) / z;
}

/* The play (backlash) operator of half-width r from state z. */
static inline double pzk_play(double u, double r, double z) {
  double lo = u - r, hi = u + r;
  double m = hi < z ? hi : z; /* min(u + r, z) */
  return lo > m ? lo : m;     /* max(u - r, .) */
}

/* A play of half-width r at rest at u in state init: u, u + r (descended) or u - r (ascended). */
static inline double pzk_play_rest(double u, double r, int init) {
  return init == PZK_DESCENDED ? u + r : (init == PZK_ASCENDED ? u - r : u);
}

static inline double pzk_clamp(double x, double lo, double hi) {
  return x < lo ? lo : (hi < x ? hi : x);
}
