// Error metrics between a measured series y and a model series ŷ on the same samples, with the
// error e_k = y_k − ŷ_k:
//
//   PI   = Σ_k e_k²                         (the paper's performance index, eq. 6) [unit²]
//   MSE  = PI / N,  RMSE = √MSE             [unit², unit]
//   max |e_k|                                [unit]
//   IAE  = ∫_{t0}^{t1} |e(t)| dt             (trapezoidal on |e_k|) [unit · s]
//   R²   = 1 − Σ e_k² / Σ (y_k − ȳ)²         (of the measured series) [-]
//
// Every function checks its inputs and throws pz::InputError with a message naming what is wrong:
// the two lengths when they differ, the first sample whose times differ beyond the tolerance, the
// first non-finite value. Pure: no I/O.
#pragma once

#include <cstddef>
#include <span>

#include "model/status.h"

namespace pz::model {

/// All the point metrics of one comparison. Units are those of the series (deg for fin angles).
struct ErrorMetrics {
  size_t n = 0;              ///< number of samples
  double pi = 0;             ///< Σ e² [unit²]
  double mse = 0;            ///< Σ e² / n [unit²]
  double rmse = 0;           ///< √mse [unit]
  double max_abs = 0;        ///< max |e| [unit]
  size_t max_abs_index = 0;  ///< sample index of max |e|
  double r2 = 0;             ///< 1 − Σe²/Σ(y−ȳ)²; NaN when the measured series is constant
};

/// OK iff measured and model have the same, non-zero length and only finite values. The message
/// names the lengths ("measured has 1200 samples, model has 600") or the first non-finite sample.
Status CheckAligned(std::span<const double> measured, std::span<const double> model);

/// OK iff t_a and t_b have the same length and |t_a[k] − t_b[k]| ≤ tolerance_s for every k, all
/// finite. The message names the first differing sample and both times.
Status CheckSameGrid(std::span<const double> t_a, std::span<const double> t_b, double tolerance_s);

/// The paper's performance index Σ (y_k − ŷ_k)² [unit²]. Throws InputError (see CheckAligned).
double PerformanceIndex(std::span<const double> measured, std::span<const double> model);
/// Σ e² / N [unit²]. Throws InputError.
double MeanSquaredError(std::span<const double> measured, std::span<const double> model);
/// √MSE [unit]. Throws InputError.
double RootMeanSquaredError(std::span<const double> measured, std::span<const double> model);
/// max_k |e_k| [unit]. Throws InputError.
double MaxAbsError(std::span<const double> measured, std::span<const double> model);
/// Coefficient of determination of the model for the measured series. Throws InputError, also when
/// the measured series is constant (R² undefined).
double RSquared(std::span<const double> measured, std::span<const double> model);

/// All point metrics at once; r2 is NaN (not an error) when the measured series is constant.
/// Throws InputError (see CheckAligned).
ErrorMetrics CompareSeries(std::span<const double> measured, std::span<const double> model);

/// Same as CompareSeries after checking that the two series live on the same time grid
/// (|t_measured[k] − t_model[k]| ≤ tolerance_s). Throws InputError naming the first differing time.
ErrorMetrics CompareTraces(std::span<const double> t_measured, std::span<const double> measured,
                           std::span<const double> t_model, std::span<const double> model,
                           double tolerance_s);

/// Integral of absolute error over the window [t0, t1] [unit · s]: the trapezoidal rule on |e_k|
/// over the samples inside the window; where the window cuts a sample interval, e is interpolated
/// linearly to the cut. t must be strictly increasing; the window must satisfy t.front() ≤ t0 ≤ t1
/// ≤ t.back(). Throws InputError otherwise (or on length mismatch / non-finite values).
double IntegratedAbsError(std::span<const double> t, std::span<const double> measured,
                          std::span<const double> model, double t0, double t1);

}  // namespace pz::model
