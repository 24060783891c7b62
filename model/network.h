// The HGANN network (spec hgann.md §1; paper Appendix C, D): a 2-H-7 feed-forward network whose
// outputs are the seven identified parameters of the bimorph-fin model.
//
//   x_i = (v_i − lo_i) / (hi_i − lo_i)                 v = (amplitude [V], frequency [Hz])
//   A_i = TF_i(x_i)                                    input layer, no weights        (D1)
//   B_j = TF_j(Σ_i A_i W1_ij + c1_j)                   hidden layer, j < H            (D2)
//   O_k = TF_k(Σ_j B_j W2_jk + c2_k)                   output layer, k < 7            (D3)
//   p_k = lower_k + (O_k − lo_TFk)/(hi_TFk − lo_TFk) · (upper_k − lower_k)
//
// Output order: μ, δ, α, β, γ, a1, a2. Pure (Eigen only): no files, no logging; a Network is an
// immutable value that any number of threads can query.
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "model/status.h"

namespace pz::model {

/// The eight bounded MATLAB transfer functions; the value is the 3-bit chromosome code.
enum class TransferFunction : int {
  kHardlim = 0,   ///< 1 if n ≥ 0, else 0                      range [0, 1]
  kHardlims = 1,  ///< 1 if n ≥ 0, else −1                     range [−1, 1]
  kSatlin = 2,    ///< 0 if n ≤ 0; n if 0 < n < 1; 1 if n ≥ 1  range [0, 1]
  kSatlins = 3,   ///< −1 if n ≤ −1; n if |n| < 1; 1 if n ≥ 1  range [−1, 1]
  kTribas = 4,    ///< 1 − |n| if |n| ≤ 1, else 0              range [0, 1]
  kTansig = 5,    ///< 2/(1 + exp(−2n)) − 1                    range [−1, 1]
  kLogsig = 6,    ///< 1/(1 + exp(−n))                         range [0, 1]
  kRadbas = 7,    ///< exp(−n²)                                range [0, 1]
};
inline constexpr int kNumTransferFunctions = 8;

/// MATLAB name ("hardlim" … "radbas").
const char* TransferFunctionName(TransferFunction tf);
/// Parses a MATLAB name (case-sensitive, lower case). Returns false if unknown.
bool ParseTransferFunction(const std::string& name, TransferFunction* tf);
/// True iff 0 ≤ code < 8.
bool IsValidTransferCode(int code);
/// The transfer function of a 3-bit code. Requires IsValidTransferCode(code) (checked).
TransferFunction TransferFromCode(int code);

/// TF(n). Finite for every finite n; hardlim/hardlims/satlin/satlins/tribas map NaN as a comparison
/// with NaN does (callers never pass NaN: inputs are validated).
double ApplyTransfer(TransferFunction tf, double n);

/// Closed range [lo, hi] of a transfer function's output.
struct TransferRange {
  double lo = 0;
  double hi = 1;
};
TransferRange RangeOf(TransferFunction tf);

inline constexpr int kNetworkInputs = 2;   ///< amplitude [V], frequency [Hz]
inline constexpr int kNetworkOutputs = 7;  ///< μ, δ, α, β, γ, a1, a2
inline constexpr int kMinHidden = 2;
inline constexpr int kMaxHidden = 9;

/// Index of each output node.
enum class NetworkOutput : int { kMu = 0, kDelta, kAlpha, kBeta, kGamma, kA1, kA2 };
/// "mu", "delta", "alpha", "beta", "gamma", "a1", "a2" (k in 0 … 6; checked).
const char* OutputName(int k);
/// "1/s", "s", "N/V", "1/V", "1/V", "deg", "deg" (k in 0 … 6; checked).
const char* OutputUnit(int k);
/// "amplitude", "frequency" and "V", "Hz" (i in 0 … 1; checked).
const char* InputName(int i);
const char* InputUnit(int i);

/// The closed interval an output is mapped onto.
struct ParameterRange {
  double lower = 0;  ///< value at the bottom of the TF's range, finite
  double upper = 1;  ///< value at the top of the TF's range, finite, ≥ lower
  bool operator==(const ParameterRange&) const = default;
};

/// The range of each identified parameter (part of a job's configuration). Defaults: spec §3.
struct ParameterRanges {
  ParameterRange mu{0, 300};          ///< μ [1/s]
  ParameterRange delta{0, 1};         ///< δ [s]
  ParameterRange alpha{0, 0.01};      ///< α [N/V]
  ParameterRange beta{0, 0.02};       ///< β [1/V]
  ParameterRange gamma{-0.02, 0.02};  ///< γ [1/V]
  ParameterRange a1{0, 2};            ///< a1 [deg]
  ParameterRange a2{0, 2};            ///< a2 [deg]

  /// The paper's Table 3 (with μ and δ in their physical roles, spec §3): α, β, γ in [−0.1, 0].
  static ParameterRanges PaperTable3();
  /// Range of output k (0 … 6, output order).
  const ParameterRange& operator[](int k) const;
  ParameterRange& operator[](int k);
  /// Every bound finite and lower ≤ upper; the error names the field, e.g. "ranges.alpha.upper".
  Status Validate() const;
  bool operator==(const ParameterRanges&) const = default;
};

/// x = (v − lo)/(hi − lo) for each input. Values outside [lo, hi] extrapolate (x outside [0, 1]).
struct InputNormalization {
  double amplitude_lo_v = 0;   ///< [V], finite
  double amplitude_hi_v = 1;   ///< [V], finite, > amplitude_lo_v
  double frequency_lo_hz = 0;  ///< [Hz], finite
  double frequency_hi_hz = 1;  ///< [Hz], finite, > frequency_lo_hz

  /// The spec's default: min and max over the training cases. If all cases share one value, the
  /// interval is widened to [v, v + 1] so that x = 0 for them. Throws InputError on empty or
  /// non-finite input or mismatched lengths.
  static InputNormalization FromCases(std::span<const double> amplitudes_v,
                                      std::span<const double> frequencies_hz);
  Status Validate() const;
  double NormalizeAmplitude(double v) const {
    return (v - amplitude_lo_v) / (amplitude_hi_v - amplitude_lo_v);
  }
  double NormalizeFrequency(double f) const {
    return (f - frequency_lo_hz) / (frequency_hi_hz - frequency_lo_hz);
  }
  bool operator==(const InputNormalization&) const = default;
};

/// The seven predicted parameters, in the units of ParameterRanges.
struct NetworkParameters {
  double mu = 0;     ///< [1/s]
  double delta = 0;  ///< [s]
  double alpha = 0;  ///< [N/V]
  double beta = 0;   ///< [1/V]
  double gamma = 0;  ///< [1/V]
  double a1 = 0;     ///< [deg]
  double a2 = 0;     ///< [deg]
  /// Output order μ, δ, α, β, γ, a1, a2.
  std::array<double, kNetworkOutputs> ToArray() const {
    return {mu, delta, alpha, beta, gamma, a1, a2};
  }
  static NetworkParameters FromArray(const std::array<double, kNetworkOutputs>& p);
  bool operator==(const NetworkParameters&) const = default;
};

/// Every layer's values for one input (diagnostics and tests).
struct NetworkActivations {
  Eigen::Vector2d x;                            ///< normalised inputs
  Eigen::Vector2d a;                            ///< input-layer outputs A
  Eigen::VectorXd b;                            ///< hidden-layer outputs B (H)
  Eigen::Matrix<double, kNetworkOutputs, 1> o;  ///< output-layer outputs O
  Eigen::Matrix<double, kNetworkOutputs, 1> s;  ///< O scaled to [0, 1]
  NetworkParameters parameters;                 ///< p
};

/// A 2-H-7 network. A plain value: build it by hand, decode it from a chromosome
/// (model/chromosome.h) or load it from a file (io/network_io.h); Validate() before use.
struct Network {
  std::array<TransferFunction, kNetworkInputs> input_tf{};    ///< TF of input nodes 0–1
  std::vector<TransferFunction> hidden_tf;                    ///< TF of hidden nodes, H entries
  std::array<TransferFunction, kNetworkOutputs> output_tf{};  ///< TF of output nodes 0–6
  Eigen::MatrixXd w1;  ///< 2 × H, W1(i, j): input i to hidden j
  Eigen::VectorXd c1;  ///< H hidden biases
  Eigen::MatrixXd w2;  ///< H × 7, W2(j, k): hidden j to output k
  Eigen::VectorXd c2;  ///< 7 output biases
  InputNormalization normalization;
  ParameterRanges ranges;

  /// H, the number of hidden nodes.
  int hidden() const { return static_cast<int>(hidden_tf.size()); }
  /// Sizes consistent (2 ≤ H ≤ 9), TF codes valid, every weight finite, normalisation and ranges
  /// valid. The error names the field, e.g. "w2(1, 4) = nan: must be finite".
  Status Validate() const;
  /// Forward pass with every intermediate value. Requires a valid network (checked cheaply: sizes);
  /// throws InputError on a non-finite input.
  NetworkActivations Forward(double amplitude_v, double frequency_hz) const;
  /// The seven parameters for a drive of amplitude [V] and frequency [Hz].
  NetworkParameters Predict(double amplitude_v, double frequency_hz) const {
    return Forward(amplitude_v, frequency_hz).parameters;
  }
  /// "2-3-7 in[satlin,tribas] hidden[tribas,satlins,tansig] out[satlin,…]".
  std::string Describe() const;
  /// Exact equality of every field (weights compared bit for bit as doubles).
  bool operator==(const Network& other) const;
};

}  // namespace pz::model
