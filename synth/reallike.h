// Real-like stack records (issue 22, item 5): an independent generator of the records a
// commercial multilayer stack in a flexure stage would give, with the truth that made them, for
// checking the product's families, effects, noise floor and excitation report. It does not use
// records/families.h, records/model.h or model/: its plant is written here, once, from physics.
//
//  - Hysteresis: a Preisach model on the triangle α ≥ β of the drive range, computed exactly from
//    its Everett function (the measure of the half-plane region switched up) and the memory of
//    dominant extrema (wiping-out), so it has return-point memory by construction. The density is
//    a Gaussian in the hysteron's width (α − β) times a Gaussian in its centre ((α + β)/2),
//    skewed by `asymmetry` (asymmetric loops), discretised on a fine grid (the Everett table).
//    Added to it: a reversible part, linear with a quadratic term (a drive-dependent gain).
//  - Creep: relaxations spread over decades (three per decade from `creep_tau_min_s` to
//    `creep_tau_max_s`, equal weights), i.e. a step response x · (1 + c · log10(t / τ_min)) in the
//    middle of the span: log creep.
//  - Sensor: a lag of whole and fractional samples (the plant runs `oversample` times faster than
//    the recorder; the sensor reads it `lag_samples` late, linearly interpolated), white noise plus
//    a first-order coloured noise, quantisation to `quantum`, and a response offset per record
//    (a sensor's zero is not the actuator's).
//  - Drive: the voltage is an analytic function of time (what the amplifier plays); the recorder
//    samples it and rounds it to `drive_quantum`. Every record starts with a rest at `rest_level`
//    (the stack settled there: no creep left), then jumps to its waveform at an arbitrary phase.
//
// The set: a constant-amplitude sine (the major loop) for training; withheld: a sine whose
// amplitude ramps down to zero and back (nested minor loops), a random reversal sequence, and
// a second constant-amplitude sine at another phase (within the training excitation).
// With training frequencies (RealLikeOptions::train_frequencies_hz) the training records are sines
// at several rates, and the withheld ones add sines at other frequencies and a chirp: the records
// that cover rates, for a plant with rate dependence (RealLikeStack::rate_lag_v) or a driver
// low-pass (RealLikeStack::driver_tau_s), both written here and not with the effect library.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "io/records.h"

namespace pz::synth {

/// The true plant of a real-like stack. Defaults: a 150 V stack with ≈ 45 µm stroke.
struct RealLikeStack {
  double u_lo = 0, u_hi = 150;  ///< drive range of the Preisach triangle [V] (saturation outside)
  double stroke_um = 45;        ///< response over the range on the major loop (approximately)
  double hysteresis_share =
      0.18;  ///< share of the stroke carried by the hysterons (the rest: reversible)
  double density_width = 0.45;        ///< mean hysteron width (α − β) as a share of the range
  double density_width_spread = 0.3;  ///< its Gaussian spread, share of the range
  double density_center_spread =
      0.3;                  ///< Gaussian spread of the hysterons' centres, share of the range
  double asymmetry = 1.2;   ///< density × exp(asymmetry · centre'), centre' in [−½, ½]
  double quadratic = 0.12;  ///< reversible part: x' + quadratic · (x'² − ¼), x' in [−½, ½]
  double creep_per_decade = 0.015;  ///< creep per decade of time, share of the displacement
  double creep_tau_min_s = 0.05, creep_tau_max_s = 50;
  int everett_grid = 240;  ///< cells per axis of the density's table
  /// Rate dependence (0 = none): the stack's polarisation follows an effective drive held within
  /// ± λ of the applied one (it lags by λ in the direction of motion and waits at a reversal),
  /// λ = rate_lag_v · tanh(rate_time_s · |u̇| / rate_lag_v) — proportional to the rate below the
  /// knee rate_lag_v / rate_time_s, bounded by rate_lag_v above it — with u̇ the analytic drive's
  /// rate on the plant's fine grid; hysterons and the reversible part both see it.
  double rate_lag_v = 0;
  double rate_time_s = 0.01;
  /// A first-order low-pass of the amplifier ahead of the stack [s] (0 = none).
  double driver_tau_s = 0;
  std::string Validate() const;  ///< "" or what is wrong (field and value)
};

/// The recorder and its sensor.
struct RealLikeSensor {
  double fs_hz = 200;
  int oversample = 8;         ///< plant steps per recorded sample
  double lag_samples = 1.35;  ///< sensor / transport lag [recorded samples], whole + fractional
  double noise_white_um = 0.06;
  double noise_colored_um = 0.02;         ///< first-order (AR(1)) coloured noise, RMS
  double colored_time_s = 0.3;            ///< its correlation time
  double quantum_um = 0.02;               ///< response resolution (0 = none)
  double drive_quantum_v = 150.0 / 4096;  ///< the drive channel's resolution (0 = none)
  double offset_range_um = 5;             ///< each record's response offset is uniform in ±this
  std::string Validate() const;
  /// The RMS a perfect model leaves: √(white² + coloured² + q²/12).
  double NominalFloor() const;
};

/// A drive: rest, then a waveform from an arbitrary phase (all levels in V).
struct RealLikeDrive {
  enum class Kind { kSine, kRampedSine, kReversals, kSamples, kChirp };
  Kind kind = Kind::kSine;
  double rest_level = 0;  ///< the rest segment's drive
  double rest_s = 1;
  double bias = 75;       ///< centre of the waveform
  double amplitude = 70;  ///< peak; kRampedSine: at the ends (zero in the middle)
  double frequency_hz =
      1;  ///< kSine / kRampedSine / kChirp (its start); kReversals: mean rate of 4·A·f as a sine
  double frequency_end_hz = 0;  ///< kChirp: the frequency at its end (logarithmic sweep)
  double phase_rad = 0;
  double duration_s = 20;  ///< after the rest
  uint64_t seed = 1;       ///< kReversals: the turning points
  std::vector<double>
      samples;  ///< kSamples: the drive at fs after the rest (linear between samples)
  double samples_fs_hz = 0;
  std::string Describe() const;
};

/// The noise-free plant (Preisach + reversible + creep), sampled by the sensor with its lag.
class RealLikePlant {
 public:
  explicit RealLikePlant(const RealLikeStack& stack);  ///< throws InputError on a bad stack
  /// Noise-free sensor readings at t_k = k / fs for the drive function u(t), 0 ≤ t ≤ t_end; the
  /// plant starts from negative saturation, goes to u(0) and settles (no creep left).
  std::vector<double> Respond(const std::function<double(double)>& u, size_t samples,
                              const RealLikeSensor& sensor) const;
  /// The Preisach-plus-reversible output (no creep, no lag) after each drive value of `u`, from
  /// negative saturation: for return-point checks.
  std::vector<double> Static(const std::vector<double>& u) const;
  const RealLikeStack& stack() const { return stack_; }

 private:
  class Memory;
  double Everett(double a, double b) const;  ///< measure of {β ≤ α ≤ a, β < b}
  double Hysteretic(const std::vector<double>& extrema) const;
  double Reversible(double u) const;
  RealLikeStack stack_;
  int g_ = 0;
  std::vector<double> table_;  ///< (g+1)², F at grid nodes
  double hyst_scale_ = 0, rev_scale_ = 0, total_ = 0;
};

/// One generated record with its truth.
struct RealLikeRecordTruth {
  std::string name;
  std::string role;
  std::string drive;     ///< RealLikeDrive::Describe
  double offset_um = 0;  ///< added to the response
  double noise_rms_um =
      0;  ///< realised RMS of (measured − noise-free − offset) over the scored window
  size_t scored = 0;
};

struct RealLikeOptions {
  RealLikeStack stack;
  RealLikeSensor sensor;
  double train_s = 40;     ///< the training sine's length (after its rest)
  double withheld_s = 30;  ///< each withheld record's length
  double frequency_hz = 1;
  double amplitude_share = 0.47;  ///< the major loop's amplitude, share of the range
  bool ramp = true, reversals = true, second_sine = true;
  /// Non-empty: the training record ("played") plays this drive (samples at sensor.fs_hz from t =
  /// 0, its leading constant samples the rest) instead of the sine; the withheld records are the
  /// same.
  std::vector<double> train_drive;
  /// Rates (issue 22, rate dependence): non-empty, the training records are one sine per frequency
  /// ("train-<f>hz", train_s each) instead of the major-loop sine at frequency_hz; the withheld
  /// records add one sine per withheld frequency ("sine-<f>hz") and, with `chirp`, a logarithmic
  /// chirp over the span of the training frequencies ("chirp").
  std::vector<double> train_frequencies_hz, withheld_frequencies_hz;
  bool chirp = false;
  uint64_t seed = 1;
};

struct RealLikeSet {
  io::RecordSet set;
  std::vector<RealLikeRecordTruth> truth;  ///< in set order
  RealLikeOptions options;
  double nominal_floor_um = 0;   ///< RealLikeSensor::NominalFloor
  double realised_floor_um = 0;  ///< RMS over every scored sample of every record
  double major_loop_width =
      0;  ///< widest gap between the branches of the noise-free major loop, share of its stroke
};

/// Generates the set (deterministic in the seed). Throws InputError on bad options.
RealLikeSet GenerateRealLikeSet(const RealLikeOptions& options);

/// One record of the plant on a drive (noise, quantisation and offset from `seed`); window: the
/// excitation after the rest. `clean` (optional) receives the noise-free readings.
io::Record SynthesizeRealLikeRecord(const RealLikePlant& plant, const RealLikeSensor& sensor,
                                    const RealLikeDrive& drive, const std::string& name,
                                    model::CaseRole role, uint64_t seed,
                                    RealLikeRecordTruth* truth = nullptr,
                                    std::vector<double>* clean = nullptr);

/// The drive as a function of time (rest then waveform); throws InputError on a bad drive.
std::function<double(double)> DriveFunction(const RealLikeDrive& drive);

}  // namespace pz::synth
