/* The HGANN fin plant of `piezoid export --plant` (controller/export_fin_c.h): ModalSimulator's
 * sampled-drive recursion (u linear between samples, model/modal_simulator.h), one sample period
 * PZF_DT at a time, forward (pzf_step) and inverse (pzf_inverse_step). Plain C99, embedded byte for
 * byte by the build (controller/CMakeLists.txt) and written into the exported header after the
 * modal helpers (model/kernels/fin_modal.h, the records bimorph-fin kernel's too: one source of the
 * step) and the plant's tables, which controller/export_fin_c.cc writes: PZF_MODES,
 * PZF_MODES_PADDED, PZF_DT, PZF_INV_LENGTH, PZF_U_MIN, PZF_U_MAX, PZF_AMPLITUDE_LO / _HI,
 * PZF_FREQUENCY_LO / _HI, PZF_INVERSE_ITERATIONS, PZF_INVERSE_HORIZON, PZF_NETWORK (the network's
 * function) and pzf_omega2(), pzf_tip_gain_u(), pzf_tip_gain_z(); it gives the names the header's
 * prefix. tests/client/export_fin_c_test.cc compiles the header with the C compiler and steps it
 * against the library. */

/* Status bits: returned by pzf_params / pzf_init, accumulated in state.status. */
#define PZF_OK 0
#define PZF_AMPLITUDE_OUT_OF_RANGE 1 /* amplitude outside the training range: p extrapolated */
#define PZF_FREQUENCY_OUT_OF_RANGE 2 /* frequency outside the training range: p extrapolated */
#define PZF_INVALID_INPUT 4          /* a non-finite input (ignored: the drive is held) */
/* init: a parameter non-finite or out of its physical range */
#define PZF_INVALID_PARAMETERS 8
/* init: alpha != 0 and not (beta + gamma > 0, beta - gamma >= 0) */
#define PZF_UNBOUNDED_HYSTERESIS 16
#define PZF_NOT_FINITE 32 /* the state became non-finite (the step was not taken) */
/* inverse: the desired angle was not reachable in one step */
#define PZF_UNREACHABLE 64

/* What one sample changes (saved and restored by the inverse's trial steps). */
typedef struct {
  double x0[PZF_MODES_PADDED],
      x1[PZF_MODES_PADDED]; /* modal states scaled by tip_i: w_tip = sum x0 */
  double u;                 /* drive at the last sample [V] */
  double z;                 /* Bouc-Wen force [N] */
  double theta;             /* linear fin angle atan(w_tip / L) [deg] */
  double y;                 /* fin angle after the backlash [deg] */
} pzf_dynamic;

typedef struct {
  double mu, delta, alpha, beta, gamma, a1, a2, b1, b2, kappa_max;
  double u_min, u_max; /* drive limits [V] (PZF_U_MIN, PZF_U_MAX; may be narrowed after init) */
  pzk_fin_poles poles[PZF_MODES];
  pzk_fin_step_t full[PZF_MODES]; /* discretisation over PZF_DT */
  pzk_fin_step_t sub[PZF_MODES];  /* over PZF_DT / sub_n, cached */
  int sub_n;
  pzf_dynamic d;
  long samples;     /* steps taken */
  long saturations; /* drives clipped to [u_min, u_max] */
  long unreachable; /* inverse steps whose desired angle was out of reach (clipped) */
  long trials;      /* the inverse's trials (PZF_INVERSE_HORIZON steps each) */
  int status;       /* PZF_* bits seen since init */
} pzf_state;

/* One sub-step tau of every mode, z held by the quintic Hermite of (zl, zr), u linear from u_a with
 * slope u_dot (modal_simulator.cc GeneralSubstep). steps == 0: discretised here for tau. */
static inline void pzf_substep(pzf_state* st, const pzk_fin_step_t* steps, double tau,
                               pzk_fin_zdata zl, pzk_fin_zdata zr, double u_a, double u_dot) {
  const double* wu = pzf_tip_gain_u();
  const double* wz = pzf_tip_gain_z();
  double fz[6];
  int i;
  if (!(tau > 0)) return;
  pzk_fin_hermite(tau, zl, zr, fz);
  for (i = 0; i < PZF_MODES; ++i) {
    pzk_fin_step_t local;
    if (!steps) pzk_fin_discretise(&st->poles[i], tau, &local);
    pzk_fin_mode_update(steps ? steps + i : &local, wu[i], wz[i], fz, u_a, u_dot, tau, &st->d.x0[i],
                        &st->d.x1[i]);
  }
}

/* Fin angle [deg] of the state (fin_modal.h). */
static inline double pzf_degrees(const pzf_state* st, int* finite) {
  return pzk_fin_angle(st->d.x0, PZF_MODES, PZF_INV_LENGTH, finite);
}

/* The backlash step (fin_modal.h). */
static inline double pzf_backlash(const pzf_state* st, double theta, double y_prev) {
  return pzk_fin_backlash(st->a1, st->a2, st->b1, st->b2, theta, y_prev);
}

/* pzk_fin_sample's sub-step over the state: a regular one with the cached discretisation, a piece
 * cut at a zero crossing of z discretised for its tau. */
typedef struct {
  pzf_state* st;
  const pzk_fin_step_t* cached;
} pzf_walk;
static inline void pzf_walk_substep(void* ctx, double tau, int regular, pzk_fin_zdata zl,
                                    pzk_fin_zdata zr, double u_a, double u_dot) {
  const pzf_walk* w = (const pzf_walk*)ctx;
  pzf_substep(w->st, regular ? w->cached : 0, tau, zl, zr, u_a, u_dot);
}

/* One sample from the drive d.u to u1 (fin_modal.h pzk_fin_sample); returns the angle. */
static inline double pzf_advance(pzf_state* st, double u1) {
  const double tau = PZF_DT, u0 = st->d.u;
  const int nsub = pzk_fin_substeps(st->alpha != 0.0, st->kappa_max, (u1 - u0) / tau, tau);
  int finite;
  double z, theta;
  pzf_walk w;
  pzf_dynamic before = st->d;
  if (nsub == 1) {
    w.cached = st->full;
  } else {
    if (st->sub_n != nsub) {
      int i;
      for (i = 0; i < PZF_MODES; ++i) pzk_fin_discretise(&st->poles[i], tau / nsub, &st->sub[i]);
      st->sub_n = nsub;
    }
    w.cached = st->sub;
  }
  w.st = st;
  z = pzk_fin_sample(st->alpha, st->beta, st->gamma, u0, st->d.z, u1, tau, nsub, pzf_walk_substep,
                     &w);
  theta = pzf_degrees(st, &finite);
  if (!finite) { /* the step is not taken */
    st->d = before;
    st->status |= PZF_NOT_FINITE;
    return st->d.y;
  }
  st->d.z = z;
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
 * or PZF_AMPLITUDE_OUT_OF_RANGE | PZF_FREQUENCY_OUT_OF_RANGE when an input lies outside the
 * training range [PZF_AMPLITUDE_LO, PZF_AMPLITUDE_HI] x [PZF_FREQUENCY_LO, PZF_FREQUENCY_HI] (p is
 * then the network's extrapolation: do not trust it without checking), PZF_INVALID_INPUT for a
 * non-finite input (p untouched). */
static inline int pzf_params(double amplitude_v, double frequency_hz, double p[7]) {
  int status = PZF_OK;
  if (!isfinite(amplitude_v) || !isfinite(frequency_hz)) return PZF_INVALID_INPUT;
  if (!(amplitude_v >= PZF_AMPLITUDE_LO && amplitude_v <= PZF_AMPLITUDE_HI))
    status |= PZF_AMPLITUDE_OUT_OF_RANGE;
  if (!(frequency_hz >= PZF_FREQUENCY_LO && frequency_hz <= PZF_FREQUENCY_HI))
    status |= PZF_FREQUENCY_OUT_OF_RANGE;
  PZF_NETWORK(amplitude_v, frequency_hz, p);
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
  if (!isfinite(b1) || !isfinite(b2) || !isfinite(u0) || st->mu < 0 || st->delta < 0 ||
      st->a1 < 0 || st->a2 < 0 || !(b1 > 0) || !(b2 < 0))
    st->status = PZF_INVALID_PARAMETERS;
  if (st->status == PZF_OK &&
      !(st->alpha == 0.0 || (st->beta + st->gamma > 0.0 && st->beta - st->gamma >= 0.0)))
    st->status = PZF_UNBOUNDED_HYSTERESIS;
  if (st->status != PZF_OK) return st->status;
  for (i = 0; i < PZF_MODES; ++i) {
    st->poles[i] = pzk_fin_make_poles(omega2[i], st->mu + st->delta * omega2[i]);
    pzk_fin_discretise(&st->poles[i], PZF_DT, &st->full[i]);
  }
  st->d.u = pzf_clip(st, u0);
  st->d.theta = pzf_degrees(st, &finite);
  st->d.y = pzf_backlash(st, st->d.theta, 0.0);
  return st->status;
}

/* The angle at the last sample [deg]. */
static inline double pzf_angle(const pzf_state* st) { return st->d.y; }

/* Forward: the drive u [V] at the next sample (clipped to [u_min, u_max]) -> the angle there [deg].
 */
static inline double pzf_step(pzf_state* st, double u) {
  if (st->status & (PZF_INVALID_PARAMETERS | PZF_UNBOUNDED_HYSTERESIS)) return 0.0;
  return pzf_advance(st, pzf_clip(st, u));
}

/* Inverse: the drive u for the next sample that brings the angle to angle_desired
 * PZF_INVERSE_HORIZON samples after the current one, and the step taken with it (the state advances
 * as pzf_step(st, u) would; call it again at the next sample: receding horizon). Give it the
 * reference that far ahead if the controller knows it (preview); the reference at the next sample
 * otherwise, with a lag of PZF_INVERSE_HORIZON - 1 samples. The backlash is inverted exactly:
 * moving up needs theta = y + a1, moving down theta = y - a2; inside the dead band (angle_desired =
 * the current angle) the theta nearest its course is kept. theta(u) = target is solved on the
 * horizon's map (drive ramped to u at the next sample, then continuing its slope) by a bracket
 * search on both sides of the last drive (the root nearest to it) and the Illinois method: at most
 * PZF_INVERSE_ITERATIONS trials of PZF_INVERSE_HORIZON steps each, until theta is within 1e-13 deg
 * (relative above 1 deg) or the bracket is two adjacent doubles. What it cannot do. It undoes no
 * dynamics beyond its horizon: the drive's linear hold between samples gives the sampled plant a
 * zero outside the unit circle (the second sample's response to a drive step is several times the
 * first's), so an exact one-step inverse (horizon 1) makes the drive oscillate; a horizon of 2
 * plans the next two samples and follows a reachable reference to a small fraction of the dead
 * band, not exactly (errors where the reference leaves the dead band or turns). The plan is greedy:
 * where the reference's state was reached by a path the plan did not take (the Bouc-Wen force
 * remembers it) a target can be out of reach for a few samples, and theta(u) need not be monotone.
 * docs/deploy.md has the figures. A target out of reach within [u_min, u_max], or an angle outside
 * [b2, b1], is clipped: the drive that came nearest is applied, and the step is counted in
 * st->unreachable (bit PZF_UNREACHABLE). */
/* theta PZF_INVERSE_HORIZON samples ahead less the target: the inverse's map. */
typedef struct {
  pzf_state* st;
  double th;
} pzf_target;
static inline double pzf_miss(void* ctx, double u) {
  const pzf_target* t = (const pzf_target*)ctx;
  return pzf_trial(t->st, u) - t->th;
}

static inline double pzf_inverse_step(pzf_state* st, double angle_desired) {
  double yd = angle_desired, th, best_u;
  int reached = 1;
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
   * saturation) any theta of [yd - a2, yd + a1] does; the one nearest its course with the drive
   * held is taken, which keeps theta at the band's edge, ready to move. */
  if (yd > st->d.y) {
    th = yd + st->a1;
  } else if (yd < st->d.y) {
    th = yd - st->a2;
  } else {
    th = pzf_trial(st, st->d.u);
    th = th < yd - st->a2 ? yd - st->a2 : (th > yd + st->a1 ? yd + st->a1 : th);
  }
  /* g(u) = theta(u) - th need not be monotone (at small drives the Bouc-Wen force can outweigh
   * the drive's moment): the root nearest the last drive (fin_modal.h pzk_fin_nearest_root). */
  {
    pzf_target target;
    target.st = st;
    target.th = th;
    if (!pzk_fin_nearest_root(pzf_miss, &target, st->d.u, st->u_min, st->u_max,
                              1e-13 * (fabs(th) > 1 ? fabs(th) : 1), PZF_INVERSE_ITERATIONS,
                              &best_u))
      reached = 0; /* out of reach: the drive that came nearest */
  }
  if (!reached) {
    ++st->unreachable;
    st->status |= PZF_UNREACHABLE;
  }
  pzf_advance(st, best_u);
  return best_u;
}
