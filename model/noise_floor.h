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
//                  the samples).
//
// A model whose residual RMS is at σ explains the record down to the noise. Pure: no I/O.
#pragma once

#include <span>
#include <vector>

#include "model/status.h"

namespace pz::model {

/// The quantum of a quantised series: the largest q such that every value is an integer multiple
/// of q (to 1e-6 q), found from the smallest step between distinct values and its integer divisors
/// (1 … 16). 0 when the series is not on a grid (continuous data) or has fewer than 2 distinct values.
double EstimateQuantum(std::span<const double> y);

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
/// extremes (b1 = max y, b2 = min y): on a saturation plateau the model output is that constant,
/// and the reading's rounding and jitter scatter around it (the plateau reads one quantum inside the
/// extreme now and then), so the residual there, (y_k − b)², is irreducible. A plateau is found
/// from the data alone: a run of ≥ 3 consecutive readings within one quantum of an extreme that
/// holds the extreme itself at least once. Elsewhere the noise is q²/12 + s²:
///   σ = √([Σ_{k ∈ plateaus} (y_k − b)² + N_other (q²/12 + s²)] / N)   [deg].
/// Without a quantum (continuous data) this is the plain floor. Throws InputError on an empty series.
double PlateauAwareFloor(const CaseNoise& noise, std::span<const double> measured);

/// Pooled floor over several records: √(Σ_c N_c σ_c² / Σ_c N_c) [deg].
double PooledFloor(std::span<const CaseNoise> noise, std::span<const int> samples);

}  // namespace pz::model
