// The Bouc–Wen hysteretic oscillator of the public benchmark (Noël & Schoukens 2016, see
// data/boucwen-benchmark/README.md):
//
//   m ÿ + c ẏ + k y + z = u
//   ż = α ẏ − β (γ |ẏ| |z|^(ν−1) z + δ ẏ |z|^ν)
//
// driven by a force u sampled at fs (750 Hz in the benchmark). How the benchmark made its data
// (BoucWen_generate_train.m of the benchmark files): the multisine is defined at the integration
// rate fs·20 (= 15 kHz) with lines up to 150 Hz only, integrated by Newmark at h = 1/15000 s, and
// the output is FIR-decimated to 750 Hz; the published u is the 15 kHz input downsampled. So the
// input between samples is the band-limited (for the periodic multisine: trigonometric)
// interpolation of the samples, not a zero-order hold. This simulator therefore:
//
//   1. reconstructs u once per record (BwInput) at every half sub-step, by zero-order hold, linear,
//      cubic B-spline, or periodic Fourier interpolation (exact for a periodic band-limited input);
//   2. integrates by classical RK4 with `substeps` steps per input sample (h = 1/(fs·substeps)),
//      the inputs at t, t + h/2, t + h read from that table; no allocation per step;
//   3. returns y at the input samples (y[0] = the initial state's y).
//
// With the true parameters, 20 sub-steps and Fourier interpolation, the simulated multisine test
// output is within 2.3e-7 m RMS of the official one (tests/complete/bw_oscillator_test.cc), the
// floor the benchmark README measured: the integrator matches the generator.
#pragma once

#include <array>
#include <cstddef>
#include <span>
#include <string>
#include <vector>

#include "model/status.h"

namespace pz::model {

/// Parameters of the oscillator; defaults are the benchmark's true values (README Table 1).
struct BwParams {
  double m = 2;         ///< mass m_L [kg], > 0
  double c = 10;        ///< viscous damping c_L [N s/m], finite
  double k = 5e4;       ///< linear stiffness k_L [N/m], finite
  double alpha = 5e4;   ///< α [N/m], finite
  double beta = 1e3;    ///< β [m^-ν], finite
  double gamma = 0.8;   ///< γ [-], finite
  double delta = -1.1;  ///< δ [-], finite
  double nu = 1;        ///< ν [-], ≥ 1 (ν = 1 takes a fast path without pow)
  /// The error names the field: "bw.m = -1: must be finite and > 0".
  Status Validate() const;
};

enum class InputInterpolation { kZeroOrderHold, kLinear, kCubicSpline, kPeriodicFourier };
/// "zoh", "linear", "spline", "fourier".
const char* InputInterpolationName(InputInterpolation i);
/// Parses the names above; throws InputError naming the value otherwise.
InputInterpolation ParseInputInterpolation(const std::string& name);

struct BwInputOptions {
  double sample_rate_hz = 750;  ///< of the samples of u, finite > 0
  int substeps = 20;            ///< RK4 steps per input sample, 1 … 1000
  InputInterpolation interpolation = InputInterpolation::kCubicSpline;
  /// kPeriodicFourier: samples per period; the record length must be a multiple of it and every
  /// period equal to the first (checked to 1e-9 relative). 0 = the whole record is one period.
  size_t period_samples = 0;
  Status Validate() const;
};

/// A record's input, reconstructed once at every half RK4 step: u(j h / 2), j = 0 … 2 S (n − 1).
class BwInput {
 public:
  BwInput() = default;
  /// Throws InputError naming the option, the first non-finite sample, a short record (≥ 2
  /// samples; ≥ 4 for the spline), or the first sample where a "periodic" record is not.
  BwInput(std::span<const double> u, const BwInputOptions& options);
  /// The same table for another drive, in this input's storage (no allocation when it is no
  /// larger: a search's per-evaluation drives). Throws as the constructor does, leaving the input
  /// empty (samples() = 0).
  void Assign(std::span<const double> u, const BwInputOptions& options);

  size_t samples() const { return samples_; }
  int substeps() const { return options_.substeps; }
  double sample_rate_hz() const { return options_.sample_rate_hz; }
  const BwInputOptions& options() const { return options_; }
  /// u at the half steps; size 2 · substeps · (samples − 1) + 1.
  std::span<const double> half_steps() const { return fine_; }

 private:
  BwInputOptions options_;
  size_t samples_ = 0;
  std::vector<double> fine_;
};

struct BwState {
  double y = 0;  ///< displacement [m]
  double v = 0;  ///< velocity [m/s]
  double z = 0;  ///< hysteretic force [N]
};

/// Simulates the record from `state` (rest when null) and writes y at the n input samples into
/// `y` (size n, checked). On return *state (if given) holds the final state. Returns OutOfRange
/// naming the sample and time when the solution diverges (non-finite, or |y| > 1e3 m, |z| > 1e12
/// N): y is then filled up to that sample and zero after. Throws InputError on invalid parameters.
Status SimulateBw(const BwParams& params, const BwInput& input, std::span<double> y,
                  BwState* state = nullptr);

/// Two parameter sets on one input, side by side in one thread (SimulateBwMany): y[l] and states[l]
/// (rest when null) as SimulateBw(params[l], input, y[l], states ? &states[l] : nullptr) has them,
/// bit for bit, with the same status each (ν = 1 runs as a pair; otherwise, or when a lane
/// diverges, each lane alone). Throws InputError as SimulateBw does.
std::array<Status, 2> SimulateBwPair(const std::array<BwParams, 2>& params, const BwInput& input,
                                     const std::array<std::span<double>, 2>& y,
                                     std::array<BwState, 2>* states = nullptr);
/// The same with each lane on its own input (e.g. each parameter set's own delayed or crept drive):
/// y[l] and states[l] as SimulateBw(params[l], *inputs[l], y[l], …) has them, bit for bit. The
/// inputs must have the same samples, sub-steps and sample rate (InputError naming them otherwise).
std::array<Status, 2> SimulateBwPair(const std::array<BwParams, 2>& params,
                                     const std::array<const BwInput*, 2>& inputs,
                                     const std::array<std::span<double>, 2>& y,
                                     std::array<BwState, 2>* states = nullptr);
/// Any number of parameter sets, each on its own input (pointers may repeat), in groups of four
/// side by side (two SSE2 vector chains of two lanes each: four sets in about the time of one),
/// then two, then one: y[l], states[l] (rest when empty) and the status as SimulateBw has them, bit
/// for bit. Throws InputError as SimulateBwPair does.
std::vector<Status> SimulateBwMany(std::span<const BwParams> params,
                                   std::span<const BwInput* const> inputs,
                                   std::span<const std::span<double>> y,
                                   std::span<BwState> states = {});

/// The identifiable parameterisation for ν = 1 (β appears only in the products β·γ and β·δ, see
/// the benchmark README): θ = (m, c, k, α, β·γ, β·δ) ↦ BwParams with β = 1, γ = β·γ, δ = β·δ,
/// ν = 1. Throws InputError unless θ has 6 values.
BwParams BwFromIdentifiable(std::span<const double> theta);
/// θ of a parameter set with ν = 1: (m, c, k, α, β·γ, β·δ).
std::vector<double> BwIdentifiable(const BwParams& p);
/// The names of θ: "m", "c", "k", "alpha", "beta_gamma", "beta_delta".
const std::vector<std::string>& BwIdentifiableNames();

}  // namespace pz::model
