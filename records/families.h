// The plant families `piezoid fit` identifies on measured records (issue 14), behind one
// interface: drive samples u (any waveform) → model output ŷ on the same samples, from rest at u_0.
//
//   stack-bouc-wen      Bouc–Wen stack with driver filter (model/stack_models.h), α β γ d fc
//   backlash-like       Coleman–Hodgdon / Su backlash-like (model/stack_models.h), α c B1
//   duhem               Duhem-type with cubic curve and relaxation (model/duhem.h), α c c3 b λ
//   prandtl-ishlinskii  PI operator (model/prandtl_ishlinskii.h): weights solved by non-negative
//                       least squares for given thresholds (no search), invertible by design
//   bw-oscillator       Bouc–Wen hysteretic oscillator (model/bw_oscillator.h), driven by the
//                       drive through a gain: K fn ζ share βγ βδ; or, with OscillatorOptions, the
//                       Bouc–Wen benchmark's protocol (complete/boucwen_benchmark.h): m c k α βγ βδ
//   preisach            discrete Preisach model on a triangular grid of relays over the training
//                       drive range (model/preisach.h), FamilyOptions::pi_operators levels: cell
//                       weights by non-negative least squares with a roughness penalty along the
//                       centre axis or over the whole triangle, the penalty and its strength chosen
//                       by blocked cross-validation (records/regularisation.h ChoosePenalty); exact
//                       inverse by one-step bisection
//   asymmetric-pi       PI operator plus a monotone memoryless bend from one-sided dead zones of
//                       the drive (model/preisach.h): asymmetric loops, weights ≥ 0 (monotone,
//                       exact inverse), a ridge on the dead zones chosen by the same validation
//   bimorph-fin         the bimorph fin (model/bimorph.h, modal path) with an output gain:
//                       μ δ α β γ a1 a2 b1 b2 gain, and the beam's geometry: active length L_p
//                       and tip length L_e (searched around FamilyOptions::geometry; the
//                       cross-section and materials stay that geometry's); in its bench form
//                       (FamilyOptions::bench_form) the fin bench's model: μ δ α β γ a1 a2 in
//                       the fin's box, γ searched as γ/β, the geometry and the gain (1: degrees)
//                       fixed, b1 b2 per record from its measured extremes, each record's stated
//                       sinusoid simulated with any fin effect, beam ones included (on CVODE)
//
// A family is made for a data scale (drive range, response range, dominant frequency, sample
// rate) measured on the training records: its search box is scaled to it, so the same family fits
// volts and micrometres, millivolts and nanometres, 1 Hz and 300 Hz.
#pragma once

#include <algorithm>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "io/records.h"
#include "model/beam.h"
#include "model/bw_oscillator.h"
#include "model/effect_library.h"
#include "model/prandtl_ishlinskii.h"
#include "model/status.h"
#include "records/fin_effects.h"

namespace pz::records {

class NormalEquationsBuilder;  // records/regularisation.h

/// FamilyOptions::pi_operators for a Preisach grid whose levels the validation chooses.
inline constexpr int kAutoLevels = 0;

/// Scales measured on the records a family is made for (model/effect_library.h: the effects' ranges
/// are scaled by it too).
using DataScale = model::DataScale;
/// Measures the scale on the scored samples of the records (≥ 1). Throws InputError when the drive
/// is constant (nothing to identify) naming the records.
DataScale MeasureScale(const std::vector<const io::Record*>& records);

using ParamInfo = model::ParamInfo;  ///< a searched parameter (model/effect_library.h)

/// The bw-oscillator family's protocol. The defaults are `piezoid fit`'s (the scaled parameters, a
/// drive linear between samples, from rest under u_0); the Bouc–Wen benchmark
/// (complete/boucwen_benchmark.h) sets every field.
struct OscillatorOptions {
  /// θ = (m, c, k, α, β·γ, β·δ) in the data's units (ν = 1, model::BwFromIdentifiable) in the
  /// benchmark's box (SI: m 0.2–20 kg, c 0.1–1000 N s/m, k and α 1e3–1e6 N/m, β·γ 1–1e5 1/m,
  /// β·δ ±1e4 1/m; not scaled to the data), instead of (K, f_n, ζ, share, β·γ, β·δ) scaled to it.
  bool physical = false;
  int rk4_steps = 0;  ///< RK4 steps per sample, 1 … 1000; 0 = 2 × FamilyOptions::substeps
  model::InputInterpolation interpolation =
      model::InputInterpolation::kLinear;  ///< the drive between samples
  size_t period_samples = 0;  ///< kPeriodicFourier: samples per period (0 = the whole record)
  bool from_zero_state =
      false;  ///< start at y = ẏ = z = 0 (the benchmark's generator), not at rest under u_0
};

struct FamilyOptions {
  int substeps = 2;  ///< stack Bouc–Wen filter / Duhem sub-steps; oscillator RK4 steps (×2)
  /// Prandtl–Ishlinskii / asymmetric-pi plays; preisach grid levels, or kAutoLevels: chosen by
  /// validation on the training records (records/fit.h FitRecords, ChoosePreisachLevels).
  int pi_operators = 12;
  /// The memory at rest at the first sample's drive u_0 (model/prandtl_ishlinskii.h InitialState)
  /// of the families that take it (TakesInitialState): the plays of prandtl-ishlinskii,
  /// asymmetric-pi and preisach at u_0, u_0 + r or u_0 − r; the Bouc–Wen h of stack-bouc-wen and
  /// the w of backlash-like after a rise by the data's full range 2 u_half and a fall back to u_0
  /// (model/stack_models.h StackRestState), or the mirror. Others start centred (and ignore it).
  /// Default kAuto: resolved on each record's first drive against the data's drive range
  /// (model::ResolveInitialState: descended at a rest at the bottom, ascended at the top, else
  /// centred). A fit.json written before the field reads as centred (records/stepper.h).
  model::InitialState initial_state = model::InitialState::kAuto;
  model::BeamGeometry geometry;  ///< bimorph fin
  /// bimorph-fin: the fin bench's form, its diagnosis's model (diagnose/fin_diagnose.h): μ, δ, α,
  /// β, γ, a1, a2 searched in the fin's box (γ as the ratio γ/β, Family::SearchForm), the geometry
  /// fixed at `geometry` and the output the fin angle in degrees (no gain); the saturations b1, b2
  /// of each record from its measured extremes (model/saturation.h SaturationFromExtremes); each
  /// record simulated on its stated sinusoid (io::Record::sinusoid, io/fin_records.h) by
  /// EffectSimulator (records/fin_effects.h) with `fin_sim`, the fin's effects in their boxes, beam
  /// effects (hinge-friction, cubic-stiffening) included: those run on CVODE.
  bool bench_form = false;
  EffectSimOptions fin_sim;         ///< bench form: the simulator's options
  OscillatorOptions oscillator;     ///< bw-oscillator
  /// A fold of a cross-validation (records/select.h): the family is made for the whole training
  /// set's scale and a fold's training pieces may not reach every part of it (loops growing from a
  /// rest reach the top of the range in their last block only). The preisach grid then accepts a
  /// level without training samples: the roughness prior sets its cells, and the masked block
  /// scores that extrapolation. A fit on the user's records keeps the check (CheckTraining).
  bool cross_validation_fold = false;
};

class Family {
 public:
  virtual ~Family() = default;
  virtual std::string name() const = 0;
  virtual std::string title() const = 0;
  virtual std::string equation() const = 0;
  /// The searched parameters (empty for a linear-in-parameters family).
  virtual const std::vector<ParamInfo>& params() const = 0;
  /// Simulates from rest at u[0] into y (same size). A diverging parameter set gives non-finite
  /// values (callers penalise them); invalid sizes throw InputError. Thread-safe.
  virtual void Simulate(std::span<const double> p, std::span<const double> u, double dt,
                        std::span<double> y) const = 0;
  /// The per-record prepare step: work that depends on the drive alone and that every simulation
  /// of it would repeat (the oscillator's input table: an FFT or spline per record) is done once
  /// by Prepare and handed to SimulatePrepared, which must give Simulate's output bit for bit.
  /// RecordModel::Prepare calls it for a record whose drive no effect changes, RecordFitness keeps
  /// one per training record. Immutable, so shared by threads. The default prepares nothing.
  struct Prepared {
    virtual ~Prepared() = default;
  };
  virtual std::shared_ptr<const Prepared> Prepare(std::span<const double> u, double dt) const;
  /// Simulate with `prepared` = Prepare(u, dt) of this family (null: as Simulate).
  virtual void SimulatePrepared(const Prepared* prepared, std::span<const double> p,
                                std::span<const double> u, double dt, std::span<double> y) const;
  /// How many parameter sets SimulatePreparedMany and SimulateMany run side by side to gain from it
  /// (1: none).
  virtual int lanes() const { return 1; }
  /// SimulatePrepared for each ps[l] into ys[l], bit for bit (the default calls it for each).
  virtual void SimulatePreparedMany(const Prepared* prepared,
                                    std::span<const std::span<const double>> ps,
                                    std::span<const double> u, double dt,
                                    std::span<const std::span<double>> ys) const;
  /// Each parameter set on its own drive (us[l]: what a model's drive effects make of the record's
  /// drive for that set, RecordModel::SimulateMany): Simulate(ps[l], us[l], dt, ys[l]) for each,
  /// bit for bit (the default calls it for each). The drives have one length.
  virtual void SimulateMany(std::span<const std::span<const double>> ps,
                            std::span<const std::span<const double>> us, double dt,
                            std::span<const std::span<double>> ys) const;
  /// Linear-in-parameters families: the regressors of u (rows = samples, columns = weights, in
  /// row-major order), whose non-negative combination is the output. Others: not called.
  virtual bool linear() const { return false; }
  virtual size_t regressors() const { return 0; }
  virtual void Regressors(std::span<const double> u, std::span<double> out) const;
  /// A linear family whose rows have structure (preisach: records/preisach_normal.h): adds record
  /// r's scored rows — AddRecordRows's of Regressors(u), u the drive of the rows from `from` — to
  /// the builder without forming them. False (the default): the caller forms them.
  virtual bool AddNormalEquations(const io::Record& r, size_t from, std::span<const double> u,
                                  int pol, NormalEquationsBuilder& builder) const;
  /// How parameter i is searched beyond its box (RecordModel::search_forms): `ratio_of` ≥ 0: as
  /// the ratio p[i] / p[ratio_of] within [lower, upper] (the fin's γ/β: every point of the box is
  /// a bounded loop; records/fit.h RecordMap); `scale` > 0: its typical magnitude (the
  /// uncertainty's steps and sensitivities) in place of the box's.
  struct SearchForm {
    int ratio_of = -1;
    double scale = 0;
  };
  /// One per params() entry; empty (the default): each parameter by its box.
  virtual std::vector<SearchForm> search_forms() const { return {}; }
  /// A family that simulates whole records, its effects included (bimorph-fin's bench form: each
  /// record's stated sinusoid and saturations): RecordModel hands it each record with the model's
  /// parameters (SimulateRecord) and takes the effects' boxes from EffectBox, in the order given.
  virtual bool simulates_records() const { return false; }
  /// Its fit's cost is the sum of squared errors over the training records, not their mean (the
  /// fin bench's CF = Σ PI: bimorph-fin's bench form, so that its fit runs the fin's arithmetic —
  /// a CVODE model's finite differences turn a rounding of the residuals into a different step).
  virtual bool sums_errors() const { return false; }
  /// simulates_records: the output on samples [0, end) of r into y with the family's parameters p
  /// and `effects` with their parameters `ep` (each one's EffectBox, in that order); NaN for a
  /// parameter set the model cannot run. Throws InputError for a record it cannot simulate.
  virtual void SimulateRecord(const io::Record& r, std::span<const double> p,
                              std::span<const model::EffectKind> effects,
                              std::span<const double> ep, size_t end, std::span<double> y) const;
  /// simulates_records: effect e's parameters and their search forms (appended to `forms`); throws
  /// InputError naming an effect the family does not take.
  virtual std::vector<ParamInfo> EffectBox(model::EffectKind e,
                                           std::vector<SearchForm>* forms) const;
  /// Names of the solved weights (linear families).
  virtual std::vector<std::string> weight_names() const { return {}; }
  /// A penalty λ wᵀRw on a linear family's weights: its name (reports) and the Gram matrix R
  /// (regressors × regressors, row-major, positive semi-definite).
  struct Penalty {
    std::string name;
    std::vector<double> gram;
  };
  /// Linear families: the candidate penalties added to the weights' least squares; the validation
  /// on the training records keeps one and chooses its strength λ (records/regularisation.h
  /// ChoosePenalty). Empty: none.
  virtual std::vector<Penalty> regularisation() const { return {}; }
  /// Throws InputError saying what is missing when the training records (scored windows) cannot
  /// support the family (e.g. no reversals for a Preisach grid). Default: accepts any records.
  virtual void CheckTraining(const std::vector<const io::Record*>& train) const { (void)train; }
  /// The effects of the diagnosis library that make physical sense on top of this family (the
  /// ones it already contains are left out: the stack Bouc–Wen has a driver filter, the Duhem
  /// model a relaxation, the PI model plays).
  virtual std::vector<std::string> excluded_effects() const { return {}; }
  /// Whether `effect` is one of excluded_effects() (the family already holds it).
  bool Excludes(std::string_view effect) const {
    const std::vector<std::string> e = excluded_effects();
    return std::find(e.begin(), e.end(), effect) != e.end();
  }
  /// The memory it starts with at rest (FamilyOptions::initial_state for the families that take
  /// it; centred for the others).
  virtual model::InitialState initial_state() const { return model::InitialState::kCentred; }
  /// The truth of `diagnose-check --records-family` (synth/synthetic.cc): a typical set on the
  /// synthetic stack's scale (synth::SyntheticStackScale), or the weights of a linear family;
  /// each value is scaled by a factor drawn in [0.8, 1.25] per trial. Empty: the family has none.
  virtual std::vector<double> CheckNominal() const { return {}; }
};

/// A family's step in the C kernels (records/stepper.h): the block's sizes beyond its parameters,
/// and the constants of a family whose block does not take its solved weights.
struct KernelShape {
  int n = 0;                 ///< pzk_block::n (plays, levels, sub-steps, modes)
  int m = 0;                 ///< pzk_block::m (the asymmetric PI's dead-zone knots)
  std::vector<double> data;  ///< the block's w in place of the weights (the fin's modal data)
};
inline KernelShape KernelSizes(int n, int m = 0) {
  KernelShape s;
  s.n = n;
  s.m = m;
  return s;
}

/// A plant family as registered (records/registry.h Families()): what is known of it before any
/// data. Each family's source defines its own (`const FamilyDef kXFamily`, C++20 designated
/// initialisers) beside its class and declares it in its header, and one line of Families()
/// registers it; the CLI's family list and the `--family auto` grid, the initial-state support,
/// the stepper's and the export's kernel id and a fit.json's family name are read from there.
struct FamilyDef {
  const char* name;
  bool takes_initial_state;  ///< FamilyOptions::initial_state sets its memory at rest
  bool linear;               ///< weights solved by non-negative least squares (Family::linear)
  bool auto_grid;            ///< tried by `--family auto` unless the families are named
  int kernel;                ///< its step's id in the C kernels (PZK_*, model/kernels/common.h)
  std::unique_ptr<Family> (*make)(const DataScale&, const FamilyOptions&);
  /// The kernel block's sizes for a model's options and fitted parameters; throws InputError
  /// naming the fit.json field for parameters the step cannot take.
  KernelShape (*kernel_shape)(const FamilyOptions&, std::span<const double> params);
};

/// The registrations of the families defined in records/families.cc (records/registry.h lists
/// them with the others).
extern const FamilyDef kStackBoucWenFamily, kBacklashLikeFamily, kDuhemFamily,
    kPrandtlIshlinskiiFamily, kBwOscillatorFamily, kBimorphFinFamily;

}  // namespace pz::records
