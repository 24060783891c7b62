// Residual localisation (model/residual_analysis.h) on residual patterns whose answers are known
// in closed form.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "model/residual_analysis.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/series.h"

namespace pz::model {
namespace {

constexpr double kPi = std::numbers::pi;
using pz::testing::Sine;

ResidualCaseInput Input(const std::vector<double>& meas, const std::vector<double>& model,
                        double f = 0.5) {
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
  for (size_t k = 0; k < meas.size(); ++k)
    meas[k] += 0.02 * std::cos(2 * 2 * kPi * 0.5 * k / 100.0);
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
  const ResidualAnalysis a =
      AnalyseResiduals(std::vector<ResidualCaseInput>{Input(meas, model, 1.0)});
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
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] {
                  AnalyseResiduals(std::vector<ResidualCaseInput>{Input(m1, short_model)});
                }),
                "case 1");
}

}  // namespace
}  // namespace pz::model
