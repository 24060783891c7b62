// The HGANN network: transfer functions at their edge points (MATLAB definitions, spec table),
// output scaling onto the parameter ranges, validation messages, and the paper's Appendix D 2-3-7
// network run forward and checked against a hand computation.
#include "model/network.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace pz::model {
namespace {

using TF = TransferFunction;
constexpr double kTight = 1e-15;  // pure arithmetic, a few roundings at most

TEST(TransferFunctions, ValuesAtZeroAndPlusMinusOne) {
  struct Row {
    TF tf;
    double at_minus1, at_0, at_plus1;
  };
  const Row rows[] = {
      {TF::kHardlim, 0, 1, 1},
      {TF::kHardlims, -1, 1, 1},
      {TF::kSatlin, 0, 0, 1},
      {TF::kSatlins, -1, 0, 1},
      {TF::kTribas, 0, 1, 0},
      {TF::kTansig, -std::tanh(1.0), 0, std::tanh(1.0)},
      {TF::kLogsig, 1 / (1 + std::exp(1.0)), 0.5, 1 / (1 + std::exp(-1.0))},
      {TF::kRadbas, std::exp(-1.0), 1, std::exp(-1.0)},
  };
  for (const Row& r : rows) {
    SCOPED_TRACE(TransferFunctionName(r.tf));
    EXPECT_NEAR(ApplyTransfer(r.tf, -1), r.at_minus1, kTight);
    EXPECT_NEAR(ApplyTransfer(r.tf, 0), r.at_0, kTight);
    EXPECT_NEAR(ApplyTransfer(r.tf, 1), r.at_plus1, kTight);
  }
}

TEST(TransferFunctions, InteriorPointsAndSaturation) {
  EXPECT_EQ(ApplyTransfer(TF::kSatlin, 0.25), 0.25);
  EXPECT_EQ(ApplyTransfer(TF::kSatlins, -0.25), -0.25);
  EXPECT_EQ(ApplyTransfer(TF::kTribas, -0.25), 0.75);
  EXPECT_EQ(ApplyTransfer(TF::kTribas, 1.5), 0.0);
  EXPECT_EQ(ApplyTransfer(TF::kHardlim, -1e-300), 0.0);
  EXPECT_EQ(ApplyTransfer(TF::kHardlims, -0.0), 1.0);  // −0 ≥ 0
  for (int c = 0; c < kNumTransferFunctions; ++c) {
    const TF tf = TransferFromCode(c);
    const TransferRange r = RangeOf(tf);
    for (double n : {-1e6, -50.0, -3.0, 3.0, 50.0, 1e6}) {
      const double v = ApplyTransfer(tf, n);
      EXPECT_TRUE(std::isfinite(v)) << TransferFunctionName(tf) << " at " << n;
      EXPECT_GE(v, r.lo) << TransferFunctionName(tf) << " at " << n;
      EXPECT_LE(v, r.hi) << TransferFunctionName(tf) << " at " << n;
    }
  }
  EXPECT_EQ(ApplyTransfer(TF::kTansig, -1e6), -1.0);
  EXPECT_EQ(ApplyTransfer(TF::kLogsig, -1e6), 0.0);
}

TEST(TransferFunctions, NamesCodesAndRanges) {
  const char* names[] = {"hardlim", "hardlims", "satlin", "satlins",
                         "tribas",  "tansig",   "logsig", "radbas"};
  for (int c = 0; c < kNumTransferFunctions; ++c) {
    EXPECT_STREQ(TransferFunctionName(TransferFromCode(c)), names[c]);
    TF parsed;
    ASSERT_TRUE(ParseTransferFunction(names[c], &parsed));
    EXPECT_EQ(static_cast<int>(parsed), c);
  }
  TF unused;
  EXPECT_FALSE(ParseTransferFunction("purelin", &unused));
  EXPECT_FALSE(IsValidTransferCode(8));
  EXPECT_FALSE(IsValidTransferCode(-1));
  EXPECT_EQ(RangeOf(TF::kHardlims).lo, -1);
  EXPECT_EQ(RangeOf(TF::kTansig).lo, -1);
  EXPECT_EQ(RangeOf(TF::kSatlins).lo, -1);
  EXPECT_EQ(RangeOf(TF::kRadbas).lo, 0);
}

TEST(ParameterRanges, DefaultsAndPaperPreset) {
  const ParameterRanges d;
  EXPECT_EQ(d.mu, (ParameterRange{0, 300}));
  EXPECT_EQ(d.delta, (ParameterRange{0, 1}));
  EXPECT_EQ(d.alpha, (ParameterRange{0, 0.01}));
  EXPECT_EQ(d.beta, (ParameterRange{0, 0.02}));
  EXPECT_EQ(d.gamma, (ParameterRange{-0.02, 0.02}));
  EXPECT_EQ(d.a1, (ParameterRange{0, 2}));
  EXPECT_EQ(d.a2, (ParameterRange{0, 2}));
  EXPECT_TRUE(d.Validate().ok());
  const ParameterRanges p = ParameterRanges::PaperTable3();
  EXPECT_EQ(p.alpha, (ParameterRange{-0.1, 0}));
  EXPECT_EQ(p.beta, (ParameterRange{-0.1, 0}));
  EXPECT_EQ(p.gamma, (ParameterRange{-0.1, 0}));
  EXPECT_EQ(p.mu, (ParameterRange{0, 300}));
  EXPECT_TRUE(p.Validate().ok());
  EXPECT_EQ(&d[0], &d.mu);
  EXPECT_EQ(&d[6], &d.a2);
}

TEST(ParameterRanges, ValidateNamesTheField) {
  ParameterRanges r;
  r.alpha.upper = std::numeric_limits<double>::quiet_NaN();
  Status s = r.Validate();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("ranges.alpha.upper"), std::string::npos) << s.message();
  r = ParameterRanges{};
  r.beta = {0.5, 0.1};
  s = r.Validate();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("ranges.beta.upper"), std::string::npos) << s.message();
  r = ParameterRanges{};
  r.a1 = {1, 1};  // a fixed parameter is allowed
  EXPECT_TRUE(r.Validate().ok());
}

TEST(InputNormalization, FromCasesUsesMinAndMax) {
  const double v[] = {375, 500, 500, 750};
  const double f[] = {0.25, 0.5, 1.0, 0.25};
  const InputNormalization n = InputNormalization::FromCases(v, f);
  EXPECT_EQ(n.amplitude_lo_v, 375);
  EXPECT_EQ(n.amplitude_hi_v, 750);
  EXPECT_EQ(n.frequency_lo_hz, 0.25);
  EXPECT_EQ(n.frequency_hi_hz, 1.0);
  EXPECT_EQ(n.NormalizeAmplitude(750), 1.0);
  EXPECT_EQ(n.NormalizeFrequency(0.25), 0.0);
  EXPECT_TRUE(n.Validate().ok());
  // One case: widened to [v, v + 1], x = 0.
  const double v1[] = {500}, f1[] = {0.5};
  const InputNormalization one = InputNormalization::FromCases(v1, f1);
  EXPECT_EQ(one.amplitude_hi_v, 501);
  EXPECT_EQ(one.NormalizeFrequency(0.5), 0.0);
  EXPECT_THROW(InputNormalization::FromCases({}, {}), InputError);
  const double bad[] = {std::numeric_limits<double>::infinity()};
  EXPECT_THROW(InputNormalization::FromCases(bad, f1), InputError);
  InputNormalization inverted;
  inverted.frequency_hi_hz = -1;
  const Status s = inverted.Validate();
  EXPECT_NE(s.message().find("normalization.frequency_hi_hz"), std::string::npos) << s.message();
}

// A 2-2-7 network whose outputs are pinned by their biases (zero weights).
Network BiasOnlyNetwork(TF output_tf, double bias) {
  Network n;
  n.input_tf = {TF::kSatlin, TF::kSatlin};
  n.hidden_tf = {TF::kSatlin, TF::kSatlin};
  n.output_tf.fill(output_tf);
  n.w1 = Eigen::MatrixXd::Zero(2, 2);
  n.c1 = Eigen::VectorXd::Zero(2);
  n.w2 = Eigen::MatrixXd::Zero(2, 7);
  n.c2 = Eigen::VectorXd::Constant(7, bias);
  return n;
}

TEST(Network, OutputsMapOntoTheParameterRanges) {
  // hardlims: −1 → lower, +1 → upper.
  Network lo = BiasOnlyNetwork(TF::kHardlims, -5);
  Network hi = BiasOnlyNetwork(TF::kHardlims, 5);
  ASSERT_TRUE(lo.Validate().ok());
  const ParameterRanges r;
  const auto p_lo = lo.Predict(400, 0.5).ToArray();
  const auto p_hi = hi.Predict(400, 0.5).ToArray();
  for (int k = 0; k < kNetworkOutputs; ++k) {
    EXPECT_EQ(p_lo[k], r[k].lower) << OutputName(k);
    EXPECT_EQ(p_hi[k], r[k].upper) << OutputName(k);
  }
  // tansig(0) = 0 is the middle of [−1, 1]; logsig(0) = 0.5 the middle of [0, 1].
  for (TF tf : {TF::kTansig, TF::kLogsig}) {
    const NetworkParameters mid = BiasOnlyNetwork(tf, 0).Predict(400, 0.5);
    EXPECT_NEAR(mid.mu, 150, 1e-12);
    EXPECT_NEAR(mid.gamma, 0, 1e-17);
    EXPECT_NEAR(mid.a2, 1, 1e-15);
  }
}

TEST(Network, ValidateNamesTheField) {
  Network n = BiasOnlyNetwork(TF::kSatlin, 0);
  n.w2(1, 4) = std::numeric_limits<double>::quiet_NaN();
  Status s = n.Validate();
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("w2(1, 4)"), std::string::npos) << s.message();
  n = BiasOnlyNetwork(TF::kSatlin, 0);
  n.c1.resize(3);
  s = n.Validate();
  EXPECT_NE(s.message().find("c1 shape"), std::string::npos) << s.message();
  n = BiasOnlyNetwork(TF::kSatlin, 0);
  n.output_tf[3] = static_cast<TF>(11);
  s = n.Validate();
  EXPECT_NE(s.message().find("output_tf[3]"), std::string::npos) << s.message();
  n = BiasOnlyNetwork(TF::kSatlin, 0);
  n.hidden_tf.assign(10, TF::kSatlin);
  s = n.Validate();
  EXPECT_NE(s.message().find("2 … 9"), std::string::npos) << s.message();
  n = BiasOnlyNetwork(TF::kSatlin, 0);
  EXPECT_THROW(n.Predict(std::numeric_limits<double>::quiet_NaN(), 1), InputError);
}

// Appendix D of the paper: the trained 2-3-7 network. The output layer lists its weights in the
// order a1, a2, α, β, γ, δ, μ; the transcription of the output TFs is incomplete (five names for
// seven nodes), so the output TFs here are our choice — the point is the forward pass, which is
// checked against the equations written out by hand, not the paper's Table 6.
Network AppendixDNetwork() {
  Network n;
  n.input_tf = {TF::kSatlin, TF::kTribas};
  n.hidden_tf = {TF::kTribas, TF::kSatlins, TF::kTansig};
  n.w1.resize(2, 3);
  n.w1 << -0.4275, 0.4876, -0.2992,  //
      0.3023, -0.1596, -0.4471;
  n.c1.resize(3);
  n.c1 << -0.9587, 0.6075, 0.1368;
  // Paper rows (per output, paper order a1, a2, α, β, γ, δ, μ), columns = hidden nodes.
  const double paper_w2[7][3] = {{0.4087, -0.1336, 0.6655},   {-0.7645, 0.7950, 0.8903},
                                 {-0.0727, -0.8490, -0.0146}, {0.5457, -0.7805, -0.6846},
                                 {0.2659, -0.4597, 0.3016},   {0.9394, -0.7958, -0.0425},
                                 {0.5949, -0.9322, 0.8555}};
  const double paper_c2[7] = {0.1787, -0.5144, -0.1008, -0.3780, 0.1154, 0.7307, 0.0825};
  const TF paper_tf[7] = {TF::kSatlin, TF::kSatlin, TF::kHardlim, TF::kSatlin,
                          TF::kSatlin, TF::kLogsig, TF::kLogsig};
  // Our output order μ, δ, α, β, γ, a1, a2 → paper row.
  const int paper_row[7] = {6, 5, 2, 3, 4, 0, 1};
  n.w2.resize(3, 7);
  n.c2.resize(7);
  for (int k = 0; k < 7; ++k) {
    for (int j = 0; j < 3; ++j) n.w2(j, k) = paper_w2[paper_row[k]][j];
    n.c2(k) = paper_c2[paper_row[k]];
    n.output_tf[k] = paper_tf[paper_row[k]];
  }
  // Training cases 1, 5, 6, 7: V ∈ {375, 500, 750}, f ∈ {0.25, 0.5, 1}.
  const double v[] = {375, 500, 500, 750}, f[] = {0.25, 0.5, 1.0, 0.25};
  n.normalization = InputNormalization::FromCases(v, f);
  n.ranges = ParameterRanges::PaperTable3();
  return n;
}

TEST(Network, AppendixDForwardPassMatchesHandComputation) {
  const Network n = AppendixDNetwork();
  ASSERT_TRUE(n.Validate().ok()) << n.Validate().message();
  EXPECT_EQ(n.Describe(),
            "2-3-7 in[satlin,tribas] hidden[tribas,satlins,tansig] "
            "out[logsig,logsig,hardlim,satlin,satlin,satlin,satlin]");
  // Case 5: 500 V, 0.5 Hz. x = ((500 − 375)/375, (0.5 − 0.25)/0.75) = (1/3, 1/3).
  const NetworkActivations act = n.Forward(500, 0.5);
  const double x = 1.0 / 3.0;
  EXPECT_NEAR(act.x(0), x, kTight);
  EXPECT_NEAR(act.x(1), x, kTight);
  const double a1 = x;      // satlin(1/3)
  const double a2 = 1 - x;  // tribas(1/3)
  EXPECT_NEAR(act.a(0), a1, kTight);
  EXPECT_NEAR(act.a(1), a2, kTight);
  // Hidden: n_j = A1 W1(0, j) + A2 W1(1, j) + c1_j.
  const double n1 = a1 * -0.4275 + a2 * 0.3023 - 0.9587;   // = −0.89966…
  const double n2 = a1 * 0.4876 + a2 * -0.1596 + 0.6075;   // = 0.66363…
  const double n3 = a1 * -0.2992 + a2 * -0.4471 + 0.1368;  // = −0.261
  const double b1 = 1 - std::abs(n1);                      // tribas, |n1| ≤ 1
  const double b2 = n2;                                    // satlins, |n2| < 1
  const double b3 = std::tanh(n3);                         // tansig ≡ tanh
  EXPECT_NEAR(b1, 0.1003333333333333, 1e-13);
  EXPECT_NEAR(b2, 0.6636333333333333, 1e-13);
  EXPECT_NEAR(b3, std::tanh(-0.261), 1e-13);
  EXPECT_NEAR(act.b(0), b1, kTight);
  EXPECT_NEAR(act.b(1), b2, kTight);
  EXPECT_NEAR(act.b(2), b3, 1e-15);
  // Outputs, paper order a1, a2, α, β, γ, δ, μ: O = TF(B · W2 + c2), then mapped on Table 3.
  auto dot = [&](double w1, double w2, double w3, double c) {
    return b1 * w1 + b2 * w2 + b3 * w3 + c;
  };
  auto satlin = [](double v) { return std::clamp(v, 0.0, 1.0); };
  auto logsig = [](double v) { return 1 / (1 + std::exp(-v)); };
  const double o_a1 = satlin(dot(0.4087, -0.1336, 0.6655, 0.1787));
  const double o_a2 = satlin(dot(-0.7645, 0.7950, 0.8903, -0.5144));
  const double o_alpha = dot(-0.0727, -0.8490, -0.0146, -0.1008) >= 0 ? 1.0 : 0.0;
  const double o_beta = satlin(dot(0.5457, -0.7805, -0.6846, -0.3780));
  const double o_gamma = satlin(dot(0.2659, -0.4597, 0.3016, 0.1154));
  const double o_delta = logsig(dot(0.9394, -0.7958, -0.0425, 0.7307));
  const double o_mu = logsig(dot(0.5949, -0.9322, 0.8555, 0.0825));
  const NetworkParameters& p = act.parameters;
  EXPECT_NEAR(p.mu, 0 + o_mu * 300, 1e-12);
  EXPECT_NEAR(p.delta, 0 + o_delta * 1, 1e-15);
  EXPECT_NEAR(p.alpha, -0.1 + o_alpha * 0.1, 1e-16);
  EXPECT_NEAR(p.beta, -0.1 + o_beta * 0.1, 1e-16);
  EXPECT_NEAR(p.gamma, -0.1 + o_gamma * 0.1, 1e-16);
  EXPECT_NEAR(p.a1, 0 + o_a1 * 2, 1e-15);
  EXPECT_NEAR(p.a2, 0 + o_a2 * 2, 1e-15);
  // Spot values: α's hardlim sees a negative sum → lower bound; β's satlin saturates at 0.
  EXPECT_EQ(p.alpha, -0.1);
  EXPECT_EQ(p.beta, -0.1);
  EXPECT_EQ(n.Predict(500, 0.5), p);
}

TEST(Network, EqualityIsExact) {
  const Network a = AppendixDNetwork();
  Network b = a;
  EXPECT_TRUE(a == b);
  b.w2(2, 6) = std::nextafter(b.w2(2, 6), 1.0);
  EXPECT_FALSE(a == b);
  b = a;
  b.hidden_tf.push_back(TF::kRadbas);
  EXPECT_FALSE(a == b);
}

}  // namespace
}  // namespace pz::model
