// The bimorph-fin bench's effects (the bench form of records/families.h's bimorph-fin family,
// FamilyOptions::bench_form; issues 6, 21, 46): which effects of the one library
// (model/effect_library.h) the bench offers, each with its search box — physical ranges, a typical
// scale, a doc line and its place in the fin's order, in one table (kFinBoxes in
// records/fin_effects.cc) keyed by the library's effect —, and EffectSimulator, which runs the
// bimorph plant with any list of them. The library itself knows nothing of the bench. Zero
// magnitude is the identity. Today, in the fin's order:
//
//   library effect     stage    fin-bench range
//   driver-lowpass     drive    tau_s ∈ [0, 0.2] s
//   creep              drive    k_c ∈ [0, 1], tau_c_s ∈ [0.05, 50] s
//   hinge-friction     beam     fc_n ∈ [0, 1] N, sigma ∈ [20, 2e5] N/m
//   delay              drive    tau_d_s ∈ [0, 0.1] s
//   cubic-stiffening   beam     k3 ∈ [−5e6, 2e7] N/m³
//   quadratic-drive    drive    c2 ∈ [−5e-4, 5e-4] 1/V
//   drift              output   rate ∈ [−0.2, 0.2] deg/s  (former name output-drift)
//
// The arithmetic is the library's: drive effects run in the library's chain order (low-pass →
// quadratic → creep → delay) through EffectDef::ApplyDrive, output effects through ApplyOutput on
// the fin angle, beam effects (and, on the CVODE path, the drive filters) as the library's
// BimorphExtensions. EffectSimulator runs a plant with any list of effects on the fastest exact
// path: without beam effects the shaped drive is computed on a fine grid (the library's exact
// first-order-hold filters; without filters pointwise, the delay as an exact time shift) and fed to
// the fast modal path as a SampledSignal, the linear fin angle θ is read on the record's grid and
// the backlash is applied there (spec §3: the backlash lives on the sample grid); with a beam
// effect the whole chain runs on CVODE (drive stages as extensions, the delay as a shift of the
// output times, which is exact for a time-invariant plant started from rest).
//
// Pure library: no I/O. EffectSimulator is immutable and thread-safe (per-thread scratch, which
// never carries a result from one call to the next).
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "model/bimorph.h"
#include "model/bimorph_ode.h"
#include "model/effect_library.h"
#include "model/modal_simulator.h"
#include "model/signal.h"
#include "model/simulation.h"
#include "model/status.h"

namespace pz::records {

/// One physical parameter of an effect.
struct EffectParamInfo {
  std::string name;  ///< e.g. "tau_s"
  std::string unit;  ///< e.g. "s"
  double lower = 0;  ///< valid range, lower ≤ value ≤ upper
  double upper = 0;
  double scale = 1;        ///< typical magnitude (search scaling, finite-difference steps), > 0
  bool log_scale = false;  ///< searched on a log scale (then lower > 0)
  std::string doc;
};

/// An effect as the fin bench offers it: the library's names, the bench box's parameters.
struct FinEffectInfo {
  model::EffectKind kind;                 ///< the library's effect (none: the entry "none")
  const model::EffectDef* def = nullptr;  ///< kind.def()
  std::string name;                       ///< selectable name, e.g. "driver-lowpass"
  std::string title;                      ///< e.g. "driver (amplifier) low-pass"
  model::EffectStage stage = model::EffectStage::kDrive;
  std::string equation;  ///< one line
  /// Index of the parameter whose zero makes the effect the identity (the magnitude), or -1.
  int magnitude_param = 0;
  std::vector<EffectParamInfo> params;
};

/// Every effect the fin bench offers (one with a box in kFinBoxes), in the fin's order.
const std::vector<FinEffectInfo>& FinEffects();
/// The entry of one kind (none, or an effect the fin does not offer: name "none", no parameters).
const FinEffectInfo& GetFinEffectInfo(model::EffectKind kind);
/// True when the fin bench offers the effect.
bool IsFinEffect(model::EffectKind kind);
/// Position of a fin effect in FinEffects() plus one; 0 for none (the rows of the fin check's
/// confusion matrix). Throws std::logic_error for an effect the fin does not offer.
int FinIndex(model::EffectKind kind);
/// Parses a name of FinEffects(), "none" or a former name ("output-drift"); nullopt if unknown
/// or not a fin effect (FinEffectError says which).
std::optional<model::EffectKind> ParseEffectKind(std::string_view name);
/// Why `name` is not a fin effect ("not an effect of the fin bench: …" for a library effect the fin
/// does not offer, "not an effect of the library: …" else); lists the fin's effects.
std::string FinEffectError(std::string_view name);

/// One effect with its parameter values (in GetFinEffectInfo(kind).params order, physical units).
struct Effect {
  model::EffectKind kind;
  std::vector<double> params;

  /// Count, finiteness and ranges; the error names the effect, the parameter, the value and the
  /// range.
  Status Validate() const;
  /// True when the effect changes nothing (none, or its magnitude parameter is 0).
  bool IsIdentity() const;
  /// e.g. "driver-lowpass(tau_s = 0.02 s)".
  std::string Describe() const;
  /// The effect with every parameter at zero magnitude (identity) and others mid-range.
  static Effect Zero(model::EffectKind kind);
};

/// True if any (non-identity) effect of the list needs the CVODE path.
bool NeedsCvode(std::span<const Effect> effects);

/// Options of EffectSimulator.
struct EffectSimOptions {
  int oversample = 4;        ///< fine-grid factor of the sampled fast path, 1 … 64
  double rtol = 1e-6;        ///< CVODE relative tolerance, in (0, 1e-2] (≈ 2e-6 deg on the bench)
  double atol = 1e-13;       ///< CVODE absolute tolerance, > 0
  long max_steps = 5000000;  ///< CVODE step budget, > 0
  bool force_cvode = false;  ///< run on CVODE even without beam effects (accuracy checks)
  Status Validate() const;
};

/// The drive u_e(t_j) [V] after the drive-stage effects (low-pass, quadratic, creep, delay) at the
/// given times (≥ 0, increasing), for the sinusoid u from rest. Exact to first-order-hold
/// discretisation error on a grid 4 × finer than the spacing of `t` (≈ 1e-7 of V at 400 Hz).
std::vector<double> ShapedDrive(std::span<const Effect> effects, const model::Sinusoid& drive,
                                std::span<const double> t);

/// CVODE extensions of the drive and beam stages, in stage order (delay and drift are not
/// extensions: they act on the output times and values). Identity effects are left out.
std::vector<std::unique_ptr<model::BimorphExtension>> MakeExtensions(
    std::span<const Effect> effects);

/// Runs the bimorph plant with effects. Immutable after construction; thread-safe.
class EffectSimulator {
 public:
  /// The plant must outlive the simulator.
  explicit EffectSimulator(const model::BimorphPlant& plant);
  const model::BimorphPlant& plant() const { return *plant_; }
  const model::ModalSimulator& modal() const { return modal_; }

  /// Fin angle y_k [deg] on the drive's sample grid into angle_deg (drive.NumSamples() entries);
  /// optionally the linear fin angle θ_k [deg] into theta_deg (same size, or empty). Never throws:
  /// invalid parameters / effects / options come back as kInvalidInput, physical failures as in
  /// model::Simulate(). A CVODE run that stalls is tried once more at BDF order ≤ 2
  /// (model/cvode.h).
  model::SimulationSummary SimulateAngle(const model::BimorphParams& params,
                                         std::span<const Effect> effects,
                                         const model::Sinusoid& drive, std::span<double> angle_deg,
                                         const EffectSimOptions& options = {},
                                         std::span<double> theta_deg = {}) const;

 private:
  const model::BimorphPlant* plant_;
  model::ModalSimulator modal_;
};

}  // namespace pz::records
