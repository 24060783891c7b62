// The fast path of the bimorph-fin plant as a reusable, allocation-free simulator for the GA
// fitness.
//
// With C = μM + δK the mass-normalised modes decouple (spec §6):
//
//   η̈_i + (μ + δ ω_i²) η̇_i + ω_i² η_i = g_u,i u(t) − g_z,i z(t),     w_tip = Σ_i tip_i η_i
//
// and z (Bouc–Wen) depends on u alone, in closed form per branch (model/bouc_wen.h). Each mode is
// advanced by its exact discretisation (the C step kernel's, model/kernels/fin_modal.h: the one
// source of the fin's step, which the records family and the exported plant run too) with a
// quintic Hermite hold of z built from the analytic z, ż, z̈ at the step ends; steps are split at
// the zero crossings of z and the reversals of u. For a sinusoid the response to u is the exact
// particular solution Im(H_i(iΩ) g_u,i V e^{iΩt}), so only z drives the recursion (a path of its
// own: the kernel has none); for a sampled signal u is linear
// between samples and held exactly: each sample's walk is the kernel's (pzk_fin_sample), its
// sub-steps run four modes a vector (the kernel's arithmetic, the same bits; docs/architecture.md
// "The fin's step" has the two paths kept beside the kernel and their figures).
//
// Threading: a ModalSimulator is immutable after construction and can be shared by any number of
// threads; all mutable state lives in a ModalWorkspace, one per thread (the overloads without a
// workspace use a thread_local one).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "model/bimorph.h"
#include "model/bouc_wen.h"
#include "model/modal_discretise.h"

namespace pz::model {

namespace modal {
/// z and its first two time derivatives at one instant: the end data of the quintic hold.
struct ZData {
  double z = 0;    ///< [N]
  double zd = 0;   ///< ż [N/s]
  double zdd = 0;  ///< z̈ [N/s²]
  bool operator==(const ZData&) const = default;
};
/// A sub-step of the sampled path (u linear, z held by the quintic Hermite of its end data).
struct SampledSub {
  double tau = 0;             ///< length [s]
  double u_a = 0, u_dot = 0;  ///< u at its start [V], its slope [V/s]
  ZData l, r;                 ///< the hold data at its ends
  bool cached = false;        ///< over the workspace's step (its discretisation), else made for tau
  int out = -1;               ///< ≥ 0: the last sub-step of output sample `out` of the chunk
};
/// The discretisation of a sub-step of arbitrary length (all modes) and DiscretiseBatch's scratch.
struct SubStep {
  std::vector<ModeStep> steps;
  std::vector<double> scratch;
  std::vector<int> idx;
};
}  // namespace modal

/// Scratch for ModalSimulator: mode states and a cache of the last discretisation (keyed by the
/// simulator, μ, δ and the step). Grows on first use, then allocates nothing. One per thread.
class ModalWorkspace {
 public:
  ModalWorkspace() = default;

 private:
  friend class ModalSimulator;
  // Cache key.
  uint64_t sim_id_ = 0;
  double mu_ = -1, delta_ = -1, step_ = -1;
  // Per-mode data for the cached (μ, δ, step), padded to a multiple of 4 modes.
  std::vector<modal::ModePoles> poles_;
  std::vector<modal::ModeStep> steps_;  // discretisation over `step_`
  modal::SubStep sub_;
  std::vector<double> e11_, e12_, e21_, e22_;
  std::vector<double> g_[6];    // G = E P1 + P0 (rows 0, 1 × z, τż, τ²z̈)
  std::vector<double> p1_[6];   // P1: response to the end-of-step Hermite data
  std::vector<double> ep1_[6];  // E P1
  double t1_[3] = {0, 0, 0};    // Σ_i P1_i row 0 (feed-through of the end data to w_tip)
  // Mode states (scaled by tip_i, so that w_tip = Σ x0).
  std::vector<double> x0_, x1_;
  // Sinusoid path, one chunk of steps at a time.
  struct Special {  // a step with breakpoints inside, or with a data jump at its first node
    long step;
    int inner_begin, inner_end;  // its breakpoints in inner_
  };
  struct Inner {  // a breakpoint: time since the step's first node, data just before and after
    double offset;
    modal::ZData left, right;
  };
  std::vector<modal::ZData> zr_;  // hold data at the nodes: right limits (the left ones are zz_ …)
  std::vector<double> xs_, base_;  // Σ x̄0, state-free part of w_tip at the nodes
  // Pass 1 computes each node's drive (u, u̇, ü, e^{iΩt}) in one vectorised loop, finds the
  // breakpoints, and evaluates z segment by segment (the nodes between breakpoints share a branch).
  std::vector<double> nu_, nud_, nudd_, nre_, nim_;
  std::vector<double> zz_, zzd_, zzdd_;
  struct SegmentData {
    long from, to;
    BoucWenBranch branch;
  };
  std::vector<SegmentData> segments_;
  std::vector<std::pair<long, BoucWenBranch>>
      jumps_;                          // nodes whose right limit is on another branch
  std::vector<double> wo_, tho_, yo_;  // pass 3: w_tip, θ and y at the chunk's outputs
  std::vector<long> io_;               //         and their nodes
  std::vector<Special> special_;
  std::vector<Inner> inner_;
  // Sampled path, one chunk of samples at a time: pass 1 lists the sub-steps with their hold data,
  // pass 2 runs the modes over them (runs of cached steps in one loop over the modes' SoA data).
  std::vector<modal::SampledSub> subs_;
  std::vector<double> d_[modal::kMaxPhi + 1];  // the cached step's D_j per mode (npad entries)
  std::vector<double> nwz_, wu_;               // −tip_i g_z,i and tip_i g_u,i, padded with zeros
  std::vector<double> zo_;                     // z at the chunk's output samples
};

class ModalSimulator {
 public:
  /// Copies what it needs of the plant's modal basis; the plant must outlive the simulator.
  explicit ModalSimulator(const BimorphPlant& plant);

  const BimorphPlant& plant() const { return *plant_; }
  /// Number of modes simulated (modes invisible at the tip are dropped).
  int num_modes() const { return n_; }
  /// The simulated modes' ω_i² [1/s²], tip_i g_u,i and tip_i g_z,i (num_modes() each), and the fin
  /// length L [m]: what a per-sample export of the plant (controller/export_fin_c.h) needs.
  std::span<const double> omega2() const { return omega2_; }
  std::span<const double> tip_gain_u() const { return wu_; }
  std::span<const double> tip_gain_z() const { return wz_; }
  double length_m() const { return length_m_; }

  /// Hot path of the GA fitness: the fin angle y_k [deg] of a sinusoid drive into `angle_deg`,
  /// whose size must be drive.NumSamples(). Validates params and drive, returns
  /// kUnboundedHysteresis for an unbounded loop; never throws. No heap allocation once `ws` has
  /// served a run of this plant.
  SimulationSummary SimulateAngle(const BimorphParams& params, const Sinusoid& drive,
                                  std::span<double> angle_deg, ModalWorkspace& ws) const;
  /// Same with a thread_local workspace.
  SimulationSummary SimulateAngle(const BimorphParams& params, const Sinusoid& drive,
                                  std::span<double> angle_deg) const;
  /// Any drive (sinusoid or sampled); `angle_deg` has one entry per sample of the drive.
  SimulationSummary SimulateAngle(const BimorphParams& params, const DriveSignal& drive,
                                  std::span<double> angle_deg, ModalWorkspace& ws) const;

  /// Full trace (t, u, z, w_tip, θ, y and the summary) into `trace`, reusing its vectors.
  void Simulate(const BimorphParams& params, const DriveSignal& drive, BimorphTrace& trace,
                ModalWorkspace& ws) const;
  BimorphTrace Simulate(const BimorphParams& params, const DriveSignal& drive) const;

 private:
  template <class Sink>
  SimulationSummary Run(const BimorphParams& params, const DriveSignal& drive, ModalWorkspace& ws,
                        Sink& sink) const;
  struct SineChunks;  // RunSinusoid's chunk loop: its buffers in the workspace and its passes
  template <class Sink>
  void RunSinusoid(const BimorphParams& params, const Sinusoid& drive, ModalWorkspace& ws,
                   Sink& sink, SimulationSummary& summary) const;
  template <class Sink>
  void RunSampled(const BimorphParams& params, const SampledSignal& drive, ModalWorkspace& ws,
                  Sink& sink, SimulationSummary& summary) const;
  /// Discretises the modes over `step` into ws, unless ws holds (μ, δ) and a step within 1e-10 of
  /// it. `exact`: only the same step is reused — every run starts so, so a run's result never
  /// depends on what the thread's workspace ran before (within a run the tolerance saves the
  /// re-discretising of a sampled grid's steps, which differ in their last bits).
  void Prepare(const BimorphParams& params, double step, ModalWorkspace& ws,
               bool exact = false) const;
  /// True when Prepare(params, step, ws) (not exact) would keep ws's discretisation.
  bool Holds(const BimorphParams& params, double step, const ModalWorkspace& ws) const;

  const BimorphPlant* plant_;
  uint64_t id_;
  int n_ = 0;     // modes kept
  int npad_ = 0;  // n_ rounded up to a multiple of 4
  double length_m_ = 0;
  std::vector<double> omega2_;  // ω_i² [1/s²]
  std::vector<double> wu_;      // tip_i g_u,i [m/V per unit modal acceleration]
  std::vector<double> wz_;      // tip_i g_z,i
};

}  // namespace pz::model
