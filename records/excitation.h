// The excitation and identifiability report (issue 22, item 3): before a fit, what the training
// records excite, and for each withheld record what it needs beyond that; a withheld gap on a
// record that needs what training lacks is an excitation gap (the model extrapolates), not
// necessarily missing physics. And a training drive that covers it.
//
// What a record excites, over its scored window:
//  - the drive range;
//  - its reversals: turning points of the drive (a retreat of more than `turn_threshold` of the
//    training range from the running extreme), counted by the rainflow rule (four-point: an inner
//    range no larger than its neighbours is a closed minor loop; the rest are half cycles). Each
//    cycle is a point (upper turn, lower turn) of the Preisach plane, binned on a `bins` × `bins`
//    grid of the training range; its depth is (upper − lower) / training range;
//  - its rates: the 95th percentile and the maximum of |du/dt|, and the rate span: the peak |du/dt|
//    of each complete half cycle (between turning points), its 10th and 90th percentiles over the
//    records' time together (each half cycle weighted by its duration) — one sine at one amplitude
//    and frequency has a span of 1, sines at 0.5, 2 and 8 Hz one of 16; rate dependence (the effect
//    `rate-dependence`) needs a span of kMinRateSpan at least, else it cannot be told from the
//    loop's shape (RateCoverageError);
//  - its duration and longest hold (the drive within `hold_level` of the range) against the creep
//    times: a relaxation slower than the longest hold shows only as a drift.
// A withheld record needs:
//  - range: drive beyond the training range by more than `range_margin` of it;
//  - reversals: at least `uncovered_share` of its cycles (and one full cycle) in cells of the plane
//    where training has no cycle, nor in the next cells (its minor loops are extrapolated);
//  - rate: a 95th percentile of |du/dt| more than `rate_faster` × the fastest training record's,
//    or less than 1 / `rate_slower` of the slowest one's;
//  - hold: a hold longer than `min_hold_s` and than twice the training's longest.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "io/records.h"
#include "model/effect_library.h"

namespace pz::records {

struct ExcitationOptions {
  double turn_threshold = 0.02;
  int bins = 10;
  double range_margin = 0.02;
  double uncovered_share = 0.1;
  double rate_faster = 1.5, rate_slower = 3;
  double hold_level = 0.005;
  double min_hold_s = 1.0;
  std::string Validate() const;  ///< "" or the field and value that are wrong
};

/// A rainflow cycle: its upper and lower turns; weight 1 (a closed loop) or 0.5 (a half cycle).
struct ReversalCycle {
  double upper = 0, lower = 0, weight = 1;
};

struct DriveExcitation {
  std::string name;  ///< a record's name, or "training" for the training records together
  size_t records = 0;
  double u_min = 0, u_max = 0;
  double duration_s = 0;
  double rate_p95 = 0, rate_max = 0;        ///< |du/dt| [drive unit / s], over the records together
  double rate_p95_lo = 0, rate_p95_hi = 0;  ///< the slowest and fastest record's 95th percentile
  double longest_hold_s = 0;
  size_t half_cycles = 0;  ///< complete half cycles (between two turns)
  double rate_peak_lo = 0,
         rate_peak_hi = 0;  ///< 10th / 90th percentile of their peak |du/dt| over time
  double rate_span() const { return rate_peak_lo > 0 ? rate_peak_hi / rate_peak_lo : 1; }
  size_t turns = 0;
  std::vector<ReversalCycle> cycles;
  std::vector<double>
      depth_weight;  ///< rainflow weight per depth bin (share of the training range)
  std::vector<double> level_weight;  ///< turning points per level bin of the training range
};

struct ExcitationNeed {
  enum class Kind { kRange, kReversals, kRate, kHold };
  Kind kind = Kind::kReversals;
  double amount =
      0;  ///< range: share beyond; reversals: uncovered share; rate: ratio; hold: seconds
  std::string text;
};
const char* ExcitationNeedName(ExcitationNeed::Kind k);  ///< "range", "reversals", "rate", "hold"

struct WithheldExcitation {
  size_t record = 0;  ///< index into the set
  DriveExcitation drive;
  double uncovered_share = 0;  ///< rainflow weight outside the training's cells / total
  std::vector<ExcitationNeed> needs;
};

struct ExcitationReport {
  std::string drive_unit;
  DriveExcitation training;
  std::vector<std::string> training_lines;   ///< what the training records excite, one line each
  std::vector<WithheldExcitation> withheld;  ///< set order
  bool HasGap() const;
};

/// Throws InputError when the set has no training record, a training record has no excitation
/// (constant drive), or on bad options.
ExcitationReport AnalyseExcitation(const io::RecordSet& set, const ExcitationOptions& options = {});

/// The least rate span (DriveExcitation::rate_span) of the training records for an effect whose
/// magnitude depends on the drive rate.
constexpr double kMinRateSpan = 2;
/// True for an effect that only rates spread over the training records identify (rate-dependence).
bool NeedsRateCoverage(model::EffectKind effect);
/// Empty when the training records of `set` cover the rates the effects need; else the refusal:
/// which effect, the rate span the training has and what to record. A fit (records::FitModel)
/// throws it; the diagnosis leaves such a candidate out by default.
std::string RateCoverageError(const io::RecordSet& set, std::span<const model::EffectKind> effects,
                              const ExcitationOptions& options = {});

/// The excitation-gap sentence of a diagnosis. `rms_ratio[i]`: record i's withheld RMS error of the
/// base model / the noise floor (set order; training entries ignored). Empty when no withheld
/// record needs what training lacks, or when no withheld record's gap is significant.
std::string ExcitationGapNote(const io::RecordSet& set, const ExcitationReport& report,
                              const std::vector<double>& rms_ratio, double significance_ratio);

/// A training drive that covers what the withheld records need: a rest, a decaying-amplitude sine
/// (nested minor loops around the middle), a random reversal sequence over the whole range (the
/// Preisach plane), and a staircase of holds (creep over seconds); over the range of every record,
/// at the faster of the training's and the withheld records' rates, sampled at the training rate.
struct TrainingDriveProposal {
  double fs_hz = 0;          ///< the records' rate, or lower when that would take over 4e6 samples
  double records_fs_hz = 0;  ///< the training records' sample rate
  std::vector<double> u;     ///< from t = 0
  double rest_s = 0;         ///< the leading rest
  std::vector<std::string> segments;  ///< what each part is for
  std::string description;
};
TrainingDriveProposal ProposeTrainingDrive(const io::RecordSet& set, const ExcitationReport& report,
                                           uint64_t seed = 1);

}  // namespace pz::records
