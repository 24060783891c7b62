// Series with known answers for the tests of the noise floor (records/noise_floor.h), the quantum
// (io/quantum.h) and the residual analysis (model/residual_analysis.h): sines sampled at 100 Hz and
// their reading through an encoder's grid.
#pragma once

#include <cmath>
#include <numbers>
#include <vector>

namespace pz::testing {

inline constexpr double kEncoderQuantum = 360.0 / 8192;  ///< the bench encoder's quantum [deg]

/// y_k = round(y_k / q) q.
inline std::vector<double> Quantise(const std::vector<double>& y, double q) {
  std::vector<double> r;
  for (double v : y) r.push_back(q * std::round(v / q));
  return r;
}

/// a sin(2π f k / 100 − phase), k = 0 … n−1 (100 Hz sampling).
inline std::vector<double> Sine(int n, double f, double a, double phase = 0) {
  std::vector<double> y;
  for (int k = 0; k < n; ++k)
    y.push_back(a * std::sin(2 * std::numbers::pi * f * k / 100.0 - phase));
  return y;
}

}  // namespace pz::testing
