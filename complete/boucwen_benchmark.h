// The protocol of the Bouc–Wen hysteretic benchmark (data/boucwen-benchmark/README.md, Noël and
// Schoukens): a mass–spring–damper with Bouc–Wen hysteresis driven by a force u [N], displacement
// y [m] sampled at 750 Hz; multisine records of 8192-sample periods. The identification uses the
// training records (train_A from rest; train_B, a steady-state response, after a one-period
// warm-up that is not counted); the test records are simulated only afterwards: the multisine as
// one steady-state period (three simulated from rest, the last compared, as the README's floor),
// the sine sweep from rest with a cubic-spline input. `piezoid boucwen` drives it and reports.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "complete/bw_fitness.h"
#include "model/bw_oscillator.h"

namespace pz::complete {

inline constexpr size_t kBwPeriod = 8192;          ///< samples per multisine period
inline constexpr double kBwSampleRateHz = 750;     ///< the benchmark's sample rate [Hz]

/// One record of the benchmark: force u [N] and displacement y [m].
struct BwSeries {
  std::vector<double> u, y;
};

/// Reads a benchmark CSV (columns u_N, y_m); InputError naming file, line, column.
BwSeries LoadBwSeries(const std::filesystem::path& file);

/// A training record of its first `samples` samples (a whole number of periods, else InputError
/// naming `name`). `steady_state`: the record is a steady-state response (train_B: its first
/// samples are far from a start at rest), so one period of the periodic input is simulated first
/// as a warm-up and not counted (the 1.1 % damped mode decays in about 0.4 s).
BwTrainingRecord MakeBwTrainingRecord(const std::string& name, const BwSeries& s, size_t samples, int substeps,
                                      bool steady_state);

/// The model's response on the official multisine test set: one steady-state period (three are
/// simulated from rest, the last returned), periodic Fourier input, 20 RK4 sub-steps.
std::vector<double> SimulateBwMultisineTest(const model::BwParams& p, const BwSeries& test);

/// The model's response on the sine sweep, from rest: cubic-spline input, 20 sub-steps.
std::vector<double> SimulateBwSweepTest(const model::BwParams& p, const BwSeries& test);

}  // namespace pz::complete
