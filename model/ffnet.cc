#include "model/ffnet.h"
#include "model/fast_exp.h"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <algorithm>
#include <vector>
#include <string>

#include <Eigen/Dense>

namespace pz::model {

MinMaxMap MinMaxMap::Identity(int channels) {
  PZ_CHECK(channels >= 1);
  MinMaxMap m;
  m.xmin = Eigen::VectorXd::Constant(channels, -1.0);
  m.gain = Eigen::VectorXd::Ones(channels);
  return m;
}

MinMaxMap MinMaxMap::Fit(const Eigen::MatrixXd& X) {
  if (X.rows() < 1 || X.cols() < 1)
    throw InputError(FieldError("data rows", X.rows(), "need at least one sample and one channel"));
  MinMaxMap m;
  m.xmin.resize(X.cols());
  m.gain.resize(X.cols());
  for (Eigen::Index k = 0; k < X.cols(); ++k) {
    if (!X.col(k).allFinite())
      throw InputError("channel " + std::to_string(k) + " has a non-finite value");
    const double lo = X.col(k).minCoeff();
    const double hi = X.col(k).maxCoeff();
    m.xmin(k) = lo;
    m.gain(k) = hi > lo ? 2.0 / (hi - lo) : 1.0;
    if (!std::isfinite(m.gain(k)))
      throw InputError(FieldError("channel " + std::to_string(k) + " range", hi - lo,
                                  "too small for a finite mapminmax gain"));
  }
  return m;
}

Eigen::MatrixXd MinMaxMap::Apply(const Eigen::MatrixXd& X) const {
  PZ_CHECK_MSG(X.cols() == size(), "MinMaxMap::Apply: channel count mismatch");
  Eigen::MatrixXd out(X.rows(), X.cols());
  for (Eigen::Index k = 0; k < X.cols(); ++k)
    out.col(k) = ((X.col(k).array() - xmin(k)) * gain(k) - 1.0).matrix();
  return out;
}

Status MinMaxMap::Validate() const {
  if (xmin.size() < 1)
    return InvalidArgument(FieldError("map channels", xmin.size(), "must be >= 1"));
  if (gain.size() != xmin.size())
    return InvalidArgument(FieldError("map gain size", gain.size(), "must equal the xmin size"));
  for (Eigen::Index k = 0; k < xmin.size(); ++k) {
    if (!std::isfinite(xmin(k)))
      return InvalidArgument(
          FieldError("xmin[" + std::to_string(k) + "]", xmin(k), "must be finite"));
    if (!(std::isfinite(gain(k)) && gain(k) > 0))
      return InvalidArgument(
          FieldError("gain[" + std::to_string(k) + "]", gain(k), "must be finite and > 0"));
  }
  return Status::Ok();
}

Status FfnetShape::Validate() const {
  if (inputs < 1 || inputs > 1000)
    return InvalidArgument(FieldError("inputs", inputs, "must be in [1, 1000]"));
  if (hidden < 1 || hidden > 100000)
    return InvalidArgument(FieldError("hidden", hidden, "must be in [1, 100000]"));
  return Status::Ok();
}

namespace {

// tansig(v) = sign(v) (1 − 2/(e^(2|v|) + 1)) in place: e^a by range reduction a = k ln2 + r,
// |r| ≤ ln2/2, a degree-13 Taylor polynomial (truncation < 1e−17 relative) and 2^k assembled in the
// exponent bits; |v| is clamped at 20 (tansig(20) rounds to ±1). Error ≤ 3e−16 absolute against
// std::tanh. Branch-free so GCC vectorises it (this file is compiled with -fno-trapping-math, see
// model/CMakeLists.txt); target_clones adds an AVX2+FMA copy chosen at load time on CPUs that have
// it.
__attribute__((target_clones("arch=x86-64-v3", "default"))) void TansigKernel(double* x,
                                                                              std::ptrdiff_t n) {
  for (std::ptrdiff_t i = 0; i < n; ++i) {
    const double v = x[i];
    const double a0 = 2.0 * std::fabs(v);
    const double a = a0 > 40.0 ? 40.0 : a0;  // NaN passes through
    const double e = ExpReduced(a);
    x[i] = std::copysign(1.0 - 2.0 / (e + 1.0), v);
  }
}

}  // namespace

void TansigInPlace(Eigen::Ref<Eigen::MatrixXd> n) {
  if (n.rows() == n.outerStride()) {
    TansigKernel(n.data(), n.size());
  } else {
    for (Eigen::Index j = 0; j < n.cols(); ++j) TansigKernel(n.col(j).data(), n.rows());
  }
}

FeedForwardNet::FeedForwardNet(const FfnetShape& shape) : shape_(shape) {
  ThrowIfError(shape.Validate());
  w_ = Eigen::VectorXd::Zero(shape.num_params());
  input_map_ = MinMaxMap::Identity(shape.inputs);
  output_map_ = MinMaxMap::Identity(1);
}

void FeedForwardNet::set_params(const Eigen::VectorXd& w) {
  if (w.size() != num_params())
    throw InputError(FieldError("params size", w.size(),
                                "must equal H R + 2H + 1 = " + std::to_string(num_params())));
  for (Eigen::Index i = 0; i < w.size(); ++i)
    if (!std::isfinite(w(i)))
      throw InputError(FieldError("params[" + std::to_string(i) + "]", w(i), "must be finite"));
  w_ = w;
}

void FeedForwardNet::ConfigureMaps(const Eigen::MatrixXd& X, const Eigen::VectorXd& t) {
  if (X.cols() != inputs())
    throw InputError(
        FieldError("input columns", X.cols(),
                   "must equal the network's inputs (" + std::to_string(inputs()) + ")"));
  if (t.size() != X.rows())
    throw InputError(
        FieldError("targets", t.size(),
                   "must have one entry per input row (" + std::to_string(X.rows()) + ")"));
  input_map_ = MinMaxMap::Fit(X);
  output_map_ = MinMaxMap::Fit(t);
}

void FeedForwardNet::set_maps(const MinMaxMap& input, const MinMaxMap& output) {
  ThrowIfError(input.Validate());
  ThrowIfError(output.Validate());
  if (input.size() != inputs())
    throw InputError(
        FieldError("input map channels", input.size(), "must equal the network's inputs"));
  if (output.size() != 1)
    throw InputError(FieldError("output map channels", output.size(), "must be 1"));
  input_map_ = input;
  output_map_ = output;
}

Eigen::Map<const Eigen::MatrixXd> FeedForwardNet::IW() const {
  return {w_.data(), hidden(), inputs()};
}
Eigen::Map<const Eigen::VectorXd> FeedForwardNet::b1() const {
  return {w_.data() + hidden() * inputs(), hidden()};
}
Eigen::Map<const Eigen::VectorXd> FeedForwardNet::LW() const {
  return {w_.data() + hidden() * inputs() + hidden(), hidden()};
}

void FeedForwardNet::InitNguyenWidrow(std::mt19937_64& rng) {
  const int H = hidden(), R = inputs();
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  const double active_half_width = 2.0;  // tansig's active input range is [−2, 2]
  const double mag = 0.7 * std::pow(static_cast<double>(H), 1.0 / R);
  Eigen::MatrixXd iw(H, R);
  Eigen::VectorXd b(H);
  for (int j = 0; j < H; ++j) {
    double norm2 = 0;
    for (int k = 0; k < R; ++k) {
      iw(j, k) = normal(rng);
      norm2 += iw(j, k) * iw(j, k);
    }
    const double inv = norm2 > 0 ? 1.0 / std::sqrt(norm2) : 1.0;
    iw.row(j) *= mag * inv * active_half_width;
    const double spread = H == 1 ? 0.0 : -1.0 + 2.0 * j / (H - 1);
    b(j) = active_half_width * mag * spread * (iw(j, 0) >= 0 ? 1.0 : -1.0);
  }
  Eigen::VectorXd w(num_params());
  w.head(H * R) = Eigen::Map<const Eigen::VectorXd>(iw.data(), H * R);
  w.segment(H * R, H) = b;
  for (int j = 0; j < H; ++j) w(H * R + H + j) = uniform(rng);
  w(num_params() - 1) = uniform(rng);
  w_ = w;
}

void FeedForwardNet::InitAdaptive(std::mt19937_64& rng,
                                  const Eigen::Ref<const Eigen::VectorXd>& x_train,
                                  const Eigen::Ref<const Eigen::VectorXd>& t_train, double lambda,
                                  double min_samples_per_neuron) {
  const int H = hidden();
  if (inputs() != 1)
    throw InputError(
        FieldError("inputs", inputs(), "the adaptive initialisation needs a one-input network"));
  if (x_train.size() != t_train.size())
    throw InputError(FieldError(
        "training targets", t_train.size(),
        "must have one entry per training input (" + std::to_string(x_train.size()) + ")"));
  const Eigen::Index n = x_train.size();
  if (n < 2)
    throw InputError(FieldError("training samples", n, "the adaptive initialisation needs >= 2"));
  if (!(lambda >= 0.0 && lambda <= 1.0))
    throw InputError(FieldError("adaptive fraction", lambda, "must be in [0, 1]"));
  if (!(std::isfinite(min_samples_per_neuron) && min_samples_per_neuron >= 0))
    throw InputError(
        FieldError("samples per neuron", min_samples_per_neuron, "must be finite and >= 0"));
  for (Eigen::Index i = 0; i < n; ++i)
    if (!std::isfinite(x_train(i)) || !std::isfinite(t_train(i)))
      throw InputError(FieldError("training sample " + std::to_string(i),
                                  std::isfinite(x_train(i)) ? t_train(i) : x_train(i),
                                  "must be finite"));

  // Normalised samples sorted by input (stable: ties keep their order), and the cumulative
  // variation of the normalised target along them.
  std::vector<Eigen::Index> order(static_cast<size_t>(n));
  for (Eigen::Index i = 0; i < n; ++i) order[static_cast<size_t>(i)] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](Eigen::Index a, Eigen::Index b) { return x_train(a) < x_train(b); });
  const double gx = input_map_.gain(0), gt = output_map_.gain(0);
  std::vector<double> xs(static_cast<size_t>(n)), cv(static_cast<size_t>(n), 0.0);
  for (size_t k = 0; k < xs.size(); ++k) {
    const Eigen::Index i = order[k];
    xs[k] = (x_train(i) - input_map_.xmin(0)) * gx - 1.0;
    if (k > 0) cv[k] = cv[k - 1] + std::abs(t_train(i) - t_train(order[k - 1])) * gt;
  }
  const double x0 = xs.front(), x1 = xs.back();
  if (!(x1 > x0)) throw InputError(FieldError("training input range", x1 - x0, "must be > 0"));
  const double tv = cv.back();
  const double lam = tv > 0 ? lambda : 0.0;
  // The mixture's CDF at the sorted samples (non-decreasing from 0 to 1), then its quantiles.
  std::vector<double> F(static_cast<size_t>(n));
  for (size_t k = 0; k < F.size(); ++k)
    F[k] = (1.0 - lam) * (xs[k] - x0) / (x1 - x0) + (lam > 0 ? lam * cv[k] / tv : 0.0);
  F.back() = 1.0;
  std::vector<double> c(static_cast<size_t>(H));
  for (int j = 0; j < H; ++j) {
    const double q = H == 1 ? 0.5 : static_cast<double>(j) / (H - 1);
    const size_t k = static_cast<size_t>(std::lower_bound(F.begin(), F.end(), q) - F.begin());
    if (k == 0) {
      c[static_cast<size_t>(j)] = xs[0];
    } else {
      const double f0 = F[k - 1], f1 = F[k];
      const double u = f1 > f0 ? (q - f0) / (f1 - f0) : 1.0;
      c[static_cast<size_t>(j)] = xs[k - 1] + u * (xs[k] - xs[k - 1]);
    }
  }
  // NW: |IW| = 2 · 0.7 H on the spacing 2/(H − 1), i.e. |IW| · spacing = kappa. A neuron's active
  // region (|IW x̃ + b| ≤ 2) is then 4 s/kappa wide; it must hold min_samples_per_neuron training
  // samples at their median spacing, or the network can bend between the samples it is fitted to.
  const double kappa = H == 1 ? 2.8 : 2.8 * H / (H - 1.0);
  std::vector<double> gaps;
  gaps.reserve(static_cast<size_t>(n - 1));
  for (size_t k = 1; k < xs.size(); ++k)
    if (xs[k] > xs[k - 1]) gaps.push_back(xs[k] - xs[k - 1]);
  std::nth_element(gaps.begin(), gaps.begin() + static_cast<std::ptrdiff_t>(gaps.size() / 2),
                   gaps.end());
  const double s_min = min_samples_per_neuron * gaps[gaps.size() / 2] * kappa / 4.0;
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  Eigen::VectorXd w(num_params());
  for (int j = 0; j < H; ++j) {
    const size_t u = static_cast<size_t>(j);
    double s;
    if (H == 1)
      s = x1 - x0;
    else if (j == 0)
      s = c[1] - c[0];
    else if (j == H - 1)
      s = c[u] - c[u - 1];
    else
      s = (c[u + 1] - c[u - 1]) / 2;
    s = std::max(s, s_min);
    const double sign = normal(rng) >= 0 ? 1.0 : -1.0;  // NW's random direction, in one dimension
    w(j) = sign * kappa / s;
    w(H + j) = -w(j) * c[u];
  }
  for (int j = 0; j < H; ++j) w(2 * H + j) = uniform(rng);
  w(num_params() - 1) = uniform(rng);
  set_params(w);
}

Eigen::VectorXd FeedForwardNet::PredictNormalised(
    const Eigen::Ref<const Eigen::MatrixXd>& Xn) const {
  PZ_CHECK(Xn.cols() == inputs());
  const Eigen::Index n = Xn.rows();
  Eigen::VectorXd y(n);
  constexpr Eigen::Index kBlock = 512;
  Eigen::MatrixXd A;
  const auto iw = IW();
  const auto bias = b1();
  const auto lw = LW();
  for (Eigen::Index r0 = 0; r0 < n; r0 += kBlock) {
    const Eigen::Index m = std::min(kBlock, n - r0);
    A.noalias() = Xn.middleRows(r0, m) * iw.transpose();
    A.rowwise() += bias.transpose();
    TansigInPlace(A);
    y.segment(r0, m).noalias() = A * lw;
  }
  const double c = 1.0 / output_map_.gain(0);
  y = ((y.array() + b2() + 1.0) * c + output_map_.xmin(0)).matrix();
  return y;
}

Eigen::VectorXd FeedForwardNet::Predict(const Eigen::MatrixXd& X) const {
  if (X.cols() != inputs())
    throw InputError(
        FieldError("input columns", X.cols(),
                   "must equal the network's inputs (" + std::to_string(inputs()) + ")"));
  return PredictNormalised(input_map_.Apply(X));
}

void FeedForwardNet::JacobianNormalised(const Eigen::Ref<const Eigen::MatrixXd>& Xn,
                                        Eigen::Ref<Eigen::VectorXd> y,
                                        Eigen::Ref<Eigen::MatrixXd> J) const {
  const int H = hidden(), R = inputs(), P = num_params();
  const Eigen::Index m = Xn.rows();
  PZ_CHECK(Xn.cols() == R && y.size() == m && J.rows() == m && J.cols() == P);
  const double c = 1.0 / output_map_.gain(0);  // ∂y/∂ỹ of the reverse output map
  const auto lw = LW();
  auto A = J.middleCols(R * H + H, H);  // hidden activations, later ∂y/∂LW = c A
  auto D = J.middleCols(R * H, H);      // ∂y/∂b1_j = c LW_j (1 − a_j²)
  A.noalias() = Xn * IW().transpose();
  A.rowwise() += b1().transpose();
  TansigInPlace(A);
  y.noalias() = A * lw;
  y = ((y.array() + b2() + 1.0) * c + output_map_.xmin(0)).matrix();
  for (int j = 0; j < H; ++j) D.col(j) = ((1.0 - A.col(j).array().square()) * (c * lw(j))).matrix();
  for (int k = 0; k < R; ++k)
    J.middleCols(k * H, H) = (D.array().colwise() * Xn.col(k).array()).matrix();
  A *= c;
  J.col(P - 1).setConstant(c);
}

}  // namespace pz::model
