// The fitnet-style network: mapminmax maps, tansig, Nguyen–Widrow initialisation, the forward
// pass against a hand-written formula, the Jacobian against central finite differences, and the
// dense kernels (SYRK, GEMM, Cholesky) against Eigen's reference products.
#include "model/ffnet.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>
#include <vector>
#include <algorithm>

#include <Eigen/Dense>

#include "model/dense_kernels.h"
#include "tests/testing/expect_error.h"

namespace pz::model {
namespace {

using pz::testing::InputErrorOf;

FeedForwardNet RandomNet(int inputs, int hidden, uint64_t seed) {
  FeedForwardNet net(FfnetShape{inputs, hidden});
  Eigen::MatrixXd X = Eigen::MatrixXd::Random(50, inputs) * 3.0;
  Eigen::VectorXd t = Eigen::VectorXd::Random(50) * 5.0 + Eigen::VectorXd::Constant(50, 2.0);
  net.ConfigureMaps(X, t);
  std::mt19937_64 rng(seed);
  net.InitNguyenWidrow(rng);
  return net;
}

TEST(MinMaxMap, MapsEachChannelOntoMinusOneOne) {
  Eigen::MatrixXd X(3, 2);
  X << 0, 10, 5, 10, 10, 10;  // channel 1 constant
  const MinMaxMap m = MinMaxMap::Fit(X);
  const Eigen::MatrixXd Y = m.Apply(X);
  EXPECT_DOUBLE_EQ(Y(0, 0), -1.0);
  EXPECT_DOUBLE_EQ(Y(1, 0), 0.0);
  EXPECT_DOUBLE_EQ(Y(2, 0), 1.0);
  EXPECT_DOUBLE_EQ(m.gain(1), 1.0);  // constant channel: gain 1 (MATLAB)
  EXPECT_DOUBLE_EQ(Y(0, 1), -1.0);
  EXPECT_DOUBLE_EQ(m.Reverse0(Y(1, 0)), 5.0);
}

TEST(Tansig, MatchesTanhAndSaturatesExactly) {
  // 2,001 points over [−25, 25] (odd count: contiguous path) and a strided block (column path).
  Eigen::MatrixXd n = Eigen::VectorXd::LinSpaced(2001, -25.0, 25.0);
  Eigen::MatrixXd a = n;
  TansigInPlace(a);
  for (int i = 0; i < n.rows(); ++i) EXPECT_NEAR(a(i, 0), std::tanh(n(i, 0)), 3e-16) << n(i, 0);
  Eigen::MatrixXd m(4, 3);
  m << -800, 1e-300, 0.3, -1, -0.0, 20, 0.5, 800, std::numeric_limits<double>::infinity(), 7, 7, 7;
  Eigen::MatrixXd b = m;
  TansigInPlace(b.topRows(3));
  EXPECT_EQ(b(0, 0), -1.0);
  EXPECT_EQ(b(2, 1), 1.0);
  EXPECT_EQ(b(2, 2), 1.0);
  EXPECT_LE(std::abs(b(0, 1) - 1e-300), 1e-300);
  EXPECT_TRUE(std::signbit(b(1, 1)));
  EXPECT_NEAR(b(0, 2), std::tanh(0.3), 3e-16);
  EXPECT_EQ(b(3, 0), 7.0);  // row outside the block untouched
  Eigen::MatrixXd nan = Eigen::MatrixXd::Constant(1, 1, std::nan(""));
  TansigInPlace(nan);
  EXPECT_TRUE(std::isnan(nan(0, 0)));
}

TEST(FeedForwardNet, ForwardPassMatchesTheFormula) {
  const FeedForwardNet net = RandomNet(2, 5, 3);
  Eigen::MatrixXd X(4, 2);
  X << 0.1, -2, 1.5, 0.7, -2.9, 2.9, 0, 0;
  const Eigen::VectorXd y = net.Predict(X);
  const MinMaxMap& im = net.input_map();
  const MinMaxMap& om = net.output_map();
  for (int i = 0; i < 4; ++i) {
    double out = net.b2();
    for (int j = 0; j < 5; ++j) {
      double z = net.b1()(j);
      for (int k = 0; k < 2; ++k) z += net.IW()(j, k) * ((X(i, k) - im.xmin(k)) * im.gain(k) - 1.0);
      out += net.LW()(j) * std::tanh(z);
    }
    EXPECT_NEAR(y(i), om.xmin(0) + (out + 1.0) / om.gain(0), 1e-12) << "row " << i;
  }
}

// Central differences with step h have truncation error O(h²) and rounding O(ε/h); h = 1e-6 on
// O(1) weights leaves about 1e-8 relative error.
TEST(FeedForwardNet, JacobianMatchesCentralDifferences) {
  for (int inputs : {1, 3}) {
    FeedForwardNet net = RandomNet(inputs, 7, 11);
    // Moderate weights so the finite differences are well conditioned.
    Eigen::VectorXd w = net.params();
    w *= 0.3;
    net.set_params(w);
    const Eigen::MatrixXd Xn = Eigen::MatrixXd::Random(9, inputs);
    Eigen::VectorXd y(9);
    Eigen::MatrixXd J(9, net.num_params());
    net.JacobianNormalised(Xn, y, J);
    EXPECT_LT((y - net.PredictNormalised(Xn)).cwiseAbs().maxCoeff(), 1e-13);
    const double h = 1e-6;
    for (int p = 0; p < net.num_params(); ++p) {
      FeedForwardNet plus = net, minus = net;
      Eigen::VectorXd wp = w, wm = w;
      wp(p) += h;
      wm(p) -= h;
      plus.set_params(wp);
      minus.set_params(wm);
      const Eigen::VectorXd fd =
          (plus.PredictNormalised(Xn) - minus.PredictNormalised(Xn)) / (2 * h);
      const double scale = std::max(1.0, fd.cwiseAbs().maxCoeff());
      EXPECT_LT((J.col(p) - fd).cwiseAbs().maxCoeff(), 1e-7 * scale)
          << "inputs " << inputs << " param " << p;
    }
  }
}

TEST(FeedForwardNet, NguyenWidrowTilesTheInputRange) {
  FeedForwardNet net(FfnetShape{1, 10});
  std::mt19937_64 rng(5);
  net.InitNguyenWidrow(rng);
  // R = 1: |IW_j| = 2 · 0.7 · H, centres −b_j/IW_j evenly spaced over [−1, 1].
  for (int j = 0; j < 10; ++j) {
    EXPECT_DOUBLE_EQ(std::abs(net.IW()(j, 0)), 14.0);
    EXPECT_NEAR(-net.b1()(j) / net.IW()(j, 0), -(-1.0 + 2.0 * j / 9), 1e-12);
    EXPECT_LE(std::abs(net.LW()(j)), 1.0);
  }
  std::mt19937_64 rng2(5);
  FeedForwardNet again(FfnetShape{1, 10});
  again.InitNguyenWidrow(rng2);
  EXPECT_EQ(net.params(), again.params());
}

// The data-adaptive Nguyen–Widrow: λ = 0 is NW's tiling; λ > 0 moves centres into a narrow step of
// the target, but no neuron gets narrower than its minimum number of training samples.
TEST(FeedForwardNet, AdaptiveInitWithoutVariationWeightIsNguyenWidrowsTiling) {
  const int H = 10;
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(201, 0.0, 4.0);
  Eigen::VectorXd t = x.array().sin().matrix();
  FeedForwardNet net(FfnetShape{1, H});
  net.ConfigureMaps(x, t);
  std::mt19937_64 rng(3);
  net.InitAdaptive(rng, x, t, 0.0);
  std::vector<double> centres;
  for (int j = 0; j < H; ++j) {
    EXPECT_NEAR(std::abs(net.IW()(j, 0)), 2 * 0.7 * H, 1e-9);
    EXPECT_LE(std::abs(net.LW()(j)), 1.0);
    centres.push_back(-net.b1()(j) / net.IW()(j, 0));
  }
  std::sort(centres.begin(), centres.end());
  for (int j = 0; j < H; ++j)
    EXPECT_NEAR(centres[static_cast<size_t>(j)], -1.0 + 2.0 * j / (H - 1), 1e-12);
  // Deterministic for a seed; another seed flips other signs.
  FeedForwardNet again(FfnetShape{1, H}), other(FfnetShape{1, H});
  again.ConfigureMaps(x, t);
  other.ConfigureMaps(x, t);
  std::mt19937_64 rng3(3), rng4(4);
  again.InitAdaptive(rng3, x, t, 0.0);
  other.InitAdaptive(rng4, x, t, 0.0);
  EXPECT_EQ(net.params(), again.params());
  EXPECT_NE(net.params(), other.params());
}

TEST(FeedForwardNet, AdaptiveInitPutsNeuronsWhereTheTargetVaries) {
  // A fast first-order rise over the first 0.5 % of the range, then flat (the Dahl corner).
  const int H = 40;
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(2001, 0.0, 10.0);  // 0.001 apart once normalised
  Eigen::VectorXd t = (1.0 - (-x.array() / 0.01).exp()).matrix();
  FeedForwardNet net(FfnetShape{1, H});
  net.ConfigureMaps(x, t);
  std::mt19937_64 rng(1);
  net.InitAdaptive(rng, x, t, 0.5);
  int in_rise = 0;
  double min_abs_iw = 1e300, max_abs_iw = 0;
  for (int j = 0; j < H; ++j) {
    const double c = -net.b1()(j) / net.IW()(j, 0);  // normalised input; the rise is x̃ < −0.99
    in_rise += c < -0.99;
    min_abs_iw = std::min(min_abs_iw, std::abs(net.IW()(j, 0)));
    max_abs_iw = std::max(max_abs_iw, std::abs(net.IW()(j, 0)));
  }
  EXPECT_GE(in_rise, H / 2 - 1);
  EXPECT_LE(in_rise, H / 2 + 1);
  // The other half spreads evenly at half NW's density, so twice NW's width (|IW| = 1.4 H / 2).
  EXPECT_NEAR(min_abs_iw, 0.5 * 2 * 0.7 * H, 0.05 * 2 * 0.7 * H);
  // The active region |n| ≤ 2 is 4/|IW| wide: at least 10 samples (0.01), so |IW| ≤ 400 ...
  EXPECT_LE(max_abs_iw, 400.0 * (1 + 1e-12));
  EXPECT_GT(max_abs_iw, 399.0);  // ... and the crowded neurons are held at that floor
  // A smaller floor lets them be narrower.
  FeedForwardNet narrow(FfnetShape{1, H});
  narrow.ConfigureMaps(x, t);
  std::mt19937_64 rng2(1);
  narrow.InitAdaptive(rng2, x, t, 0.5, 2.0);
  EXPECT_GT(narrow.IW().cwiseAbs().maxCoeff(), 1000.0);
}

TEST(FeedForwardNet, AdaptiveInitRejectsBadInput) {
  Eigen::VectorXd x = Eigen::VectorXd::LinSpaced(11, 0.0, 1.0), t = x;
  FeedForwardNet net(FfnetShape{1, 4});
  net.ConfigureMaps(x, t);
  std::mt19937_64 rng(1);
  PZ_EXPECT_HAS(InputErrorOf([&] { net.InitAdaptive(rng, x, t, 1.5); }), "adaptive fraction = 1.5");
  PZ_EXPECT_HAS(InputErrorOf([&] { net.InitAdaptive(rng, x, t, 0.5, -1.0); }),
                "samples per neuron = -1");
  PZ_EXPECT_HAS(InputErrorOf([&] { net.InitAdaptive(rng, x, t.head(5), 0.5); }),
                "training targets = 5");
  PZ_EXPECT_HAS(InputErrorOf([&] { net.InitAdaptive(rng, x.head(1), t.head(1), 0.5); }),
                "training samples = 1");
  Eigen::VectorXd bad = t;
  bad(3) = std::nan("");
  PZ_EXPECT_HAS(InputErrorOf([&] { net.InitAdaptive(rng, x, bad, 0.5); }), "training sample 3");
  PZ_EXPECT_HAS(InputErrorOf([&] { net.InitAdaptive(rng, Eigen::VectorXd::Zero(11), t, 0.5); }),
                "training input range = 0");
  FeedForwardNet two(FfnetShape{2, 4});
  PZ_EXPECT_HAS(InputErrorOf([&] { two.InitAdaptive(rng, x, t, 0.5); }), "inputs = 2");
}

TEST(FeedForwardNet, RejectsBadShapesAndParameters) {
  PZ_EXPECT_HAS(InputErrorOf([] { FeedForwardNet(FfnetShape{0, 3}); }), "inputs = 0");
  PZ_EXPECT_HAS(InputErrorOf([] { FeedForwardNet(FfnetShape{1, 0}); }), "hidden = 0");
  FeedForwardNet net(FfnetShape{1, 3});
  PZ_EXPECT_HAS(InputErrorOf([&] { net.set_params(Eigen::VectorXd::Zero(5)); }), "params size = 5");
  Eigen::VectorXd w = Eigen::VectorXd::Zero(net.num_params());
  w(2) = std::nan("");
  PZ_EXPECT_HAS(InputErrorOf([&] { net.set_params(w); }), "params[2]");
  PZ_EXPECT_HAS(InputErrorOf([&] { (void)net.Predict(Eigen::MatrixXd::Zero(2, 2)); }),
                "input columns = 2");
}

TEST(DenseKernels, SyrkGemmAndCholeskyAgreeWithEigen) {
  const Eigen::MatrixXd J = Eigen::MatrixXd::Random(57, 13);
  Eigen::MatrixXd C = Eigen::MatrixXd::Constant(13, 13, 7.0);
  SyrkTnLower(J, 2.0, 0.0, C);
  const Eigen::MatrixXd ref = 2.0 * J.transpose() * J;
  EXPECT_LT((C.triangularView<Eigen::Lower>().toDenseMatrix() -
             ref.triangularView<Eigen::Lower>().toDenseMatrix())
                .cwiseAbs()
                .maxCoeff(),
            1e-12);
  EXPECT_EQ(C(0, 12), 7.0);                 // upper triangle untouched
  SyrkTnLower(J.topRows(20), 1.0, 1.0, C);  // accumulate a block with a row stride
  const Eigen::MatrixXd ref2 = ref + J.topRows(20).transpose() * J.topRows(20);
  EXPECT_LT((C.triangularView<Eigen::Lower>().toDenseMatrix() -
             ref2.triangularView<Eigen::Lower>().toDenseMatrix())
                .cwiseAbs()
                .maxCoeff(),
            1e-12);

  const Eigen::MatrixXd B = Eigen::MatrixXd::Random(57, 4);
  Eigen::MatrixXd G(13, 4);
  GemmTn(J, B, 1.0, 0.0, G);
  EXPECT_LT((G - J.transpose() * B).cwiseAbs().maxCoeff(), 1e-12);

  Eigen::MatrixXd A = ref + Eigen::MatrixXd::Identity(13, 13);
  Eigen::MatrixXd L = A;
  double rcond = 0;
  ASSERT_TRUE(CholeskyLower(L, &rcond));
  EXPECT_GT(rcond, 1e-6);
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(13, -1, 1), x = b;
  CholeskySolve(L, x);
  EXPECT_LT((A * x - b).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_NEAR(CholeskyInverseTrace(L), A.inverse().trace(), 1e-10);
  Eigen::MatrixXd indefinite = -Eigen::MatrixXd::Identity(3, 3);
  EXPECT_FALSE(CholeskyLower(indefinite));
}

}  // namespace
}  // namespace pz::model
