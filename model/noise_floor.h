// The noise floor of a bench record, estimated from the data alone (issue 6): the part of the
// residual no model can remove.
//
//   quantisation:  the encoder's quantum q [deg] is the grid the readings lie on (every reading an
//                  integer multiple of q); a moving signal read through it carries an error of
//                  RMS q/√12.
//   scatter:       the difference between the last two steady cycles, d_k = y_{k+(C−1)P} − y_{k+(C−2)P}
//                  (P samples per cycle), differenced once more so that slow non-periodic parts (creep,
//                  drift) drop out: s² = mean((d_k − d_{k−1})²)/4 is the sample-to-sample noise that is
//                  not repeated from cycle to cycle (vibration jitter).
//   floor:         σ = √(q²/12 + s²) [deg], per case and pooled over cases (root mean square over
//                  the samples). On a quantised record the scatter holds the jitter and some of the
//                  rounding flips it causes, so the sum errs on the high side: conservative, it makes
//                  a gap harder to call significant (an exact model of the bundled nominal bench
//                  lands at 0.9 × this floor; with √max(q²/12, s²) instead it would land at 1.1 ×).
//
// A model whose residual RMS is at σ explains the record down to the noise. Pure: no I/O.
#pragma once

#include <span>
#include <vector>

#include "model/status.h"

namespace pz::model {

/// The quantum of a quantised series: the largest q such that every value is an integer multiple
/// of q (to 1e-6 q), found from the smallest step between distinct values and its integer divisors
/// (1 … 16). A recorder that prints a few decimals rounds its grid (0.0076294 µm steps written as
/// -1.6174316): when no exact grid fits, q is refined by least squares over the values taken in
/// order of magnitude and accepted when every value is within 1e-3 q of a multiple of it. 0 when
/// the series is not on a grid (continuous data) or has fewer than 2 distinct values.
double EstimateQuantum(std::span<const double> y);

/// The scatter term of two consecutive periods of `period` samples starting at sample a:
/// Σ_{k=1}^{P−1} (d_k − d_{k−1})² with d_k = y_{a+P+k} − y_{a+k}. The difference of the periods
/// holds the noise twice and whatever is not periodic; differencing once more removes the slow part,
/// so each term has expectation 4 s² (s the sample-to-sample noise not repeated from period to
/// period). Used by the bench cases (EstimateCaseNoise: the last two cycles) and by records with a
/// periodic drive (records/diagnose.h). Throws InputError unless period ≥ 2 and a + 2P ≤ y.size().
double PeriodDifferenceSquares(std::span<const double> y, size_t a, size_t period);

/// Noise estimate of one record.
struct CaseNoise {
  double quantum_deg = 0;         ///< q [deg] (0: not quantised)
  double quantisation_rms_deg = 0;  ///< q/√12 [deg]
  double scatter_rms_deg = 0;     ///< s [deg], from the last two cycles (0 with fewer than 2 cycles)
  int compared_samples = 0;       ///< P, samples per cycle compared
  double floor_rms_deg = 0;       ///< σ = √(q²/12 + s²) [deg]
};

/// Estimates the noise of a record of `cycles` whole drive cycles (y.size() divisible by cycles is
/// not required: P = floor(N / cycles)). `quantum_deg` < 0 estimates q from y; ≥ 0 uses it.
/// Throws InputError on an empty series, non-finite values or cycles < 1.
CaseNoise EstimateCaseNoise(std::span<const double> y, int cycles, double quantum_deg = -1);

/// The floor of a record for a model that clips at the saturations b1, b2 taken from the measured
/// extremes: where the model output sits on b1 or b2 it is a constant that the reading's rounding
/// and jitter scatter around (a plateau reads one quantum inside the extreme now and then, or for a
/// whole cycle), so the residual there, (y_k − ŷ_k)², is irreducible as long as it is at most one
/// quantum (a larger deviation is model error, counted like any other sample); elsewhere the noise
/// is σ_c² = floor_rms²:
///   σ = √([Σ_{k ∈ plateau} (y_k − ŷ_k)² + N_other σ_c²] / N)   [deg].
/// Throws InputError on mismatched lengths.
double SaturationAwareFloor(const CaseNoise& noise, std::span<const double> measured, std::span<const double> model,
                            double b1, double b2);

/// Pooled floor over several records: √(Σ_c N_c σ_c² / Σ_c N_c) [deg].
double PooledFloor(std::span<const CaseNoise> noise, std::span<const int> samples);

}  // namespace pz::model
