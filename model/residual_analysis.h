// Localisation of the sim-to-real gap (issue 6): the residual e_k = y_meas,k − y_model,k of every
// case of a bench set, cut along each axis where an unmodelled effect leaves a mark, each figure
// set against the noise floor σ (records/noise_floor.h, given per case):
//
//   grid:       per case PI = Σ e², RMS, max |e|, share of the total PI, RMS / σ (training vs
//   withheld); cycle:      by drive phase φ = 2π f t (twelve 30° bins; u = V sin φ), rising (u̇ >
//   0)
//   vs falling
//               branch, near the reversals (|φ − 90°| or |φ − 270°| < 20°), in saturation (measured
//               angle within q/2 of its extremes b1, b2);
//   time:       first cycle (transient) vs later cycles, the mean residual of each cycle, and the
//               least-squares slope of e over the later cycles (drift, creep);
//   frequency:  over the later cycles (a whole number of cycles, so k·f are DFT bins) the amplitude
//               |E_k| = |2/M Σ e_j exp(−i 2π k f t_j)| of the harmonics k = 1 … 9 (odd: symmetric
//               distortion, phase and gain errors; even: asymmetry), and the low-frequency content
//               = RMS of the one-cycle moving average of e (DC and trends). White noise of RMS σ
//               gives |E_k| ≈ 2σ/√M: the harmonic noise level;
//   loop:       measured vs model over the last cycle: width between the branches at u = 0, area
//               ∮ u dy, offset (max + min)/2, peak-to-peak, the phase where the rising branch
//               reaches its top level (saturation timing), and the phase lag of the fundamental
//               behind u.
//
// Pure: no I/O.
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include "model/status.h"

namespace pz::model {

/// One case to analyse (spans must outlive the call; all of the same length N ≥ 4).
struct ResidualCaseInput {
  int number = 0;
  double amplitude_v = 0;     ///< V [V], > 0
  double frequency_hz = 0;    ///< f [Hz], > 0
  double sample_rate_hz = 0;  ///< fs [Hz], > 0
  int cycles = 3;             ///< whole drive cycles in the record, ≥ 1
  bool training = false;
  std::span<const double> measured;  ///< y_meas [deg]
  std::span<const double> model;     ///< y_model [deg]
  double floor_rms_deg = 0;          ///< σ of this case [deg], ≥ 0
  double quantum_deg = 0;            ///< encoder quantum [deg], ≥ 0
};

/// RMS and mean of the residual over a subset of samples.
struct BinStat {
  double rms = 0;   ///< [deg]
  double mean = 0;  ///< [deg]
  int n = 0;        ///< samples
  void Add(double e) {
    rms += e * e;  // accumulates Σe² until Finish()
    mean += e;
    ++n;
  }
  void Finish();
};

/// Loop descriptors of one series over the last cycle.
struct LoopFeatures {
  double width_deg = 0;   ///< y on the falling branch − y on the rising branch at u = 0 [deg]
  double area_deg_v = 0;  ///< ∮ u dy [deg V] (positive: y lags u)
  double offset_deg = 0;  ///< (max + min)/2 [deg]
  double peak_to_peak_deg = 0;  ///< max − min [deg]
  double top_phase_deg = 0;     ///< drive phase where y first reaches max − q/2 [deg]
  double phase_lag_deg = 0;  ///< phase of the fundamental of u minus that of y [deg], later cycles
  double fundamental_deg = 0;  ///< amplitude of the fundamental of y [deg], later cycles
};

inline constexpr int kPhaseBins = 12;
inline constexpr int kHarmonics = 9;  ///< harmonics k = 1 … 9 are analysed

struct CaseResidual {
  int number = 0;
  bool training = false;
  double amplitude_v = 0, frequency_hz = 0;
  int samples = 0;
  double pi = 0;                          ///< Σ e² [deg²]
  double rms = 0;                         ///< [deg]
  double max_abs = 0;                     ///< [deg]
  double share = 0;                       ///< PI / Σ_cases PI
  double floor_rms = 0;                   ///< σ [deg]
  double rms_over_floor = 0;              ///< RMS / σ
  std::array<BinStat, kPhaseBins> phase;  ///< bin b: φ in [30 b, 30 b + 30) deg, later cycles
  BinStat rising, falling, near_reversal, in_saturation, first_cycle, later_cycles;
  std::vector<double> cycle_mean;  ///< mean residual of each cycle [deg]
  double trend_deg_per_s = 0;      ///< LS slope of e over the later cycles [deg/s]
  double trend_se = 0;             ///< its standard error under white noise σ [deg/s]
  std::array<double, kHarmonics + 1> harmonic{};  ///< |E_k| [deg], k = 0 (|mean|) … 9
  double harmonic_noise = 0;  ///< 2σ/√M: the amplitude white noise puts in one bin [deg]
  double odd_rms = 0;         ///< √(Σ_{k odd} |E_k|²/2) [deg]
  double even_rms = 0;        ///< √(Σ_{k even ≥ 2} |E_k|²/2) [deg]
  double low_rms = 0;         ///< RMS of the one-cycle moving average of e [deg]
  LoopFeatures measured_loop, model_loop;
};

/// Aggregates over a group of cases (training or withheld).
struct GroupResidual {
  int cases = 0;
  int samples = 0;
  double pi = 0;         ///< Σ e² [deg²]
  double rms = 0;        ///< [deg]
  double floor_rms = 0;  ///< pooled σ [deg]
  double worst_rms = 0;  ///< largest case RMS [deg]
  int worst_case = 0;
  std::array<BinStat, kPhaseBins> phase;
  BinStat rising, falling, near_reversal, in_saturation, first_cycle, later_cycles;
  double odd_rms = 0, even_rms = 0, low_rms = 0;  ///< RMS over the group's cases [deg]
  double harmonic_noise = 0;                      ///< RMS over the group's cases [deg]
};

struct ResidualAnalysis {
  std::vector<CaseResidual> cases;  ///< input order
  GroupResidual training, withheld;
  /// Plain sentences: where the gap lies, each against the floor (most telling first).
  std::vector<std::string> findings;
};

/// Analyses every case. Throws InputError (naming the case and the field) on mismatched lengths,
/// non-finite values or invalid rates.
ResidualAnalysis AnalyseResiduals(std::span<const ResidualCaseInput> cases);

/// The loop descriptors of a series y under u = V sin(2π f t_k), t_k = k/fs (exposed for tests).
LoopFeatures ComputeLoop(std::span<const double> y, double amplitude_v, double frequency_hz,
                         double sample_rate_hz, int cycles, double quantum_deg);

}  // namespace pz::model
