// Identification criteria on uniformly sampled series (issue 7, seed 002): sample k of y and ŷ is
// at t_k = k·dt, the error is e_k = y_k − ŷ_k.
//
//   IAE  = ∫_{t0}^{t1} |e(t)| dt       trapezoidal rule on |e_k|; where the window cuts a sample
//                                       interval, e is interpolated linearly to the cut (as
//                                       model/metrics.h's IntegratedAbsError) [unit·s]
//   SSE  = Σ e_k²                       over the samples with t0 ≤ t_k ≤ t1 [unit²]
//   RMSE = √(SSE / count)               same samples [unit]
//   max  = max |e_k|                    same samples [unit]
//
// The unwindowed forms use every sample. These are the hot path of complete-model fitness
// functions: no allocation, one pass. Every function checks its inputs and throws pz::InputError
// naming what is wrong: the two lengths, the first non-finite sample, dt, or the window against the
// record's span [0, (n − 1)·dt]. Windowed SSE/RMSE/max need at least one sample inside the window.
#pragma once

#include <span>

#include "model/status.h"

namespace pz::model {

double Iae(std::span<const double> y, std::span<const double> yhat, double dt, double t0,
           double t1);
double Iae(std::span<const double> y, std::span<const double> yhat, double dt);

double Sse(std::span<const double> y, std::span<const double> yhat, double dt, double t0,
           double t1);
double Sse(std::span<const double> y, std::span<const double> yhat);

double Rmse(std::span<const double> y, std::span<const double> yhat, double dt, double t0,
            double t1);
double Rmse(std::span<const double> y, std::span<const double> yhat);

double MaxAbsError(std::span<const double> y, std::span<const double> yhat, double dt, double t0,
                   double t1);
// The unwindowed max error is model/metrics.h's MaxAbsError(measured, model).

}  // namespace pz::model
