// A fitted record model (records/model.h) one sample at a time, forward and inverse, for a
// controller (issue 23): the C99 step kernels of model/kernels/ — the one source of the
// per-sample arithmetic, also copied verbatim into the headers `piezoid export` writes
// (controller/export_header.h) — driven from C++.
//
//   forward  y = Step(u): the drive clipped to the drive limits (counted), the model's output with
//            polarity and offset; equal to RecordModel::Simulate on the same drive (to rounding:
//            the kernels do the same operations in the same order).
//   inverse  u = InverseStep(y_desired): the drive whose one-step output is y_desired, by bisection
//            on the one-step map (model/kernels/chain.h: exact for the monotone families); a
//            delay of n + s samples wants the reference n samples ahead and keeps s in the map
//            solved (s <= 1/2), or n + L and undoes s backwards over L samples (s > 1/2:
//            delay_horizon()); the bimorph fin and a rate-dependence lag over a quarter sample plan
//            two samples and want the reference one more sample ahead (inverse_plan_samples(),
//            preview_samples()).
// A Stepper is used either forward or inverse after Init, not both.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "model/kernels/pzk.h"
#include "records/families.h"
#include "records/model.h"

namespace pz::records {
namespace pzk = ::pz::pzk;  // the step kernels (model/kernels/pzk.h)

/// Everything that rebuilds a fitted model (fit.json's "model" section, reports/fit_file.h).
struct ModelSpec {
  std::string family;
  int substeps = 2;       ///< FamilyOptions::substeps
  int pi_operators = 12;  ///< FamilyOptions::pi_operators
  /// FamilyOptions::initial_state (centred for a fit.json without it: the convention before it).
  model::InitialState initial_state = model::InitialState::kCentred;
  DataScale scale;  ///< the data scale the family was made for (sets its ranges and grids)
  double dt = 0;    ///< sample step the model was identified at [s]
  std::vector<EffectKind> effects;
  std::vector<double> params;   ///< RecordModel::params() order
  std::vector<double> weights;  ///< a linear family's solved weights
  int polarity = 1;             ///< ŷ_total = polarity · ŷ + offset
  double offset = 0;
  double drive_min = 0, drive_max = 0;  ///< the drive limits (the training records' drive range)
  std::string drive_unit = "V", response_unit = "um";

  FamilyOptions family_options() const;
  /// The RecordModel of this spec (the family made for the scale). Throws InputError.
  std::shared_ptr<RecordModel> Model() const;
  /// Throws InputError naming the field: sizes against the family and effects, finite values,
  /// limits, polarity, dt.
  void Validate() const;
};

/// True for every family that has a step kernel (every one of FamilyNames()).
bool HasStepKernel(const std::string& family);

class Stepper {
 public:
  /// Builds the blocks (throws InputError: a family without a kernel, an invalid spec).
  explicit Stepper(const ModelSpec& spec);
  Stepper(const Stepper&) = delete;
  Stepper& operator=(const Stepper&) = delete;

  /// At rest under drive u0; returns the output there (polarity and offset applied). Resets the
  /// saturation counter; limits are the spec's.
  double Init(double u0);
  double Step(double u);
  double InverseStep(double y_desired);
  /// With a delay's horizon L (delay_horizon() > 0): the references of the L samples before the
  /// first InverseStep's, in order (y[k] for k = preview_samples() - L + 1 … preview_samples() when
  /// the first step gets y[1 + preview_samples()]), after Init and before that step; not given, the
  /// compensator takes those samples at rest. False when no more is wanted.
  bool InversePrime(double y_desired);
  /// InversePrime with the references of a whole record or reference y (the first InverseStep's at
  /// y[1 + preview_samples()]): y[k] for k = preview_samples() - L + 1 … preview_samples(), the
  /// last value held beyond y's end. Nothing without a horizon.
  void InversePrimeFrom(std::span<const double> y);
  /// The output the next step would give for drive u (not clipped), the state unchanged, the delay
  /// passing its input on: what a lasting change of the drive meets (ReplayDrive's local gain).
  double Trial(double u);

  const ModelSpec& spec() const { return spec_; }
  const pzk::pzk_ctl& ctl() const { return ctl_; }
  pzk::pzk_ctl& ctl() { return ctl_; }
  /// The blocks (pointers into this Stepper's copies of the parameters) and the state sizes.
  const std::vector<pzk::pzk_block>& blocks() const { return blocks_; }
  int constants() const { return nc_; }
  int dynamic() const { return nd_; }
  /// True when the chain holds a delay (the inverse reads the reference ahead: preview_samples()).
  bool has_delay() const;
  /// The fraction s of the delay's n + s samples (0 without a delay), and the horizon over which
  /// the inverse undoes it backwards (0: s <= 1/2, solved in the one-step map;
  /// model/kernels/effects.h).
  double delay_fraction() const;
  int delay_horizon() const;
  /// Samples the inverse plans ahead: 2 with the bimorph fin or a rate-dependence lag over a
  /// quarter sample (model/kernels/chain.h pzk_chain_inverse_fin: its InverseStep wants the
  /// reference one sample ahead), else 1.
  int inverse_plan_samples() const;
  /// Samples the inverse solves ahead of the drive it computes (a reference's preview, a replay's
  /// look-ahead; model/kernels/chain.h pzk_chain_preview): a delay of n + s samples (0 <= s < 1) n
  /// plus its horizon (0 for s <= 1/2: the response to the drive of sample k shows from n samples
  /// later; model/kernels/effects.h), plus inverse_plan_samples() - 1.
  size_t preview_samples() const;
  /// The rate-dependence play's inverse: below its knee the play is a lag of tau_r (z = v - tau_r
  /// v', v' the second-order backward difference), so the drive its one-step inverse solves carries
  /// a difference of the past drives forward by the roots rho of (1 - 1.5 a) rho^2 + 2 a rho -
  /// 0.5 a = 0, a = tau_r / dt. The largest |rho|: < 1 (a < 1/4) a stable inverse that gives a
  /// model's own drive back; > 1 a difference (noise, model error, rounding) would grow by that
  /// factor per sample, and for a > 2/3 the one-step map is not monotone (several drives give the
  /// output): the inverse then plans two samples instead (inverse_plan_samples), stable but not
  /// exact. 0 without the effect; infinity at a = 2/3.
  double rate_dependence_inverse_gain() const;
  /// Parameters of block i (the family's, an effect's, or {polarity, offset}).
  const std::vector<double>& block_params(size_t i) const { return params_[i]; }

 private:
  ModelSpec spec_;
  std::vector<std::vector<double>> params_;  ///< per block
  std::vector<pzk::pzk_block> blocks_;
  std::vector<double> family_data_;  ///< KernelShape::data (the fin's modal data), else empty
  std::vector<std::vector<double>>
      kernel_data_;  ///< per block: an effect's EffectDef::KernelData (else empty)
  std::vector<double> c_, d_, t_;
  pzk::pzk_ctl ctl_{};
  int nc_ = 0, nd_ = 0;
};

/// The model's output (polarity and the spec's offset applied) on the record's applied drive from
/// rest at its first sample, the drive limits widened to the record's drive (the applied drive is
/// the truth).
std::vector<double> SimulateRecord(const ModelSpec& spec, const io::Record& r);

/// A replay's drive error: the inverse's drive against the drive applied over the scored samples,
/// in drive units (rms_u) and through the one-step map's local gain at the applied drive (rms_y,
/// max_y: response units).
struct ReplayError {
  double rms_u = 0, rms_y = 0, max_y = 0;
  size_t n = 0;  ///< samples scored
  size_t clipped =
      0;  ///< scored samples whose drive the inverse clipped to a limit (the record's drive range)
  /// Scored samples where the model's local gain is not finite (its one-step map overflows there):
  /// left out of rms_y and max_y, which are over the others.
  size_t no_gain = 0;
};

/// The inverse run on the response y (in the model's frame: its polarity and offset) from rest at
/// the record's first drive, the limits widened to the record's drive, each drive solved for the
/// response preview_samples() later (a delay's horizon primed with the responses before the first
/// step: InversePrime); the record's scored samples whose response lies within the
/// record are compared. On the model's own noiseless response (SimulateRecord) it is the inverse's
/// exactness: ≈ 0 where the one-step map determines the drive (not within a play's band after a
/// reversal). Throws InputError when no sample can be scored.
ReplayError ReplayDrive(const ModelSpec& spec, const io::Record& r, std::span<const double> y);

}  // namespace pz::records
