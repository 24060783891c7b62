// Extrapolation guard of a fit (issue 22: "no silent 8 µm blow-ups"): for every record that is not
// a training record, how much of the model's prediction is carried by terms outside the range they
// had on the training records.
//
//   drive      the record's drive beyond the training drive range [u_min, u_max] (any family):
//              the largest excursion and the share of scored samples outside;
//   terms      linear families: each regressor x_j (play, relay cell, dead zone …) has a range
//              [lo_j, hi_j] over the training records' scored samples (effective drive at the
//              fitted parameters); the part of the prediction outside it is
//              e_k = polarity · Σ_j w_j (x_kj − clamp(x_kj, lo_j, hi_j)) — relays never switched in
//              training that carry weight, plays driven further than in training;
//   rates      a model with a rate-dependent effect (records/excitation.h NeedsRateCoverage): the
//              record's largest |du/dt| against the training records' largest, and the share of
//              its scored samples faster than that — the effect's lag there is extrapolated;
//
// flagged when the drive leaves the training range by more than 2 % of it, when |e| reaches
// 3 × the training RMSE somewhere, or (rates) when the record is more than 1.5 × faster than
// training.
#pragma once

#include <string>
#include <vector>

#include "io/records.h"
#include "records/fit.h"

namespace pz::records {

struct ExtrapolationCheck {
  std::string record;
  double drive_beyond = 0;  ///< largest excursion beyond the training drive range (drive units)
  double drive_beyond_share = 0;  ///< share of the scored samples outside it
  double term_max = 0;            ///< largest |e_k| (response units; linear families)
  double term_rms = 0;            ///< RMS of e_k over the scored samples
  size_t terms = 0;               ///< weighted terms that leave their training range
  double rate_ratio =
      0;  ///< largest |du/dt| / the training's largest (rate-dependent models; 0 else)
  double rate_beyond_share = 0;  ///< share of the scored samples faster than any in training
  bool flagged = false;
  /// One line: "ramp: flagged — the drive reaches 12 V beyond the training range (8 % of samples);
  /// …".
  std::string Describe(const std::string& drive_unit, const std::string& response_unit) const;
};

/// The check of every non-training record of the set, set order.
std::vector<ExtrapolationCheck> CheckExtrapolation(const io::RecordSet& set, const FitResult& fit);

/// Error against reversal depth: the scored window cut at the drive's reversals (turns by more
/// than 1 % of the training drive range), each monotone piece binned by its swing as a share of
/// that range (minor loops are the shallow pieces), the RMSE of each bin.
struct DepthBin {
  double lo = 0, hi = 0;  ///< swing / training drive range
  size_t pieces = 0, samples = 0;
  double rmse = 0;
};
/// Bins [0, 0.2), [0.2, 0.4) … [0.8, ∞) (empty bins included). yhat: the model output [0,
/// end_scored).
std::vector<DepthBin> ErrorByReversalDepth(const io::Record& r, std::span<const double> yhat,
                                           double training_range);
/// "swing 0–20 %: 0.05 (3 pieces); …" over the non-empty bins.
std::string DescribeDepthBins(const std::vector<DepthBin>& bins);

/// Slow error over time (creep the model lacks): the residual y − ŷ over the scored window
/// averaged over a centred window of `window_s` (one drive period removes the loop's periodic
/// error and leaves the drift), truncated at the window's ends. One value per scored sample,
/// [first_scored, end_scored). window_s ≤ one sample: the residual itself.
std::vector<double> ResidualTrend(const io::Record& r, std::span<const double> yhat,
                                  double window_s);

}  // namespace pz::records
