#include "model/modal_simulator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

#include "model/bouc_wen.h"
#include "model/fast_exp.h"

namespace pz::model {
namespace {

using modal::ModePoles;
using modal::ModeStep;

// Quintic Hermite hold on [0, 1]: coefficients a_j of p(s) = Σ a_j s^j from the end data
// [z₀, τż₀, τ²z̈₀, z₁, τż₁, τ²z̈₁] (rows j = 0 … 5).
constexpr double kHermite[6][6] = {
    {1, 0, 0, 0, 0, 0},            //
    {0, 1, 0, 0, 0, 0},            //
    {0, 0, 0.5, 0, 0, 0},          //
    {-10, -6, -1.5, 10, -4, 0.5},  //
    {15, 8, 1.5, -15, 7, -1},      //
    {-6, -3, -0.5, 6, -3, 0.5},    //
};
constexpr double kFact[6] = {1, 1, 2, 6, 24, 120};

// A step of the z hold may span at most this much of exp(−κ Δu) and of the sinusoid's phase
// (κ u̇ τ ≤ 0.5, Ω τ ≤ 0.5): the quintic hold is then good to ~1e-7 of |z − α/κ|. Larger steps are
// split into equal sub-steps, at most kMaxSubsteps per sample.
constexpr double kMaxHoldArg = 0.5;
constexpr int kMaxSubsteps = 1000;

// Relative tolerances for reusing a cached discretisation (a sampled grid's steps differ in their
// last bits) and for treating a breakpoint as lying on a node.
constexpr double kStepRelTol = 1e-10;
constexpr double kNodeRelTol = 1e-9;

std::atomic<uint64_t> g_next_sim_id{1};

int SubstepsFor(double arg) {
  if (!(arg > kMaxHoldArg)) return 1;
  const double m = std::ceil(arg / kMaxHoldArg);
  return m >= kMaxSubsteps ? kMaxSubsteps : static_cast<int>(m);
}

using modal::ZData;

// z, ż = (α − κz) u̇, z̈ = (α − κz)(ü − κ u̇²) on a branch.
inline ZData EvalZ(const BoucWenBranch& b, double u, double ud, double udd) {
  const double z = b.Z(u);
  const double sl = b.Slope(z);
  return {z, sl * ud, sl * (udd - b.kappa * ud * ud)};
}

// The odd Taylor series of atan, good to ~1 ulp for |x| < 1/8 (x^21/21 < 1e-19), by Estrin's
// scheme: a short dependency chain, and no branch, so that a loop of it vectorises (DegreesBatch).
inline double AtanSeries(double x) {
  constexpr double kC[10] = {1.0,       -1.0 / 3, 1.0 / 5,   -1.0 / 7, 1.0 / 9,
                             -1.0 / 11, 1.0 / 13, -1.0 / 15, 1.0 / 17, -1.0 / 19};
  const double x2 = x * x, x4 = x2 * x2, x8 = x4 * x4, x16 = x8 * x8;
  const double p01 = kC[0] + kC[1] * x2, p23 = kC[2] + kC[3] * x2, p45 = kC[4] + kC[5] * x2;
  const double p67 = kC[6] + kC[7] * x2, p89 = kC[8] + kC[9] * x2;
  const double p = (p01 + p23 * x4) + (p45 + p67 * x4) * x8 + p89 * x16;
  return x * p;
}

// atan to ~1 ulp; the fin's |w/L| < 1/8 (7 deg) takes the series.
inline double FastAtan(double x) { return std::abs(x) < 0.125 ? AtanSeries(x) : std::atan(x); }

// Output angle [deg] of a tip deflection.
inline double Degrees(double w, double inv_length) {
  return FastAtan(w * inv_length) * (180.0 / std::numbers::pi);
}

// z, ż, z̈ (EvalZ) at the nodes [from, to) of a chunk, all on one branch, into
// structure-of-arrays outputs; arguments of e^x beyond ±700 (extreme parameters) are redone with
// std::expm1 afterwards. Returns false if none needed that.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
bool ZBatch(long from, long to, const double* __restrict u, const double* __restrict ud,
            const double* __restrict udd, double u0, double z0, double gain, double kappa,
            double alpha, double* __restrict z, double* __restrict zd, double* __restrict zdd) {
  int far = 0;
  for (long j = from; j < to; ++j) {
    const double du = u[j] - u0;
    const double x = -kappa * du;
    const bool in_range = (x >= -700.0) & (x <= 700.0);
    const double xc = in_range ? x : 0.0;
    far += !in_range;
    // Every candidate is computed, then selected: the loop has no branch and vectorises.
    const double taylor = Expm1Taylor4(x);  // FastExpm1's small branch
    const double expm1 = ExpReduced(xc) - 1.0;
    const double em1 = ((x < 1e-3) & (x > -1e-3)) ? taylor : expm1;
    const double linear = z0 + alpha * du, curved = z0 + gain * em1;
    const double zj = kappa == 0.0 ? linear : curved;
    const double sl = alpha - kappa * zj;
    z[j] = zj;
    zd[j] = sl * ud[j];
    zdd[j] = sl * (udd[j] - kappa * ud[j] * ud[j]);
  }
  return far == 0;
}

// θ [deg] of tip deflections w[0 … n): the vectorised FastAtan; |w/L| ≥ 1/8 (beyond 7 deg) is
// redone with std::atan by the caller (returns false when some are).
[[gnu::always_inline]] inline bool DegreesLoop(long n, const double* __restrict w,
                                               double inv_length, double* __restrict theta) {
  int far = 0;
  for (long q = 0; q < n; ++q) {
    const double x = w[q] * inv_length;
    far += !(std::abs(x) < 0.125);
    theta[q] = AtanSeries(x) * (180.0 / std::numbers::pi);
  }
  return far == 0;
}
// The sinusoid path's: with FMA where the CPU has it.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
bool DegreesBatch(long n, const double* __restrict w, double inv_length, double* __restrict theta) {
  return DegreesLoop(n, w, inv_length, theta);
}
// The sampled path's: AVX2 without FMA, so the same roundings as Degrees (the baseline's)
// everywhere.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
bool DegreesBatchExact(long n, const double* __restrict w, double inv_length,
                       double* __restrict theta) {
  return DegreesLoop(n, w, inv_length, theta);
}

// Pass 1a of a sinusoid run: the drive at the nodes [j0, j1) of a block starting at node b0, from
// e^{iΩ t_b0} = (ere, eim) and the powers of the one-step rotation: e^{iΩt}, u, u̇, ü.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void DriveNodes(long j0, long j1, long b0, const double* __restrict rpow_re,
                const double* __restrict rpow_im,
                double ere, double eim, double V, double om, double* __restrict nre,
                double* __restrict nim,
                double* __restrict nu, double* __restrict nud, double* __restrict nudd) {
  for (long j = j0; j < j1; ++j) {
    const long r = j - b0;
    const double re = ere * rpow_re[r] - eim * rpow_im[r];
    const double im = ere * rpow_im[r] + eim * rpow_re[r];
    nre[j] = re;
    nim[j] = im;
    nu[j] = V * im;
    nud[j] = V * om * re;
    nudd[j] = -om * om * (V * im);
  }
}

// Feed-through of a node's hold data d to w_tip: t1c · (z, ż, z̈) with t1c = Σ_i P1_i row 0 scaled
// by the step (1, h, h²).
inline double Feedthrough(const double* t1c, const ZData& d) {
  return t1c[0] * d.z + t1c[1] * d.zd + t1c[2] * d.zdd;
}

// Pass 1c's end: the hold data of the nodes 1 … len as right limits for the recursion (the left
// ones are (zz, zzd, zzdd) themselves; the right ones of the nodes with a jump are redone by the
// caller), and the state-free part of w_tip there: Feedthrough plus V Im(H_tip e^{iΩt}).
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void NodeData(long len, const double* __restrict zz, const double* __restrict zzd,
              const double* __restrict zzdd,
              const double* __restrict nre, const double* __restrict nim,
              const double* __restrict t1c, double V,
              double htip_re, double htip_im, ZData* __restrict zr, double* __restrict base) {
  for (long j = 1; j <= len; ++j) {
    const ZData d{zz[j], zzd[j], zzdd[j]};
    zr[j] = d;
    base[j] = Feedthrough(t1c, d) + V * (htip_re * nim[j] + htip_im * nre[j]);
  }
}

// Sinks: what a run does with each output sample.
struct AngleSink {
  std::span<double> out;
  void Emit(size_t k, double, double, double, double, double, double angle) { out[k] = angle; }
};
struct TraceSink {
  BimorphTrace* tr;
  void Emit(size_t k, double t, double u, double z, double w, double theta, double angle) {
    tr->t[k] = t;
    tr->u[k] = u;
    tr->z[k] = z;
    tr->w_tip[k] = w;
    tr->theta_deg[k] = theta;
    tr->angle_deg[k] = angle;
  }
};

// Per-mode coefficients of the regular step (arrays of npad entries).
struct StepCoeffs {
  const double *e11, *e12, *e21, *e22;
  const double* g[6];
};

// Regular steps i0 … i1−1 of a chunk: x ← E x + G·d_i⁺ (d scaled by the step hs) for every mode,
// xs[i+1] = Σ_modes x0. NB blocks of 4 modes (NB = 0: n/4 blocks, not known at compile time).
template <int NB>
[[gnu::always_inline]] inline void StepRunImpl(long i0, long i1, int n, double* __restrict x0,
                                               double* __restrict x1, const StepCoeffs& c,
                                               const ZData* __restrict d, double hs,
                                               double* __restrict xs) {
  const int nb = NB > 0 ? NB : n / 4;
  const double* __restrict e11 = c.e11;
  const double* __restrict e12 = c.e12;
  const double* __restrict e21 = c.e21;
  const double* __restrict e22 = c.e22;
  const double* __restrict g0 = c.g[0];
  const double* __restrict g1 = c.g[1];
  const double* __restrict g2 = c.g[2];
  const double* __restrict g3 = c.g[3];
  const double* __restrict g4 = c.g[4];
  const double* __restrict g5 = c.g[5];
  // A known number of modes keeps the state in registers for the whole run.
  constexpr int kLocal = NB > 0 ? 4 * NB : 1;
  double l0[kLocal], l1[kLocal];
  double* __restrict s0 = x0;
  double* __restrict s1 = x1;
  if constexpr (NB > 0) {
    for (int q = 0; q < kLocal; ++q) l0[q] = x0[q], l1[q] = x1[q];
    s0 = l0;
    s1 = l1;
  }
  const double hs2 = hs * hs;
  for (long k = i0; k < i1; ++k) {
    const double d0 = d[k].z, d1 = hs * d[k].zd, d2 = hs2 * d[k].zdd;
    double acc[4] = {0, 0, 0, 0};
    for (int blk = 0; blk < nb; ++blk) {
      for (int j = 0; j < 4; ++j) {
        const int q = 4 * blk + j;
        const double a = s0[q], b = s1[q];
        // The input terms first and the state last: the chain from one step to the next is then two
        // multiply-adds (contracted where the target has FMA), the rest runs beside it.
        const double in0 = (g0[q] * d0 + g1[q] * d1) + g2[q] * d2;
        const double in1 = (g3[q] * d0 + g4[q] * d1) + g5[q] * d2;
        const double na = e11[q] * a + (e12[q] * b + in0);
        s1[q] = e21[q] * a + (e22[q] * b + in1);
        s0[q] = na;
        acc[j] += na;
      }
    }
    xs[k + 1] = (acc[0] + acc[1]) + (acc[2] + acc[3]);
  }
  if constexpr (NB > 0) {
    for (int q = 0; q < kLocal; ++q) x0[q] = l0[q], x1[q] = l1[q];
  }
}

// Compiled for x86-64-v3 (AVX2, FMA) next to the baseline; the loader picks what the CPU runs.
// The default beam (12 modes) and other small meshes get loops unrolled over the modes.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("arch=x86-64-v3", "default")))
#endif
void StepRun(long i0, long i1, int n, double* __restrict x0, double* __restrict x1,
             const StepCoeffs& c,
             const ZData* __restrict d, double hs, double* __restrict xs) {
  switch (n) {
    case 4:
      return StepRunImpl<1>(i0, i1, n, x0, x1, c, d, hs, xs);
    case 8:
      return StepRunImpl<2>(i0, i1, n, x0, x1, c, d, hs, xs);
    case 12:
      return StepRunImpl<3>(i0, i1, n, x0, x1, c, d, hs, xs);
    case 16:
      return StepRunImpl<4>(i0, i1, n, x0, x1, c, d, hs, xs);
    default:
      return StepRunImpl<0>(i0, i1, n, x0, x1, c, d, hs, xs);
  }
}

// x += sign · M·d for a per-mode 2×3 matrix M stored as six arrays.
inline void AddMatVec(int n, double* __restrict x0, double* __restrict x1,
                      const std::vector<double>* m, double d0, double d1, double d2) {
  for (int i = 0; i < n; ++i) {
    x0[i] += m[0][i] * d0 + m[1][i] * d1 + m[2][i] * d2;
    x1[i] += m[3][i] * d0 + m[4][i] * d1 + m[5][i] * d2;
  }
}

// Σ x0 over modes (n a multiple of 4; four partial sums so the loop vectorises).
inline double SumModes(int n, const double* __restrict x0) {
  double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
  for (int i = 0; i < n; i += 4) {
    s0 += x0[i];
    s1 += x0[i + 1];
    s2 += x0[i + 2];
    s3 += x0[i + 3];
  }
  return (s0 + s1) + (s2 + s3);
}

// The kernel's hold data of a node.
inline pzk::pzk_fin_zdata Kz(const ZData& d) { return {d.z, d.zd, d.zdd}; }

// Per-mode data of the cached step, structure of arrays (npad entries each, zero in the padding).
struct SampledCoeffs {
  const double *e11, *e12, *e21, *e22;
  const double *nwz, *wu;  // −tip_i g_z,i, tip_i g_u,i
  const double* d[modal::kMaxPhi + 1];
};

// Four doubles as one vector (GCC's vector extension): each operation acts on every element as the
// scalar operation does, so a loop written with it rounds as the scalar loop. V4u reads and writes
// four doubles anywhere (8-byte aligned, aliasing them).
typedef double V4 __attribute__((vector_size(32)));
typedef double V4u __attribute__((vector_size(32), aligned(8), may_alias));
inline const V4u* At(const double* p) { return reinterpret_cast<const V4u*>(p); }
inline V4u* At(double* p) { return reinterpret_cast<V4u*>(p); }

// Sub-steps a piece of a run holds at most (the hold data and partial sums are kept for a piece).
constexpr long kRunPiece = 128;

// A run of sub-steps over the cached step (the sampled path's regular steps): the kernel's
// arithmetic (pzk_fin_hermite, pzk_fin_mode_update) for every mode, operation for operation (so bit
// for bit, without FMA contraction);
// after an output sample's last sub-step, SumModes of x0 (same partial sums) into xs[out]. The run
// goes piece by piece: first the hold coefficients of every sub-step of the piece, then each block
// of 4 modes over all of them — its 13 coefficient vectors and its state stay in registers — adding
// its x0 into the sub-step's four partial sums in the blocks' order (SumModes' order), and last the
// outputs.
[[gnu::always_inline]] inline void SampledRunImpl(const modal::SampledSub* __restrict subs,
                                                  long count, int n, double* __restrict x0,
                                                  double* __restrict x1, const SampledCoeffs& c,
                                                  double* __restrict xs) {
  alignas(32) double fz[6][kRunPiece], fu0[kRunPiece], fu1[kRunPiece], taus[kRunPiece];
  alignas(32) V4 acc[kRunPiece];
  const V4 zero = {0, 0, 0, 0};
  const double* const* d = c.d;
  for (long p0 = 0; p0 < count; p0 += kRunPiece) {
    const long m = std::min(kRunPiece, count - p0);
    const modal::SampledSub* __restrict s = subs + p0;
    long k = 0;
    for (; k + 4 <= m; k += 4) {  // pzk_fin_hermite of four sub-steps at a time
      const modal::SampledSub *s0 = s + k, *s1 = s + k + 1, *s2 = s + k + 2, *s3 = s + k + 3;
      const V4 tau = {s0->tau, s1->tau, s2->tau, s3->tau};
      const V4 tau2 = tau * tau;
      const V4 zl = {s0->l.z, s1->l.z, s2->l.z, s3->l.z}, zr = {s0->r.z, s1->r.z, s2->r.z, s3->r.z};
      const V4 zld = tau * V4{s0->l.zd, s1->l.zd, s2->l.zd, s3->l.zd};
      const V4 zrd = tau * V4{s0->r.zd, s1->r.zd, s2->r.zd, s3->r.zd};
      const V4 zldd = tau2 * V4{s0->l.zdd, s1->l.zdd, s2->l.zdd, s3->l.zdd};
      const V4 zrdd = tau2 * V4{s0->r.zdd, s1->r.zdd, s2->r.zdd, s3->r.zdd};
      for (int j = 0; j < 6; ++j) {
        const double* hj = kHermite[j];
        const V4 a =
            (((((zero + hj[0] * zl) + hj[1] * zld) + hj[2] * zldd) + hj[3] * zr) + hj[4] * zrd) +
            hj[5] * zrdd;
        *At(fz[j] + k) = a * kFact[j];
      }
      *At(taus + k) = tau;
      *At(fu0 + k) = V4{s0->u_a, s1->u_a, s2->u_a, s3->u_a};
      *At(fu1 + k) = V4{s0->u_dot, s1->u_dot, s2->u_dot, s3->u_dot} * tau;
    }
    for (; k < m; ++k) {
      double h[6];
      pzk::pzk_fin_hermite(s[k].tau, Kz(s[k].l), Kz(s[k].r), h);
      for (int j = 0; j < 6; ++j) fz[j][k] = h[j];
      taus[k] = s[k].tau;
      fu0[k] = s[k].u_a;
      fu1[k] = s[k].u_dot * s[k].tau;
    }
    for (k = 0; k < m; ++k) acc[k] = zero;
    for (int q = 0; q < n; q += 4) {
      const V4 w = *At(c.nwz + q), wu = *At(c.wu + q), e11 = *At(c.e11 + q), e12 = *At(c.e12 + q);
      const V4 e21 = *At(c.e21 + q), e22 = *At(c.e22 + q), d0 = *At(d[0] + q), d1 = *At(d[1] + q);
      const V4 d2 = *At(d[2] + q), d3 = *At(d[3] + q), d4 = *At(d[4] + q), d5 = *At(d[5] + q),
               d6 = *At(d[6] + q);
      V4 a = *At(x0 + q), b = *At(x1 + q);
      for (long k = 0; k < m; ++k) {
        const V4 f0 = w * fz[0][k] + wu * fu0[k], f1 = w * fz[1][k] + wu * fu1[k];
        const V4 f2 = w * fz[2][k], f3 = w * fz[3][k], f4 = w * fz[4][k], f5 = w * fz[5][k];
        const V4 r0 = (((((zero + f0 * d1) + f1 * d2) + f2 * d3) + f3 * d4) + f4 * d5) + f5 * d6;
        const V4 r1 = (((((zero + f0 * d0) + f1 * d1) + f2 * d2) + f3 * d3) + f4 * d4) + f5 * d5;
        const V4 na = (e11 * a + e12 * b) + taus[k] * r0;
        b = (e21 * a + e22 * b) + r1;
        a = na;
        acc[k] += na;
      }
      *At(x0 + q) = a;
      *At(x1 + q) = b;
    }
    for (long k = 0; k < m; ++k)
      if (s[k].out >= 0) xs[s[k].out] = (acc[k][0] + acc[k][1]) + (acc[k][2] + acc[k][3]);
  }
}

// AVX2 without FMA next to the baseline: four modes a vector, and the same roundings in both.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__)
__attribute__((target_clones("avx2", "default")))
#endif
void SampledRun(const modal::SampledSub* subs, long count, int n, double* x0, double* x1,
                const SampledCoeffs& c,
                double* xs) {
  SampledRunImpl(subs, count, n, x0, x1, c, xs);
}

std::string NonFiniteMessage(size_t k, double t) {
  return "non-finite tip deflection at sample " + std::to_string(k) + " (t = " + std::to_string(t) +
         " s)";
}

}  // namespace

ModalSimulator::ModalSimulator(const BimorphPlant& plant)
    : plant_(&plant), id_(g_next_sim_id.fetch_add(1)), length_m_(plant.geometry().TotalLength()) {
  const ModalBasis& mb = plant.modal();
  for (Eigen::Index i = 0; i < mb.omega.size(); ++i) {
    const double wu = mb.tip(i) * mb.gain_u(i), wz = mb.tip(i) * mb.gain_z(i);
    if (wu == 0.0 && wz == 0.0) continue;  // invisible at the tip
    omega2_.push_back(mb.omega(i) * mb.omega(i));
    wu_.push_back(wu);
    wz_.push_back(wz);
  }
  n_ = static_cast<int>(omega2_.size());
  npad_ = (n_ + 3) / 4 * 4;
}

bool ModalSimulator::Holds(const BimorphParams& params, double step,
                           const ModalWorkspace& ws) const {
  return ws.sim_id_ == id_ && ws.mu_ == params.mu && ws.delta_ == params.delta &&
         std::abs(ws.step_ - step) <= kStepRelTol * step;
}

void ModalSimulator::Prepare(const BimorphParams& params, double step, ModalWorkspace& ws,
                             bool exact) const {
  if (exact ? ws.sim_id_ == id_ && ws.mu_ == params.mu && ws.delta_ == params.delta &&
                  ws.step_ == step
            : Holds(params, step, ws))
    return;
  ws.sim_id_ = id_;
  ws.mu_ = params.mu;
  ws.delta_ = params.delta;
  ws.step_ = step;
  ws.poles_.resize(n_);
  ws.steps_.resize(n_);
  ws.sub_.steps.resize(n_);
  ws.sub_.scratch.resize(16 * static_cast<size_t>(n_));
  ws.sub_.idx.resize(n_);
  for (auto* v : {&ws.e11_, &ws.e12_, &ws.e21_, &ws.e22_, &ws.nwz_, &ws.wu_}) v->assign(npad_, 0.0);
  for (auto& v : ws.d_) v.assign(npad_, 0.0);
  ws.x0_.resize(npad_);  // the state is set by the runs, and kept when a sampled run re-prepares
  ws.x1_.resize(npad_);
  for (int r = 0; r < 6; ++r) {
    ws.g_[r].assign(npad_, 0.0);
    ws.p1_[r].assign(npad_, 0.0);
    ws.ep1_[r].assign(npad_, 0.0);
  }
  ws.t1_[0] = ws.t1_[1] = ws.t1_[2] = 0.0;
  for (int i = 0; i < n_; ++i) {
    const ModePoles poles =
        pzk::pzk_fin_make_poles(omega2_[i], params.mu + params.delta * omega2_[i]);
    ws.poles_[i] = poles;
    ModeStep& st = ws.steps_[i];
    pzk::pzk_fin_discretise(&poles, step, &st);
    // P = −w_z Σ_j j! R_j ⊗ Hermite row j, R_j = [τ D_{j+1}, D_j]: response to the 6 end data.
    double p[2][6] = {};
    for (int j = 0; j < 6; ++j) {
      const double r0 = step * st.d[j + 1] * kFact[j], r1 = st.d[j] * kFact[j];
      for (int c = 0; c < 6; ++c) {
        p[0][c] += r0 * kHermite[j][c];
        p[1][c] += r1 * kHermite[j][c];
      }
    }
    ws.e11_[i] = st.e11;
    ws.e12_[i] = st.e12;
    ws.e21_[i] = st.e21;
    ws.e22_[i] = st.e22;
    for (int j = 0; j <= modal::kMaxPhi; ++j) ws.d_[j][i] = st.d[j];
    ws.nwz_[i] = -wz_[i];
    ws.wu_[i] = wu_[i];
    for (int c = 0; c < 3; ++c) {
      const double p00 = -wz_[i] * p[0][c], p01 = -wz_[i] * p[1][c];          // P0 column c
      const double p10 = -wz_[i] * p[0][c + 3], p11 = -wz_[i] * p[1][c + 3];  // P1 column c
      const double ep0 = st.e11 * p10 + st.e12 * p11, ep1 = st.e21 * p10 + st.e22 * p11;
      ws.p1_[c][i] = p10;
      ws.p1_[3 + c][i] = p11;
      ws.ep1_[c][i] = ep0;
      ws.ep1_[3 + c][i] = ep1;
      ws.g_[c][i] = ep0 + p00;
      ws.g_[3 + c][i] = ep1 + p01;
      ws.t1_[c] += p10;
    }
  }
}

// Sub-step of length τ from the current full state (x0, x1): z held by the quintic Hermite of
// (zl, zr), u (sampled path) linear from u_a with slope u̇, every mode by the kernel's
// pzk_fin_mode_update over its discretisation for τ, made in sub.steps: by DiscretiseBatch
// (`batch`: both paths', with which the HGANN's and the fin bench's pins were made; the kernel's
// per mode differs by ulps and moved the pinned bench diagnosis) or by pzk_fin_discretise.
static void GeneralSubstep(int n, const ModePoles* poles, modal::SubStep& sub, bool batch,
                           const double* wu, const double* wz, double* x0, double* x1, double tau,
                           const ZData& zl, const ZData& zr, double u_a, double u_dot) {
  if (!(tau > 0)) return;
  ModeStep* steps = sub.steps.data();
  if (batch) {
    modal::DiscretiseBatch(n, poles, tau, steps, sub.scratch.data(), sub.idx.data());
  } else {
    for (int i = 0; i < n; ++i) pzk::pzk_fin_discretise(&poles[i], tau, &steps[i]);
  }
  double fz[6];
  pzk::pzk_fin_hermite(tau, Kz(zl), Kz(zr), fz);
  for (int i = 0; i < n; ++i)
    pzk::pzk_fin_mode_update(&steps[i], wu[i], wz[i], fz, u_a, u_dot, tau, &x0[i], &x1[i]);
}

namespace {

// The Bouc–Wen branch of a sinusoid run and its end (the next breakpoint): stretch n of the
// sinusoid runs between the reversals at t = (1/4 + (n−1)/2)/f and (1/4 + n/2)/f, with s = (−1)^n.
struct SineBranch {
  BoucWenParams bw;
  bool hyst;
  double f, V, om;
  BoucWenBranch br = StartBranch(bw, 0.0, 0.0, 1.0);
  int stretch = 0;
  double t_start = 0.0, t_end = std::numeric_limits<double>::infinity(), u_cross = 0.0;
  bool end_is_crossing = false;

  [[gnu::always_inline]] void ComputeEnd() {
    if (!hyst) return;
    const double t_rev = (0.25 + 0.5 * stretch) / f;
    t_end = t_rev;
    end_is_crossing = false;
    double uc;
    if (br.ZeroCrossing(&uc) && ((br.s > 0 && uc < V) || (br.s < 0 && uc > -V))) {
      const double a = std::asin(std::clamp(uc / V, -1.0, 1.0));
      double tc = (stretch * std::numbers::pi + ((stretch & 1) ? -a : a)) / om;
      tc = std::clamp(tc, t_start, t_rev);
      if (tc < t_rev) {
        t_end = tc;
        end_is_crossing = true;
        u_cross = uc;
      }
    }
  }
  [[gnu::always_inline]] void Advance() {
    if (end_is_crossing) {
      br = StartBranch(bw, u_cross, 0.0, br.s);
    } else {
      const double u_rev = br.s * V;
      br = StartBranch(bw, u_rev, br.Z(u_rev), -br.s);
      ++stretch;
    }
    t_start = t_end;
    ComputeEnd();
  }
  // Exact u, u̇, ü at the current branch end.
  [[gnu::always_inline]] void UAtEnd(double* u, double* ud, double* udd) const {
    if (end_is_crossing) {
      *u = u_cross;
      *ud = V * om * std::cos(om * t_end);
      *udd = -om * om * u_cross;
    } else {
      *u = br.s * V;
      *ud = 0.0;
      *udd = -om * om * br.s * V;
    }
  }
  [[gnu::always_inline]] ZData Eval(double u, double ud, double udd) const {
    return hyst ? EvalZ(br, u, ud, udd) : ZData{};
  }
};

}  // namespace

// RunSinusoid's chunk loop (a member type, so that it reads the workspace): the buffers of one
// chunk of kChunk steps in ws, and the passes over them, each with a short dependency chain:
//  1. z: the hold data at the nodes (left and right limits) and the breakpoints inside steps,
//     which depend on u alone, plus the state-free part of w_tip at the output nodes (Drive,
//     Breakpoints, NodeZ);
//  2. the modal recursion on x̄ = x − P1 d⁻: x̄_{k+1} = E x̄_k + G d_k⁺ + E P1 (d_k⁻ − d_k⁺),
//     with sub-steps on the full state x where a step holds breakpoints (Modes);
//  3. outputs: w_tip, θ, the backlash (Outputs).
// Its functions (and SineBranch's) are always inlined: RunSinusoid compiles to the one loop it was
// before the split (pair runs of bench_fitness BM_FitnessModal: no loss against that one).
struct ModalSimulator::SineChunks {
  static constexpr long kChunk = 256;
  // e^{iΩt} at the nodes: e^{iΩ t_b} exactly (sin, cos) every 64 steps, times the powers R^r of
  // the one-step rotation R = e^{iΩh} (r < 64, formed once by repeated multiplication), so that
  // the nodes of a chunk are independent of each other and their drive is one vectorised loop.
  static constexpr long kBlock = 64;
  static_assert(kChunk % kBlock == 0);
  using Segment = ModalWorkspace::SegmentData;  // nodes [from, to) whose left limits share a branch

  const ModalSimulator& sim;
  ModalWorkspace& ws;
  const int m;  // internal steps per sample
  const double hs, V, om, htip_re, htip_im;
  const bool hyst;
  ZData* zr;  // right limits; the left limits at the nodes are (zz, zzd, zzdd) themselves, node 0
              // of a chunk carries the last one
  double *xs, *base;
  double *wo, *tho, *yo;  // pass 3: w, θ, y at the outputs
  long* io;               //         and their nodes
  double *nu, *nud, *nudd, *nre, *nim;
  double *zz, *zzd, *zzdd;
  const double eps;
  const StepCoeffs coeffs;
  const double t1c[3];
  double rpow_re[kBlock], rpow_im[kBlock];
  bool jump_at_start = false;  // d⁻ ≠ d⁺ at the chunk's first node

  [[gnu::always_inline]] SineChunks(const ModalSimulator& s, ModalWorkspace& w, int m_, double hs_,
                                    double V_, double om_, double htip_re_, double htip_im_,
                                    bool hyst_)
      : sim(s),
        ws(w),
        m(m_),
        hs(hs_),
        V(V_),
        om(om_),
        htip_re(htip_re_),
        htip_im(htip_im_),
        hyst(hyst_),
        eps(kNodeRelTol * hs_),
        coeffs{w.e11_.data(),
               w.e12_.data(),
               w.e21_.data(),
               w.e22_.data(),
               {w.g_[0].data(), w.g_[1].data(), w.g_[2].data(), w.g_[3].data(), w.g_[4].data(),
                w.g_[5].data()}},
        t1c{w.t1_[0], hs_ * w.t1_[1], hs_ * hs_ * w.t1_[2]} {
    ws.zr_.resize(kChunk + 1);
    ws.xs_.resize(kChunk + 1);
    ws.base_.resize(kChunk + 1);
    for (auto* v : {&ws.nu_, &ws.nud_, &ws.nudd_, &ws.nre_, &ws.nim_, &ws.zz_, &ws.zzd_, &ws.zzdd_,
                    &ws.wo_, &ws.tho_, &ws.yo_})
      v->resize(kChunk + 1);
    ws.io_.resize(kChunk + 1);
    zr = ws.zr_.data();
    xs = ws.xs_.data();
    base = ws.base_.data();
    wo = ws.wo_.data(), tho = ws.tho_.data(), yo = ws.yo_.data();
    io = ws.io_.data();
    nu = ws.nu_.data(), nud = ws.nud_.data(), nudd = ws.nudd_.data(), nre = ws.nre_.data(),
    nim = ws.nim_.data();
    zz = ws.zz_.data(), zzd = ws.zzd_.data(), zzdd = ws.zzdd_.data();
    const double rot_re = std::cos(om * hs), rot_im = std::sin(om * hs);
    rpow_re[0] = 1.0;
    rpow_im[0] = 0.0;
    for (long r = 1; r < kBlock; ++r) {
      rpow_re[r] = rpow_re[r - 1] * rot_re - rpow_im[r - 1] * rot_im;
      rpow_im[r] = rpow_re[r - 1] * rot_im + rpow_im[r - 1] * rot_re;
    }
  }

  // The left limit at node j.
  [[gnu::always_inline]] ZData Left(long j) const { return ZData{zz[j], zzd[j], zzdd[j]}; }

  // Pass 1a: the drive at the nodes 1 … len (global node c0 + j), block by block.
  [[gnu::always_inline]] void Drive(long c0, long len) {
    for (long q = 0; q * kBlock <= len; ++q) {
      const long b = c0 + q * kBlock;  // a multiple of 64: e^{iΩ t_b} exactly
      const double tb = static_cast<double>(b) * hs;
      const double ere = b == 0 ? 1.0 : std::cos(om * tb), eim = b == 0 ? 0.0 : std::sin(om * tb);
      const long j0 = std::max<long>(1, q * kBlock), j1 = std::min(len, q * kBlock + kBlock - 1);
      DriveNodes(j0, j1 + 1, q * kBlock, rpow_re, rpow_im, ere, eim, V, om, nre, nim, nu, nud,
                 nudd);
    }
  }

  // Pass 1b: the breakpoints (zero crossings of z, reversals of u), in order. Inside a step they
  // make it special (sub-steps, z data now); on a node its data jump there. Between them the
  // nodes' left limits lie on one branch: a segment.
  [[gnu::always_inline]] void Breakpoints(SineBranch& sb, long c0, long len) {
    std::vector<Segment>& segments = ws.segments_;
    ws.special_.clear();
    ws.inner_.clear();
    ws.jumps_.clear();
    segments.clear();
    BoucWenBranch cur = sb.br;  // the branch of the next node's left limit
    long seg_from = 1;
    auto close_segment = [&](long to) {
      if (to > seg_from) segments.push_back({seg_from, to, cur});
      seg_from = to;
    };
    bool jump_at_node = jump_at_start;
    for (long i = 0; i < len; ++i) {
      if (!jump_at_node) {
        // Nothing up to the node the next breakpoint reaches: jump to a node just before it, then
        // to the first that the test below passes (it is monotone in i).
        const double kf = std::floor((sb.t_end - eps) / hs) - 2.0;
        if (kf > static_cast<double>(c0 + i))
          i = kf - static_cast<double>(c0) >= static_cast<double>(len) ? len
                                                                       : static_cast<long>(kf) - c0;
        while (i < len && !(sb.t_end <= static_cast<double>(c0 + i + 1) * hs + eps)) ++i;
        if (i == len) break;
      }
      const long k = c0 + i;
      const double t1 = static_cast<double>(k + 1) * hs;
      const int inner_begin = static_cast<int>(ws.inner_.size());
      while (sb.t_end < t1 - eps) {
        double ub, udb, uddb;
        sb.UAtEnd(&ub, &udb, &uddb);
        const double tb = sb.t_end;
        const ZData left = sb.Eval(ub, udb, uddb);
        sb.Advance();
        ws.inner_.push_back({tb - static_cast<double>(k) * hs, left, sb.Eval(ub, udb, uddb)});
      }
      const int inner_end = static_cast<int>(ws.inner_.size());
      if (jump_at_node || inner_end > inner_begin)
        ws.special_.push_back({i, inner_begin, inner_end});
      if (inner_end > inner_begin) {  // node i + 1 is on the new branch
        close_segment(i + 1);
        cur = sb.br;
      }
      jump_at_node = false;
      while (sb.t_end <= t1 + eps) {  // breakpoints on the node: the data jump there
        sb.Advance();
        jump_at_node = true;
      }
      if (jump_at_node) {  // node i + 1's left limit stays on `cur`, its right one and the next on
                           // br
        ws.jumps_.emplace_back(i + 1, sb.br);
        close_segment(i + 2);
        cur = sb.br;
      }
    }
    close_segment(len + 1);
    jump_at_start = jump_at_node;
  }

  // Pass 1c: z, ż, z̈ at the nodes, segment by segment; right limits where a breakpoint is on the
  // node.
  [[gnu::always_inline]] void NodeZ(long len) {
    if (hyst) {
      for (const Segment& sg : ws.segments_) {
        const BoucWenBranch& b = sg.branch;
        if (!ZBatch(sg.from, sg.to, nu, nud, nudd, b.u0, b.z0, b.gain, b.kappa, b.alpha, zz, zzd,
                    zzdd)) {
          for (long j = sg.from; j < sg.to; ++j) {  // arguments beyond ±700: as EvalZ has it
            const ZData d = EvalZ(b, nu[j], nud[j], nudd[j]);
            zz[j] = d.z;
            zzd[j] = d.zd;
            zzdd[j] = d.zdd;
          }
        }
      }
    } else {
      std::fill(zz + 1, zz + len + 1, 0.0);
      std::fill(zzd + 1, zzd + len + 1, 0.0);
      std::fill(zzdd + 1, zzdd + len + 1, 0.0);
    }
    NodeData(len, zz, zzd, zzdd, nre, nim, t1c, V, htip_re, htip_im, zr, base);
    for (const auto& [j, b] : ws.jumps_) zr[j] = EvalZ(b, nu[j], nud[j], nudd[j]);
  }

  // Pass 2: the modes over the chunk's steps, sub-steps in the special ones; returns the number
  // of breakpoints inside steps (each one more sub-step).
  [[gnu::always_inline]] long Modes(long len) {
    const int np = sim.npad_;
    double* x0 = ws.x0_.data();
    double* x1 = ws.x1_.data();
    long extra = 0;
    long i = 0;
    for (const ModalWorkspace::Special& sp : ws.special_) {
      if (i < sp.step) {
        StepRun(i, sp.step, np, x0, x1, coeffs, zr, hs, xs);
        i = sp.step;
      }
      if (sp.inner_begin == sp.inner_end) {
        // Data jump at the node, no breakpoint inside: one regular step plus the correction.
        const ZData a = Left(i);
        const ZData& b = zr[i];
        StepRun(i, i + 1, np, x0, x1, coeffs, zr, hs, xs);
        AddMatVec(np, x0, x1, ws.ep1_, a.z - b.z, hs * (a.zd - b.zd), hs * hs * (a.zdd - b.zdd));
      } else {
        // Breakpoints inside: back to the full state, sub-steps between them, then to x̄ again.
        AddMatVec(np, x0, x1, ws.p1_, Left(i).z, hs * Left(i).zd, hs * hs * Left(i).zdd);
        double scur = 0.0;
        ZData dcur = zr[i];
        for (int e = sp.inner_begin; e < sp.inner_end; ++e) {
          const ModalWorkspace::Inner& in = ws.inner_[e];
          GeneralSubstep(sim.n_, ws.poles_.data(), ws.sub_, true, sim.wu_.data(), sim.wz_.data(),
                         x0, x1, in.offset - scur, dcur, in.left, 0.0, 0.0);
          dcur = in.right;
          scur = in.offset;
        }
        GeneralSubstep(sim.n_, ws.poles_.data(), ws.sub_, true, sim.wu_.data(), sim.wz_.data(), x0,
                       x1, hs - scur, dcur, Left(i + 1), 0.0, 0.0);
        AddMatVec(np, x0, x1, ws.p1_, -Left(i + 1).z, -hs * Left(i + 1).zd,
                  -hs * hs * Left(i + 1).zdd);
        extra += sp.inner_end - sp.inner_begin;
      }
      xs[i + 1] = SumModes(np, x0);
      ++i;
    }
    if (i < len) StepRun(i, len, np, x0, x1, coeffs, zr, hs, xs);
    return extra;
  }

  // Pass 3: θ of every output of the chunk in one vectorised loop, then the backlash
  // (BacklashRun) and the sink. False (the summary says why) at a non-finite w_tip.
  template <class Sink>
  [[gnu::always_inline]] bool Outputs(long c0, long len, double fs, double inv_len,
                                      const BacklashParams& bl, double& y, size_t& next_out,
                                      Sink& sink, SimulationSummary& summary) {
    long n_o = 0;
    if (m == 1) {  // every node is an output
      for (long q = 0; q < len; ++q) {
        io[q] = q + 1;
        wo[q] = xs[q + 1] + base[q + 1];
      }
      n_o = len;
    } else {
      for (long i3 = 1; i3 <= len; ++i3) {
        if ((c0 + i3) % m != 0) continue;
        io[n_o] = i3;
        wo[n_o++] = xs[i3] + base[i3];
      }
    }
    long n_ok = n_o;  // outputs before the first non-finite w (DegreesBatch's test fails on those)
    if (!DegreesBatch(n_o, wo, inv_len, tho)) {
      n_ok = 0;
      while (n_ok < n_o && std::isfinite(wo[n_ok])) ++n_ok;
      for (long q = 0; q < n_ok; ++q)
        if (!(std::abs(wo[q] * inv_len) < 0.125)) tho[q] = Degrees(wo[q], inv_len);
    }
    y = BacklashRun(bl, tho, yo, n_ok, y);
    for (long q = 0; q < n_ok; ++q, ++next_out) {
      const long i3 = io[q];
      sink.Emit(next_out, static_cast<double>(next_out) / fs, nu[i3], Left(i3).z, wo[q], tho[q],
                yo[q]);
    }
    if (n_ok < n_o) {
      summary.status = SimStatus::kNonFinite;
      summary.message = NonFiniteMessage(next_out, static_cast<double>(next_out) / fs);
      return false;
    }
    return true;
  }

  // The chunk's last node is the next chunk's node 0.
  [[gnu::always_inline]] void Carry(long len) {
    zz[0] = zz[len];
    zzd[0] = zzd[len];
    zzdd[0] = zzdd[len];
    zr[0] = zr[len];
  }
};

template <class Sink>
void ModalSimulator::RunSinusoid(const BimorphParams& params, const Sinusoid& drive,
                                 ModalWorkspace& ws, Sink& sink, SimulationSummary& summary) const {
  const size_t n_out = static_cast<size_t>(drive.NumSamples());
  const double fs = drive.sample_rate_hz, f = drive.frequency_hz, V = drive.amplitude_v;
  const double om = 2 * std::numbers::pi * f;
  const double h = 1.0 / fs;
  const BoucWenParams bw{params.alpha, params.beta, params.gamma};
  const bool hyst = params.alpha != 0.0 && V != 0.0;
  const int m = hyst ? SubstepsFor(std::max(
                           (std::abs(params.beta) + std::abs(params.gamma)) * V * om * h, om * h))
                     : 1;
  const double hs = h / m;  // internal step
  const long n_steps = static_cast<long>(n_out - 1) * m;
  Prepare(params, hs, ws, /*exact=*/true);
  const int np = npad_;
  double* x0 = ws.x0_.data();
  double* x1 = ws.x1_.data();
  const BacklashParams bl = params.backlash();
  const double inv_len = 1.0 / length_m_;

  // Exact particular solution of the u part: η_p,i = g_u,i V Im(H_i e^{iΩt}), H_i = 1/(ω²−Ω²+icΩ).
  // The state x carries tip_i (η_i − η_p,i); it starts at −tip_i η_p,i(0).
  double htip_re = 0, htip_im = 0;
  std::fill(ws.x0_.begin(), ws.x0_.end(), 0.0);
  std::fill(ws.x1_.begin(), ws.x1_.end(), 0.0);
  for (int i = 0; i < n_; ++i) {
    const double dr = omega2_[i] - om * om, di = ws.poles_[i].c * om;
    const double den = dr * dr + di * di;
    const double hr = dr / den, hi = -di / den;
    x0[i] = -wu_[i] * V * hi;
    x1[i] = -wu_[i] * V * om * hr;
    htip_re += wu_[i] * hr;
    htip_im += wu_[i] * hi;
  }

  SineBranch sb{bw, hyst, f, V, om};
  sb.ComputeEnd();

  // The run goes chunk by chunk through the three passes of SineChunks.
  SineChunks ch(*this, ws, m, hs, V, om, htip_re, htip_im, hyst);
  ch.zr[0] = sb.Eval(0.0, V * om, 0.0);
  ch.zz[0] = ch.zr[0].z;
  ch.zzd[0] = ch.zr[0].zd;
  ch.zzdd[0] = ch.zr[0].zdd;
  const ZData l0 = ch.Left(0);
  AddMatVec(np, x0, x1, ws.p1_, -l0.z, -hs * l0.zd, -hs * hs * l0.zdd);
  double y = 0.0;
  // Output sample j: tip deflection w, its angle θ (NaN-safe: only used once w is checked),
  // backlash.
  auto output = [&](size_t j, double w, double theta, double u, double z) -> bool {
    const double t = static_cast<double>(j) / fs;
    if (!std::isfinite(w)) {
      summary.status = SimStatus::kNonFinite;
      summary.message = NonFiniteMessage(j, t);
      return false;
    }
    y = BacklashStep(bl, theta, y);
    sink.Emit(j, t, u, z, w, theta, y);
    return true;
  };
  const double w0 = SumModes(np, x0) + (Feedthrough(ch.t1c, l0) + V * htip_im);
  if (!output(0, w0, Degrees(w0, inv_len), 0.0, l0.z)) return;

  long steps = 0;
  size_t next_out = 1;
  for (long c0 = 0; c0 < n_steps; c0 += SineChunks::kChunk) {
    const long len = std::min(SineChunks::kChunk, n_steps - c0);
    ch.Drive(c0, len);
    ch.Breakpoints(sb, c0, len);
    ch.NodeZ(len);
    steps += ch.Modes(len);
    steps += len;
    if (!ch.Outputs(c0, len, fs, inv_len, bl, y, next_out, sink, summary)) return;
    ch.Carry(len);
  }
  summary.steps = steps;
}

/// Pass 2 of the sampled path: the modes over a chunk's sub-steps in order, runs of sub-steps over
/// the cached step in one loop (SampledRun), the others by GeneralSubstep; w_tip after each
/// sample's last sub-step.
static void SampledModes(const std::vector<modal::SampledSub>& subs, int n, int npad,
                         const ModePoles* poles, modal::SubStep& sub, const double* wu,
                         const double* wz, const SampledCoeffs& coeffs, double* x0, double* x1,
                         double* xs) {
  for (size_t i = 0; i < subs.size();) {
    if (subs[i].cached) {
      size_t j = i + 1;
      while (j < subs.size() && subs[j].cached) ++j;
      SampledRun(subs.data() + i, static_cast<long>(j - i), npad, x0, x1, coeffs, xs);
      i = j;
    } else {
      const modal::SampledSub& st = subs[i];
      GeneralSubstep(n, poles, sub, true, wu, wz, x0, x1, st.tau, st.l, st.r, st.u_a, st.u_dot);
      if (st.out >= 0) xs[st.out] = SumModes(npad, x0);
      ++i;
    }
  }
}

/// Pass 3 of the sampled path: θ of the chunk's outputs up to the first non-finite w_tip (their
/// count returned).
static long SampledAngles(long len, const double* xs, double inv_len, double* tho) {
  long n_ok = 0;
  while (n_ok < len && std::isfinite(xs[n_ok])) ++n_ok;
  if (!DegreesBatchExact(n_ok, xs, inv_len, tho)) {
    for (long q = 0; q < n_ok; ++q)
      if (!(std::abs(xs[q] * inv_len) < 0.125)) tho[q] = Degrees(xs[q], inv_len);
  }
  return n_ok;
}

// Pass 1 of the sampled path: the kernel's walk (pzk_fin_sample) lists each sub-step; a regular one
// of positive length runs over the cached step (SampledRun), the others by GeneralSubstep.
static void ListSubstep(void* ctx, double tau, int regular, pzk::pzk_fin_zdata zl,
                        pzk::pzk_fin_zdata zr, double u_a, double u_dot) {
  static_cast<std::vector<modal::SampledSub>*>(ctx)->push_back(
      {tau, u_a, u_dot, ZData{zl.z, zl.zd, zl.zdd}, ZData{zr.z, zr.zd, zr.zdd},
       regular != 0 && tau > 0, -1});
}

template <class Sink>
void ModalSimulator::RunSampled(const BimorphParams& params, const SampledSignal& drive,
                                ModalWorkspace& ws, Sink& sink, SimulationSummary& summary) const {
  const std::vector<double>& t = drive.t;
  const std::vector<double>& u = drive.u;
  const size_t n_out = t.size();
  const bool hyst = params.alpha != 0.0;
  const BacklashParams bl = params.backlash();
  const double inv_len = 1.0 / length_m_;
  const double kappa_max = std::abs(params.beta) + std::abs(params.gamma);

  Prepare(params, t[1] - t[0], ws, /*exact=*/true);
  std::fill(ws.x0_.begin(), ws.x0_.end(), 0.0);
  std::fill(ws.x1_.begin(), ws.x1_.end(), 0.0);
  double* x0 = ws.x0_.data();
  double* x1 = ws.x1_.data();

  double z = 0.0, y = 0.0;
  {
    const double w = SumModes(npad_, x0);  // 0: the run starts at rest
    const double theta = Degrees(w, inv_len);
    y = BacklashStep(bl, theta, y);
    sink.Emit(0, t[0], u[0], z, w, theta, y);
  }
  // The run goes chunk by chunk (at most kChunk output samples, and fewer when the step changes so
  // much that the discretisation is redone) through three passes:
  //  1. z, which depends on u alone: each sample's sub-steps (split where κ|u̇|τ > 1/2 and at the
  //     zero crossings of z) with the hold data at their ends, listed by the kernel's walk
  //     (pzk_fin_sample);
  //  2. the modes over the sub-steps in order: runs of sub-steps over the cached step in one loop
  //     (SampledRun), the others by GeneralSubstep; w_tip after each sample's last sub-step;
  //  3. outputs: θ in one loop, the backlash (BacklashRun), the sink.
  constexpr size_t kChunk = 256;
  std::vector<modal::SampledSub>& subs = ws.subs_;
  ws.xs_.resize(kChunk + 1);
  ws.zo_.resize(kChunk);
  for (auto* v : {&ws.tho_, &ws.yo_}) v->resize(kChunk);
  double *xs = ws.xs_.data(), *zo = ws.zo_.data(), *tho = ws.tho_.data(), *yo = ws.yo_.data();
  long steps = 0;
  size_t k = 0;
  while (k + 1 < n_out) {
    // Pass 1.
    const size_t k0 = k;
    subs.clear();
    while (k + 1 < n_out && k - k0 < kChunk) {
      const double tau = t[k + 1] - t[k];
      const double r = (u[k + 1] - u[k]) / tau;  // u̇ on the segment
      const int nsub = pzk::pzk_fin_substeps(hyst, kappa_max, r, tau);
      const double ts = nsub == 1 ? tau : tau / nsub;  // the same value, without the division
      // Holds(params, ts, ws) — the workspace holds this simulator's (μ, δ) since the Prepare above
      // (finite: Admit validated them), so only the step is compared.
      if (!(std::abs(ws.step_ - ts) <=
            kStepRelTol * ts)) {  // another discretisation: after the chunk's
        if (k > k0) break;        // sub-steps have run on this one
        Prepare(params, ts, ws);
      }
      z = pzk::pzk_fin_sample(params.alpha, params.beta, params.gamma, u[k], z, u[k + 1], tau, nsub,
                              ListSubstep, &subs);
      subs.back().out = static_cast<int>(k - k0);
      zo[k - k0] = z;
      ++k;
    }
    steps += static_cast<long>(subs.size());
    // Pass 2.
    const SampledCoeffs coeffs{ws.e11_.data(),
                               ws.e12_.data(),
                               ws.e21_.data(),
                               ws.e22_.data(),
                               ws.nwz_.data(),
                               ws.wu_.data(),
                               {ws.d_[0].data(), ws.d_[1].data(), ws.d_[2].data(), ws.d_[3].data(),
                                ws.d_[4].data(), ws.d_[5].data(), ws.d_[6].data()}};
    SampledModes(subs, n_, npad_, ws.poles_.data(), ws.sub_, wu_.data(), wz_.data(), coeffs, x0, x1,
                 xs);
    // Pass 3: the outputs up to the first non-finite w_tip.
    const long len = static_cast<long>(k - k0);
    const long n_ok = SampledAngles(len, xs, inv_len, tho);
    y = BacklashRun(bl, tho, yo, n_ok, y);
    for (long q = 0; q < n_ok; ++q) {
      const size_t j = k0 + 1 + static_cast<size_t>(q);
      sink.Emit(j, t[j], u[j], zo[q], xs[q], tho[q], yo[q]);
    }
    if (n_ok < len) {
      const size_t j = k0 + 1 + static_cast<size_t>(n_ok);
      summary.status = SimStatus::kNonFinite;
      summary.message = NonFiniteMessage(j, t[j]);
      return;
    }
  }
  summary.steps = steps;
}

template <class Sink>
SimulationSummary ModalSimulator::Run(const BimorphParams& params, const DriveSignal& drive,
                                      ModalWorkspace& ws, Sink& sink) const {
  SimulationSummary summary;
  if (std::holds_alternative<Sinusoid>(drive)) {
    RunSinusoid(params, std::get<Sinusoid>(drive), ws, sink, summary);
  } else {
    RunSampled(params, std::get<SampledSignal>(drive), ws, sink, summary);
  }
  return summary;
}

namespace {

// Validation shared by every entry point; returns false with the summary filled on failure.
bool Admit(const BimorphParams& params, size_t n_out, size_t expected_out,
           SimulationSummary& summary) {
  auto fail = [&](SimStatus st, std::string msg) {
    summary.status = st;
    summary.message = std::move(msg);
    return false;
  };
  if (auto s = params.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  if (!params.HysteresisBounded())
    return fail(
        SimStatus::kUnboundedHysteresis,
        FieldError(
            "(alpha, beta, gamma)",
            "(" + std::to_string(params.alpha) + ", " + std::to_string(params.beta) + ", " +
                std::to_string(params.gamma) + ")",
            "Bouc-Wen loop unbounded: needs alpha = 0, or beta + gamma > 0 and beta - gamma >= 0"));
  if (n_out != expected_out)
    return fail(SimStatus::kInvalidInput,
                FieldError("angle_deg.size()", n_out,
                           "must equal the number of samples " + std::to_string(expected_out)));
  return true;
}

size_t NumSamples(const DriveSignal& drive) {
  if (const auto* s = std::get_if<Sinusoid>(&drive))
    return static_cast<size_t>(std::max(0, s->NumSamples()));
  return std::get<SampledSignal>(drive).t.size();
}

double Seconds(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

SimulationSummary ModalSimulator::SimulateAngle(const BimorphParams& params, const Sinusoid& drive,
                                                std::span<double> angle_deg,
                                                ModalWorkspace& ws) const {
  const auto start = std::chrono::steady_clock::now();
  SimulationSummary summary;
  // Validate the sinusoid first: NumSamples() is only meaningful for a valid one.
  if (auto s = drive.Validate(); !s.ok()) {
    summary.status = SimStatus::kInvalidInput;
    summary.message = s.message();
  } else if (Admit(params, angle_deg.size(), static_cast<size_t>(drive.NumSamples()), summary)) {
    AngleSink sink{angle_deg};
    RunSinusoid(params, drive, ws, sink, summary);
  }
  summary.wall_time_s = Seconds(start);
  return summary;
}

SimulationSummary ModalSimulator::SimulateAngle(const BimorphParams& params, const Sinusoid& drive,
                                                std::span<double> angle_deg) const {
  thread_local ModalWorkspace ws;
  return SimulateAngle(params, drive, angle_deg, ws);
}

SimulationSummary ModalSimulator::SimulateAngle(const BimorphParams& params,
                                                const DriveSignal& drive,
                                                std::span<double> angle_deg,
                                                ModalWorkspace& ws) const {
  const auto start = std::chrono::steady_clock::now();
  SimulationSummary summary;
  if (auto s = Validate(drive); !s.ok()) {
    summary.status = SimStatus::kInvalidInput;
    summary.message = s.message();
  } else if (Admit(params, angle_deg.size(), NumSamples(drive), summary)) {
    AngleSink sink{angle_deg};
    summary = Run(params, drive, ws, sink);
  }
  summary.wall_time_s = Seconds(start);
  return summary;
}

void ModalSimulator::Simulate(const BimorphParams& params, const DriveSignal& drive,
                              BimorphTrace& trace, ModalWorkspace& ws) const {
  const auto start = std::chrono::steady_clock::now();
  trace.summary = SimulationSummary{};
  size_t n = 0;
  if (auto s = Validate(drive); !s.ok()) {
    trace.summary.status = SimStatus::kInvalidInput;
    trace.summary.message = s.message();
  } else {
    n = NumSamples(drive);
  }
  for (auto* v : {&trace.t, &trace.u, &trace.z, &trace.w_tip, &trace.theta_deg, &trace.angle_deg})
    v->assign(n, std::numeric_limits<double>::quiet_NaN());
  if (trace.summary.ok() && Admit(params, n, n, trace.summary)) {
    TraceSink sink{&trace};
    trace.summary = Run(params, drive, ws, sink);
  }
  if (!trace.summary.ok() && trace.summary.status != SimStatus::kNonFinite) {
    for (auto* v : {&trace.t, &trace.u, &trace.z, &trace.w_tip, &trace.theta_deg, &trace.angle_deg})
      v->clear();
  }
  trace.summary.wall_time_s = Seconds(start);
}

BimorphTrace ModalSimulator::Simulate(const BimorphParams& params, const DriveSignal& drive) const {
  thread_local ModalWorkspace ws;
  BimorphTrace trace;
  Simulate(params, drive, trace, ws);
  return trace;
}

}  // namespace pz::model
