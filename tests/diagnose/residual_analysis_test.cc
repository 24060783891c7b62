// Noise floor (model/noise_floor.h) and residual localisation (model/residual_analysis.h) on
// residual patterns whose answers are known in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "model/noise_floor.h"
#include "model/residual_analysis.h"
#include "tests/testing/expect_error.h"

namespace pz::model {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kQ = 360.0 / 8192;  // the bench encoder's quantum [deg]

std::vector<double> Quantise(const std::vector<double>& y, double q) {
  std::vector<double> r;
  for (double v : y) r.push_back(q * std::round(v / q));
  return r;
}

std::vector<double> Sine(int n, double f, double a, double phase = 0) {
  std::vector<double> y;
  for (int k = 0; k < n; ++k) y.push_back(a * std::sin(2 * kPi * f * k / 100.0 - phase));
  return y;
}

TEST(NoiseFloorTest, QuantumIsTheGridOfTheReadings) {
  EXPECT_DOUBLE_EQ(EstimateQuantum(Quantise(Sine(600, 0.5, 2.0), kQ)), kQ);
  // A grid whose smallest visited step is two quanta still gives the quantum if some value is odd.
  EXPECT_DOUBLE_EQ(EstimateQuantum(std::vector<double>{0, 2 * kQ, 5 * kQ, 9 * kQ}), kQ);
  EXPECT_EQ(EstimateQuantum(Sine(600, 0.5, 2.0)), 0.0);  // continuous data
  EXPECT_EQ(EstimateQuantum(std::vector<double>{1.0, 1.0}), 0.0);
  // A recorder's export: a 2^-17 mm grid printed with 7 decimals (-1.6174316 µm …) over ±40 µm.
  const double q = 1000.0 / 131072.0;
  std::vector<double> printed;
  for (double x : Sine(5000, 0.5, 40.0)) printed.push_back(std::round(std::round(x / q) * q * 1e7) / 1e7);
  EXPECT_NEAR(EstimateQuantum(printed), q, 1e-7 * q);
  // Continuous data printed with 7 decimals is not on a grid.
  std::vector<double> rounded;
  for (double x : Sine(5000, 0.5, 40.0)) rounded.push_back(std::round(x * 1e7) / 1e7);
  EXPECT_EQ(EstimateQuantum(rounded), 0.0);
}

TEST(NoiseFloorTest, PeriodicQuantisedRecordHasTheQuantisationFloor) {
  const CaseNoise n = EstimateCaseNoise(Quantise(Sine(600, 0.5, 2.0), kQ), 3);
  EXPECT_DOUBLE_EQ(n.quantum_deg, kQ);
  EXPECT_NEAR(n.scatter_rms_deg, 0.0, 1e-12);  // identical cycles
  EXPECT_NEAR(n.floor_rms_deg, kQ / std::sqrt(12.0), 1e-12);
}

TEST(NoiseFloorTest, FloorAddsRoundingAndScatter) {
  std::vector<double> y = Sine(300, 1.0, 2.0);
  for (size_t k = 200; k < 300; ++k) y[k] += (k % 2 ? 0.005 : -0.005);
  EXPECT_NEAR(EstimateCaseNoise(y, 3, 0.0).floor_rms_deg, 0.005, 1e-3);  // continuous: the scatter
  const CaseNoise n = EstimateCaseNoise(y, 3, kQ);
  EXPECT_NEAR(n.floor_rms_deg, std::hypot(kQ / std::sqrt(12.0), n.scatter_rms_deg), 1e-12);
}

TEST(NoiseFloorTest, ScatterSeesJitterButNotASlowTrend) {
  // Continuous data: alternating ±s jitter on the last cycle only, plus a slow drift.
  std::vector<double> y = Sine(300, 1.0, 2.0);
  for (size_t k = 0; k < y.size(); ++k) y[k] += 0.05 * k / 100.0;  // drift between cycles
  const CaseNoise clean = EstimateCaseNoise(y, 3, 0.0);
  EXPECT_LT(clean.scatter_rms_deg, 1e-4);  // the drift drops out
  for (size_t k = 200; k < 300; ++k) y[k] += (k % 2 ? 0.01 : -0.01);
  const CaseNoise jit = EstimateCaseNoise(y, 3, 0.0);
  EXPECT_NEAR(jit.scatter_rms_deg, 0.01, 2e-3);  // d has ±0.01 steps: var(Δd)/4 = 0.01²
}

TEST(NoiseFloorTest, PeriodDifferenceIsTheScatterOfAnyTwoPeriods) {
  // A periodic signal with a slow drift, ±0.01 jitter on the period starting at 120 (period 50):
  // 49 terms of (±0.02)² from the jitter alone, whatever comes before the periods compared.
  std::vector<double> y = Sine(250, 2.0, 1.5);
  for (size_t k = 0; k < y.size(); ++k) y[k] += 0.03 * k / 100.0;
  EXPECT_LT(PeriodDifferenceSquares(y, 70, 50), 1e-12);
  for (size_t k = 120; k < 170; ++k) y[k] += (k % 2 ? 0.01 : -0.01);
  EXPECT_NEAR(PeriodDifferenceSquares(y, 70, 50), 49 * 0.02 * 0.02, 1e-9);
  // The bench's scatter is the last two cycles of it.
  EXPECT_DOUBLE_EQ(EstimateCaseNoise(std::span<const double>(y).first(200), 4, 0.0).scatter_rms_deg,
                   std::sqrt(PeriodDifferenceSquares(y, 100, 50) / 49 / 4.0));
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { PeriodDifferenceSquares(y, 200, 50); }), "the series has 250");
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { PeriodDifferenceSquares(y, 0, 1); }), "periods of 1 samples");
}

TEST(NoiseFloorTest, SaturatedSamplesContributeTheirRoundingOnly) {
  CaseNoise n;
  n.quantum_deg = kQ;
  n.floor_rms_deg = 0.01;
  const std::vector<double> model = {1.0, 1.0, 1.0, 0.5, 0.2};             // first three clipped at b1 = 1
  const std::vector<double> meas = {1.0 - kQ, 1.0, 1.0 - 3 * kQ, 0.5, 0.21};  // one level below; three below
  const double f = SaturationAwareFloor(n, meas, model, 1.0, -1.0);
  EXPECT_NEAR(f, std::sqrt((kQ * kQ + 0 + 3 * 0.01 * 0.01) / 5), 1e-12);
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { SaturationAwareFloor(n, meas, std::vector<double>{1.0}, 1.0, -1.0); }),
                "measured has 5");
}

ResidualCaseInput Input(const std::vector<double>& meas, const std::vector<double>& model, double f = 0.5) {
  ResidualCaseInput in;
  in.number = 1;
  in.amplitude_v = 500;
  in.frequency_hz = f;
  in.sample_rate_hz = 100;
  in.cycles = 3;
  in.measured = meas;
  in.model = model;
  in.floor_rms_deg = 0.01;
  in.quantum_deg = 0;
  return in;
}

TEST(ResidualAnalysisTest, EvenHarmonicResidualIsSeenAsAsymmetry) {
  const std::vector<double> model = Sine(600, 0.5, 1.0);
  std::vector<double> meas = model;
  for (size_t k = 0; k < meas.size(); ++k) meas[k] += 0.02 * std::cos(2 * 2 * kPi * 0.5 * k / 100.0);
  const ResidualAnalysis a = AnalyseResiduals(std::vector<ResidualCaseInput>{Input(meas, model)});
  const CaseResidual& c = a.cases[0];
  EXPECT_NEAR(c.harmonic[2], 0.02, 1e-9);
  EXPECT_NEAR(c.even_rms, 0.02 / std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(c.odd_rms, 0.0, 1e-9);
  EXPECT_NEAR(c.low_rms, 0.0, 1e-9);
  EXPECT_NEAR(c.rms, 0.02 / std::sqrt(2.0), 1e-9);
  EXPECT_NEAR(c.rms_over_floor, 0.02 / std::sqrt(2.0) / 0.01, 1e-9);
}

TEST(ResidualAnalysisTest, DriftIsATrendAndLowFrequencyContent) {
  const std::vector<double> model = Sine(600, 0.5, 1.0);
  std::vector<double> meas = model;
  for (size_t k = 0; k < meas.size(); ++k) meas[k] += 0.004 * k / 100.0;
  const ResidualAnalysis a = AnalyseResiduals(std::vector<ResidualCaseInput>{Input(meas, model)});
  const CaseResidual& c = a.cases[0];
  EXPECT_NEAR(c.trend_deg_per_s, 0.004, 1e-9);
  EXPECT_GT(c.low_rms, 0.01);
  ASSERT_EQ(c.cycle_mean.size(), 3u);
  EXPECT_LT(c.cycle_mean[0], c.cycle_mean[1]);
  EXPECT_LT(c.cycle_mean[1], c.cycle_mean[2]);
}

TEST(ResidualAnalysisTest, TransientOnlyResidualSitsInTheFirstCycle) {
  const std::vector<double> model = Sine(300, 1.0, 1.0);
  std::vector<double> meas = model;
  for (int k = 0; k < 100; ++k) meas[k] += 0.05 * std::exp(-k / 20.0);
  const ResidualAnalysis a = AnalyseResiduals(std::vector<ResidualCaseInput>{Input(meas, model, 1.0)});
  EXPECT_GT(a.cases[0].first_cycle.rms, 0.01);
  EXPECT_NEAR(a.cases[0].later_cycles.rms, 0.0, 1e-12);
}

TEST(ResidualAnalysisTest, LoopOfALaggedSineHasItsClosedFormWidthAreaAndLag) {
  const double a = 1.5, phi = 0.3, v = 500;
  const std::vector<double> y = Sine(600, 0.5, a, phi);
  const LoopFeatures l = ComputeLoop(y, v, 0.5, 100, 3, 0);
  EXPECT_NEAR(l.phase_lag_deg, phi * 180 / kPi, 1e-6);
  EXPECT_NEAR(l.fundamental_deg, a, 1e-9);
  EXPECT_NEAR(l.width_deg, 2 * a * std::sin(phi), 1e-3);
  EXPECT_NEAR(l.area_deg_v, kPi * v * a * std::sin(phi), 0.01 * kPi * v * a * std::sin(phi));
  EXPECT_NEAR(l.offset_deg, 0.0, 1e-3);
}

TEST(ResidualAnalysisTest, GroupsSplitTrainingAndWithheldAndSharesSumToOne) {
  const std::vector<double> model = Sine(300, 1.0, 1.0);
  std::vector<double> m1 = model, m2 = model;
  for (auto& v : m1) v += 0.01;
  for (auto& v : m2) v -= 0.03;
  ResidualCaseInput a = Input(m1, model, 1.0), b = Input(m2, model, 1.0);
  a.training = true;
  b.number = 2;
  const ResidualAnalysis r = AnalyseResiduals(std::vector<ResidualCaseInput>{a, b});
  EXPECT_NEAR(r.cases[0].share + r.cases[1].share, 1.0, 1e-12);
  EXPECT_NEAR(r.training.rms, 0.01, 1e-12);
  EXPECT_NEAR(r.withheld.rms, 0.03, 1e-12);
  EXPECT_EQ(r.withheld.worst_case, 2);
  EXPECT_FALSE(r.findings.empty());
  const std::vector<double> short_model(5, 0.0);
  PZ_EXPECT_HAS(pz::testing::InputErrorOf(
                    [&] { AnalyseResiduals(std::vector<ResidualCaseInput>{Input(m1, short_model)}); }),
                "case 1");
}

}  // namespace
}  // namespace pz::model
