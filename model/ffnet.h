// A one-hidden-layer feed-forward regression network as MATLAB's fitnet builds it (spec
// "dahl-model", the paper's networks): R inputs, H tansig hidden neurons, one linear output, with
// mapminmax pre-processing of the inputs and post-processing of the output.
//
//   x̃_k = −1 + 2 (x_k − xmin_k) / (xmax_k − xmin_k)              input map, each input k < R
//   a_j = tansig(Σ_k IW_jk x̃_k + b1_j),  tansig(n) = 2/(1 + e^(−2n)) − 1      hidden, j < H
//   ỹ   = Σ_j LW_j a_j + b2                                         linear output
//   y   = tmin + (ỹ + 1)(tmax − tmin)/2                             output map (reverse mapminmax)
//
// The parameter vector w (P = H R + 2H + 1 entries) is laid out as
//   w = [ IW (H × R, column-major: IW_jk at k H + j) | b1 (H) | LW (H) | b2 ].
// Outputs, errors and the Jacobian J = ∂y/∂w are in target units (MATLAB's default performance
// normalisation 'none'), so the trainers' MSE, gradient and μ compare with the toolbox's.
//
// Samples are rows: an input matrix X is n × R (column-major, each input a contiguous column).
// Pure (Eigen only): no I/O. A FeedForwardNet is a value; const methods are thread-safe.
#pragma once

#include <cstdint>
#include <random>

#include <Eigen/Core>

#include "model/status.h"

namespace pz::model {

using RowMajorMatrixXd = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/// MATLAB mapminmax with ymin = −1, ymax = 1, one entry per row of the data (input or target):
/// x̃ = −1 + gain (x − xmin), gain = 2/(xmax − xmin); a constant row gets gain 1 (x̃ = x − xmin −
/// 1).
struct MinMaxMap {
  Eigen::VectorXd xmin;  ///< per-channel minimum [channel unit]
  Eigen::VectorXd gain;  ///< per-channel 2/(xmax − xmin) [1/channel unit], finite, > 0

  int size() const { return static_cast<int>(xmin.size()); }
  /// Identity-like map of `channels` channels (xmin = −1, gain = 1).
  static MinMaxMap Identity(int channels);
  /// Fits the map to the columns of X (n × R): channel k spans X.col(k). Requires n ≥ 1 and
  /// finite values (throws InputError naming the channel otherwise).
  static MinMaxMap Fit(const Eigen::MatrixXd& X);
  /// x̃ for every row of X (n × R).
  Eigen::MatrixXd Apply(const Eigen::MatrixXd& X) const;
  /// Channel 0 value back to its unit: x = xmin + (x̃ + 1)/gain.
  double Reverse0(double x_normalised) const { return xmin(0) + (x_normalised + 1.0) / gain(0); }
  Status Validate() const;
};

/// Size of a network: inputs R ≥ 1, hidden neurons H ≥ 1.
struct FfnetShape {
  int inputs = 1;    ///< R, number of input channels, in [1, 1000]
  int hidden = 100;  ///< H, number of tansig neurons, in [1, 100000]
  Status Validate() const;
  /// P = H R + 2 H + 1.
  int num_params() const { return hidden * inputs + 2 * hidden + 1; }
};

/// tansig(n) = 2/(1 + e^(−2n)) − 1 = tanh(n), elementwise and vectorised (within 3e−16 of
/// std::tanh; exactly ±1 in the tails, NaN stays NaN).
void TansigInPlace(Eigen::Ref<Eigen::MatrixXd> n);

class FeedForwardNet {
 public:
  /// All weights zero, identity maps. Throws InputError if the shape is invalid.
  explicit FeedForwardNet(const FfnetShape& shape = {});

  const FfnetShape& shape() const { return shape_; }
  int inputs() const { return shape_.inputs; }
  int hidden() const { return shape_.hidden; }
  int num_params() const { return shape_.num_params(); }

  const Eigen::VectorXd& params() const { return w_; }
  /// Throws InputError if the size is not num_params() or a value is not finite.
  void set_params(const Eigen::VectorXd& w);

  const MinMaxMap& input_map() const { return input_map_; }
  const MinMaxMap& output_map() const { return output_map_; }
  /// Fits both maps to the data (MATLAB's configure): X is n × R, t has n entries.
  void ConfigureMaps(const Eigen::MatrixXd& X, const Eigen::VectorXd& t);
  void set_maps(const MinMaxMap& input, const MinMaxMap& output);

  /// MATLAB's initnw (Nguyen–Widrow) for the tansig layer on normalised inputs in [−1, 1]:
  /// ‖IW_j‖ = 2 · 0.7 H^(1/R) in a random direction (2 = half the width of tansig's active input
  /// range [−2, 2]), b1_j = ‖IW_j‖ · linspace(−1, 1, H)_j · sign(IW_j0), so the H active regions
  /// tile the input box; the linear output layer gets uniform values in [−1, 1] (MATLAB's rands).
  /// Draws only from rng.
  void InitNguyenWidrow(std::mt19937_64& rng);

  /// Data-adaptive Nguyen–Widrow for a one-input network (R = 1), from the training samples (raw
  /// units; the maps must be configured). NW tiles the input range with evenly spaced neurons of
  /// one width, so a feature much narrower than that spacing (the Dahl response's 30 ms rise in a
  /// 10 s record) is reached only after hundreds of epochs on a plateau. Here the H centres are the
  /// quantiles j/(H − 1) of a mixture of the uniform density on the input range (weight 1 − λ) and
  /// the density of the target's variation along the input (weight λ: the cumulative Σ|Δt̃| over
  /// the training samples sorted by input). Each neuron's width follows the local spacing s_j of
  /// the centres (|IW_j| = κ/s_j with NW's product κ = 2.8 H/(H − 1)), but its active region
  /// (|n| ≤ 2) spans at least min_samples_per_neuron training samples at their median spacing; the
  /// sign of IW_j is drawn from rng, b1_j = −IW_j c_j, and the output layer is uniform in [−1, 1]
  /// as in NW. With λ = 0 the centres and widths are NW's (when the floor does not bind). Draws
  /// only from rng; the targets are used only through their variation.
  /// Throws InputError if R ≠ 1, the sizes differ, fewer than 2 samples or no input range is
  /// given, a value is not finite, λ is not in [0, 1] or min_samples_per_neuron < 0.
  void InitAdaptive(std::mt19937_64& rng, const Eigen::Ref<const Eigen::VectorXd>& x_train,
                    const Eigen::Ref<const Eigen::VectorXd>& t_train, double lambda,
                    double min_samples_per_neuron = 10.0);

  /// y (target units) for each row of X (n × R, raw input units).
  Eigen::VectorXd Predict(const Eigen::MatrixXd& X) const;
  /// y (target units) for each row of already-normalised inputs Xn (n × R).
  Eigen::VectorXd PredictNormalised(const Eigen::Ref<const Eigen::MatrixXd>& Xn) const;

  /// Outputs y (n) and Jacobian J = ∂y/∂w (n × P, column-major, target units) for the rows of
  /// normalised inputs Xn. J must already have n rows and P columns (so callers can reuse a buffer
  /// or pass a block of a larger matrix).
  void JacobianNormalised(const Eigen::Ref<const Eigen::MatrixXd>& Xn,
                          Eigen::Ref<Eigen::VectorXd> y, Eigen::Ref<Eigen::MatrixXd> J) const;

  /// Views of the parameter blocks inside params().
  Eigen::Map<const Eigen::MatrixXd> IW() const;  ///< H × R
  Eigen::Map<const Eigen::VectorXd> b1() const;  ///< H
  Eigen::Map<const Eigen::VectorXd> LW() const;  ///< H
  double b2() const { return w_(num_params() - 1); }

 private:
  FfnetShape shape_;
  Eigen::VectorXd w_;
  MinMaxMap input_map_;
  MinMaxMap output_map_;
};

}  // namespace pz::model
