// The noise floor: the part of a residual no model can remove, estimated from the data alone. One
// module for both diagnoses: the nine-case fin bench (diagnose/, per case) and record sets of any
// drive (diagnose/diagnose.h). The quantum of a series (the grid its readings lie on) is measured
// by the record reader (io/quantum.h: io/records.cc, the lowest user, cannot include records/);
// every estimator of the floor is here.
//
// A bench case of C whole cycles (issue 6):
//   quantisation:  the encoder's quantum q [deg] is the grid the readings lie on (every reading an
//                  integer multiple of q); a moving signal read through it carries an error of
//                  RMS q/√12.
//   scatter:       the difference between the last two steady cycles, d_k = y_{k+(C−1)P} −
//   y_{k+(C−2)P}
//                  (P samples per cycle), differenced once more so that slow non-periodic parts
//                  (creep, drift) drop out: s² = mean((d_k − d_{k−1})²)/4 is the sample-to-sample
//                  noise that is not repeated from cycle to cycle (vibration jitter).
//   floor:         σ = √(q²/12 + s²) [deg], per case. On a quantised record the scatter holds the
//                  jitter and some of the rounding flips it causes, so the sum errs on the high
//                  side: conservative, it makes a gap harder to call significant (an exact model of
//                  the bundled nominal bench lands at 0.9 × this floor; with √max(q²/12, s²)
//                  instead it would land at 1.1 ×).
//   saturations:   where a model clips at the measured extremes, the plateau's rounding is the
//   floor
//                  there (SaturationAwareFloor).
//
// A record set (issues 14, 45), from what the records allow, in this order of preference (every
// available estimate is reported, and which one was used):
//   repeats        records of the same drive (a manifest's repeat group, io/records.h; else records
//                  of different files whose drives are equal sample for sample): each aligned on
//                  the group's first drive (a lag of ≤ 50 samples), its mean removed, σ² the
//                  scatter about the group's mean, Σ (y_ik − ȳ_k)² / ((m − 1) N). What a
//                  deterministic model is judged against: the plant repeats itself no closer.
//   rest           the settled part of every hold of the drive (the leading rest and any hold of
//                  ≥ 50 samples inside a record): a step to a hold rings (a mechanical mode) and
//                  settles first, so the hold is cut in blocks, each block's scatter about its own
//                  line measured, and the settled part is the run of blocks at the end within twice
//                  the median block of the hold's second half (FindSettledHold); those blocks'
//                  scatter, pooled, is the estimate (the hold's slow creep, which a model with
//                  creep follows, stays out; so does noise slower than a block, a twentieth of it);
//   periods        the drive repeats with a period P: the scatter of every pair of consecutive
//                  periods after the first (PeriodDifferenceSquares);
//   residual       the high-frequency part of the base model's residual: mean((e_k − e_{k−1})²)/2
//                  (an upper bound when the model error is smooth).
// None goes below the quantisation floor q/√12 (a rest or identical periods cancel the rounding; a
// continuous model cannot): the estimate says when it was raised to it. Estimates more than
// kFloorDisagreement apart are reported (NoiseFloor::warning): a sensor's noise at rest far below
// the records' repeatability, or a hold that never settles.
//
// A model whose residual RMS is at σ explains the record down to the noise. Pure: no I/O.
#pragma once

#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "io/records.h"

namespace pz::records {

/// The RMS error of reading a moving signal through a grid of quantum q: q/√12.
double QuantisationRms(double quantum);

/// The scatter term of two consecutive periods of `period` samples starting at sample a:
/// Σ_{k=1}^{P−1} (d_k − d_{k−1})² with d_k = y_{a+P+k} − y_{a+k}. The difference of the periods
/// holds the noise twice and whatever is not periodic; differencing once more removes the slow
/// part, so each term has expectation 4 s² (s the sample-to-sample noise not repeated from period
/// to period). Used by the bench cases (EstimateCaseNoise: the last two cycles) and by records with
/// a periodic drive (EstimateNoiseFloor). Throws InputError unless period ≥ 2 and a + 2P ≤
/// y.size().
double PeriodDifferenceSquares(std::span<const double> y, size_t a, size_t period);

// ---- a bench case -------------------------------------------------------------------------------

/// Noise estimate of one bench case.
struct CaseNoise {
  double quantum_deg = 0;           ///< q [deg] (0: not quantised)
  double quantisation_rms_deg = 0;  ///< q/√12 [deg]
  double scatter_rms_deg = 0;  ///< s [deg], from the last two cycles (0 with fewer than 2 cycles)
  int compared_samples = 0;    ///< P, samples per cycle compared
  double floor_rms_deg = 0;    ///< σ = √(q²/12 + s²) [deg]
};

/// Estimates the noise of a record of `cycles` whole drive cycles (y.size() divisible by cycles is
/// not required: P = floor(N / cycles)). `quantum_deg` < 0 estimates q from y (io/quantum.h); ≥ 0
/// uses it. Throws InputError on an empty series, non-finite values or cycles < 1.
CaseNoise EstimateCaseNoise(std::span<const double> y, int cycles, double quantum_deg = -1);

/// The floor of a record for a model that clips at the saturations b1, b2 taken from the measured
/// extremes: where the model output sits on b1 or b2 it is a constant that the reading's rounding
/// and jitter scatter around (a plateau reads one quantum inside the extreme now and then, or for a
/// whole cycle), so the residual there, (y_k − ŷ_k)², is irreducible as long as it is at most one
/// quantum (a larger deviation is model error, counted like any other sample); elsewhere the noise
/// is σ_c² = floor_rms²:
///   σ = √([Σ_{k ∈ plateau} (y_k − ŷ_k)² + N_other σ_c²] / N)   [deg].
/// Throws InputError on mismatched lengths.
double SaturationAwareFloor(const CaseNoise& noise, std::span<const double> measured,
                            std::span<const double> model, double b1, double b2);

// ---- a record set -------------------------------------------------------------------------------

struct NoiseEstimate {
  std::string method;  ///< "rest", "periods", "repeats", "residual"
  double sigma = 0;
  size_t samples = 0;
  std::string detail;
};
struct NoiseFloor {
  double sigma = 0;
  std::string used;
  std::vector<NoiseEstimate> estimates;
  /// "" or why the estimates disagree by more than kFloorDisagreement × (largest / smallest).
  std::string warning;
  /// "0.021 um (repeats; rest 0.0012, periods 0.004 um)".
  std::string Summary(const std::string& unit) const;
};
/// Estimates further apart than this factor are reported as disagreeing.
constexpr double kFloorDisagreement = 3;
/// The settled part of a hold of the drive: samples [from, to) of the hold's response y, and its
/// scatter (the settled blocks', each about its line, pooled); `trailing_motion`: the drive moves
/// right after the hold (its last 4 samples are left out: the response lags). sigma 0 when fewer
/// than 50 samples settle.
struct SettledHold {
  size_t from = 0, to = 0;
  size_t unsettled_samples = 0;  ///< at its start: ringing or settling
  double sigma = 0;
};
SettledHold FindSettledHold(std::span<const double> y, bool trailing_motion);

/// Repeats, rest and periods from the records; `residuals` (the base model's, per record over its
/// scored window) adds the residual estimate. Throws InputError when no estimate is possible.
NoiseFloor EstimateNoiseFloor(const io::RecordSet& set,
                              const std::vector<std::vector<double>>* residuals = nullptr);

}  // namespace pz::records
