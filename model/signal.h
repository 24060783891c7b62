// Drive signals u(t) [V] for the plants: the spec's sinusoid and arbitrary sampled input.
#pragma once

#include <cmath>
#include <numbers>
#include <string>
#include <variant>
#include <vector>

#include "model/status.h"

namespace pz::model {

/// u(t) = V sin(2π f t) sampled at fs: t_k = k / fs, k = 0 … N−1, N = round(cycles · fs / f).
struct Sinusoid {
  double amplitude_v = 375.0;     ///< V [V], finite, ≥ 0
  double frequency_hz = 0.25;     ///< f [Hz], finite, > 0
  double cycles = 3.0;            ///< number of cycles, > 0
  double sample_rate_hz = 100.0;  ///< fs [Hz], > 0
  Status Validate() const;
  int NumSamples() const {
    return static_cast<int>(std::lround(cycles * sample_rate_hz / frequency_hz));
  }
  double Value(double t) const {
    return amplitude_v * std::sin(2 * std::numbers::pi * frequency_hz * t);
  }
  double Derivative(double t) const {
    const double w = 2 * std::numbers::pi * frequency_hz;
    return amplitude_v * w * std::cos(w * t);
  }
};

/// Sampled input u_k at strictly increasing times t_k, linear in between (so u̇ is piecewise
/// constant). The outputs of a simulation live on the same t_k. t_0 is the start of the simulation
/// (zero state).
struct SampledSignal {
  std::vector<double> t;  ///< [s], strictly increasing, finite, ≥ 2 samples
  std::vector<double> u;  ///< [V], finite, same length as t
  Status Validate() const;
  double Value(double time) const;  ///< linear interpolation, clamped at the ends
  double Derivative(
      double time) const;  ///< slope of the segment containing time (right-continuous)
};

using DriveSignal = std::variant<Sinusoid, SampledSignal>;

Status Validate(const DriveSignal& s);
/// The output sample times of a signal.
std::vector<double> SampleTimes(const DriveSignal& s);
/// u at the sample times.
std::vector<double> SampleValues(const DriveSignal& s);
/// Human-readable one-liner, e.g. "sinusoid 375 V 0.25 Hz x3 @100 Hz".
std::string Describe(const DriveSignal& s);

}  // namespace pz::model
