// The protocol of the Bouc–Wen hysteretic benchmark (data/boucwen-benchmark/README.md, Noël and
// Schoukens) on the records engine: a mass–spring–damper with Bouc–Wen hysteresis driven by a
// force u [N], displacement y [m] sampled at 750 Hz; multisine records of 8192-sample periods.
//
// The data are a record set (LoadBwBenchmark), the model is the records engine's bw-oscillator
// family with the benchmark's OscillatorOptions (records/families.h: θ = (m, c, k, α, β·γ, β·δ),
// the input reconstructed between samples — periodic Fourier for the multisines, a cubic spline
// for the sweep —, from the zero state, RK4), and the cost is the records engine's RecordFitness
// (the output-error MSE over the scored samples, offset fixed at 0): the oscillator's simulation
// and fitness exist once. What is the benchmark's own is here: which records, the training cut
// (train_A from rest; train_B, a steady-state response, after a one-period warm-up that is not
// scored), the search box, and the test protocol (the multisine as one steady-state period, three
// simulated from rest and the last compared, as the README's floor; the sine sweep from rest with
// a cubic-spline input; both at 20 RK4 sub-steps). `piezoid boucwen` drives it and reports; the
// service's workers rebuild BwTraining from a complete_model spec (complete/job_kind.h).
#pragma once

#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "io/records.h"
#include "opt/evaluator.h"
#include "opt/param_search.h"
#include "records/fit.h"

namespace pz::complete {

inline constexpr size_t kBwPeriod = 8192;       ///< samples per multisine period
inline constexpr double kBwSampleRateHz = 750;  ///< the benchmark's sample rate [Hz]

/// A benchmark record from its samples: t = k / fs, dt = 1 / fs, scored from `first_scored` to the
/// end, offset fixed at 0, simulated from its first sample (rest_samples = 1: the zero state is no
/// rest under u_0 ≠ 0, and a periodic drive is interpolated whole). The one builder of the
/// benchmark's records (the CSV reader, the training cut, the service's workers). Throws
/// InputError naming the record: u and y of different lengths, fewer than 2 samples, a
/// non-finite sample, first_scored leaving no scored sample, a bad sample rate.
io::Record MakeBwRecord(std::string name, model::CaseRole role, std::vector<double> u,
                        std::vector<double> y, size_t first_scored,
                        double sample_rate_hz = kBwSampleRateHz);

/// Reads the benchmark's records of one role from its folder as a record set (format
/// "boucwen-benchmark"; drive N, response m, as the files: not converted): train → train_A,
/// train_B (train_A_multisine.csv, train_B_multisine.csv), test → test_multisine,
/// test_sinesweep (test_multisine.csv, test_sinesweep.csv); columns u_N, y_m. The test records are
/// read only after the identification. InputError naming file, line, column; or a role without
/// records (validate).
io::RecordSet LoadBwBenchmark(const std::filesystem::path& dir, model::CaseRole role);

/// A training record of the first `samples` samples of `raw` (a whole number of periods, else
/// InputError naming the record). `steady_state`: the record is a steady-state response (train_B:
/// its first samples are far from a start at rest), so one period of the periodic input is
/// simulated first as a warm-up and not scored (the 1.1 % damped mode decays in about 0.4 s).
io::Record MakeBwTrainingRecord(const io::Record& raw, size_t samples, bool steady_state);

/// The benchmark's oscillator: θ = (m, c, k, α, β·γ, β·δ) in its box, `rk4_steps` per sample, the
/// input reconstructed by `interpolation` (period_samples for FOURIER), from the zero state.
records::OscillatorOptions BwProtocol(int rk4_steps, model::InputInterpolation interpolation,
                                      size_t period_samples);
/// The records engine's model of it (bw-oscillator, no effect; not scaled to the data: polarity
/// +1).
std::shared_ptr<records::RecordModel> MakeBwModel(const records::OscillatorOptions& options);

/// The identification on training records: owns them and the model; its cost is the records
/// engine's RecordFitness (a diverging simulation costs `penalty`). What `piezoid boucwen`
/// evaluates locally and the service's workers rebuild from the spec: the same costs bit for bit.
class BwTraining final : public opt::FitnessFunction {
 public:
  /// Throws InputError naming the record: none given, a record the input reconstruction refuses
  /// (not periodic, too short), or a penalty that is not finite and > 0.
  BwTraining(std::vector<io::Record> records, const records::OscillatorOptions& options,
             double penalty = 1.0);
  BwTraining(const BwTraining&) = delete;
  BwTraining& operator=(const BwTraining&) = delete;

  opt::FitnessResult Evaluate(const opt::Genome& genome) const override;
  /// The records fitness's lanes (the oscillator runs four parameter sets side by side): each
  /// genome's result Evaluate's, bit for bit.
  int lanes() const override { return fitness_->lanes(); }
  void EvaluateMany(std::span<const opt::Genome* const> genomes,
                    std::span<opt::FitnessResult> out) const override;
  const records::RecordFitness& fitness() const { return *fitness_; }
  /// The search box: the family's parameters and ranges.
  opt::ParamBox Box() const;
  const std::vector<io::Record>& records() const { return records_; }
  const records::OscillatorOptions& options() const { return options_; }
  double penalty() const { return fitness_->penalty(); }
  /// Scored samples over all records.
  size_t counted_samples() const { return fitness_->samples(); }

 private:
  std::vector<io::Record> records_;
  records::OscillatorOptions options_;
  std::shared_ptr<records::RecordModel> model_;
  std::unique_ptr<records::RecordFitness> fitness_;
};

/// θ's response on the official multisine test set: one steady-state period (three simulated
/// from rest, the last returned), periodic Fourier input, 20 RK4 sub-steps.
std::vector<double> SimulateBwMultisineTest(std::span<const double> theta, const io::Record& test);

/// θ's response on the sine sweep, from rest: cubic-spline input, 20 sub-steps.
std::vector<double> SimulateBwSweepTest(std::span<const double> theta, const io::Record& test);

}  // namespace pz::complete
