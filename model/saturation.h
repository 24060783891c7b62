// Saturations b1, b2 of the backlash operator (paper Appendix B, spec section 3). They are not
// identified by the GA: per case they are read off the measured fin angle y_k [deg],
//
//   b1 = max_k y_k,    b2 = min_k y_k          (over every sample of the case, as recorded)
//
// and across cases they are regressed on the drive amplitude V [V] and frequency f [Hz] by
// ordinary least squares,
//
//   b = c_V V + c_f f + c_0 + ε,
//
// reporting each coefficient's standard error, t statistic (n − 3 degrees of freedom) and two-sided
// p-value, and R². The paper's printed fit (Table B2) is
//   b1 = 0.00645 V − 0.84771 f − 0.63061 (R² 0.985),   b2 = −0.00622 V + 0.68371 f + 0.71011 (R²
//   0.981).
//
// Note on "measured extremes": when a case never reaches its saturation (the plant's peak angle
// stays below b1), the extreme is the peak of the response, not the plateau; encoder quantisation
// also rounds it to the encoder's quantum. That is what the paper's procedure yields, and it is
// what SaturationFromExtremes returns. Pure: no I/O.
#pragma once

#include <cstddef>
#include <span>

#include "model/status.h"

namespace pz::model {

/// A pair of saturations [deg].
struct SaturationPair {
  double b1 = 1.0;   ///< upper saturation [deg], > 0
  double b2 = -1.0;  ///< lower saturation [deg], < 0
};

/// b1 = max, b2 = min of the measured angle [deg]. Throws InputError if the series is empty, holds
/// a non-finite value, or never rises above 0 (b1 ≤ 0) / never falls below 0 (b2 ≥ 0).
SaturationPair SaturationFromExtremes(std::span<const double> measured_angle_deg);

/// One regressor's estimate.
struct RegressionTerm {
  double coef = 0;       ///< estimate
  double std_error = 0;  ///< standard error of the estimate
  double t_stat = 0;     ///< coef / std_error (±inf for a perfect fit)
  double p_value = 0;    ///< two-sided, Student t with dof degrees of freedom
};

/// b = v.coef · V + f.coef · f + intercept.coef, fitted by OLS.
struct PlaneFit {
  RegressionTerm v;          ///< coefficient of amplitude [deg / V]
  RegressionTerm f;          ///< coefficient of frequency [deg / Hz]
  RegressionTerm intercept;  ///< [deg]
  double r2 = 0;             ///< coefficient of determination
  double adjusted_r2 = 0;    ///< 1 − (1 − R²)(n − 1)/(n − 3)
  double residual_se = 0;    ///< √(SSE / dof) [deg]
  int n = 0;                 ///< observations
  int dof = 0;               ///< n − 3
  double Predict(double amplitude_v, double frequency_hz) const {
    return v.coef * amplitude_v + f.coef * frequency_hz + intercept.coef;
  }
};

/// OLS of y on (V, f, 1). Throws InputError for mismatched lengths, non-finite values, fewer than 4
/// observations (no degree of freedom left) or collinear regressors (e.g. a single amplitude).
PlaneFit FitPlane(std::span<const double> amplitude_v, std::span<const double> frequency_hz,
                  std::span<const double> y);

/// One case's saturations and operating point.
struct SaturationSample {
  double amplitude_v = 0;   ///< V [V]
  double frequency_hz = 0;  ///< f [Hz]
  double b1 = 0;            ///< [deg]
  double b2 = 0;            ///< [deg]
};

struct SaturationRegression {
  PlaneFit b1;
  PlaneFit b2;
  SaturationPair Predict(double amplitude_v, double frequency_hz) const {
    return {b1.Predict(amplitude_v, frequency_hz), b2.Predict(amplitude_v, frequency_hz)};
  }
};

/// Regresses b1 and b2 of the samples on V and f (see FitPlane for the errors).
SaturationRegression FitSaturationRegression(std::span<const SaturationSample> samples);

/// The paper's printed regression (eqs. B1, B2): coefficients and R² as printed; the other
/// statistics are NaN (n and dof 9 and 6).
SaturationRegression PaperSaturationRegression();

}  // namespace pz::model
