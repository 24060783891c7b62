// The noise floor of a bench case (records/noise_floor.h): rounding, scatter of the last two
// cycles, saturation plateaus, on series whose answers are known in closed form. The floor of
// record sets (EstimateNoiseFloor) is tested on synthetic records in diagnose_test.cc and
// reallike_test.cc.
#include <gtest/gtest.h>

#include <cmath>
#include <span>
#include <vector>

#include "records/noise_floor.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/series.h"

namespace pz::records {
namespace {

using pz::testing::Quantise;
using pz::testing::Sine;
constexpr double kQ = pz::testing::kEncoderQuantum;

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
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { PeriodDifferenceSquares(y, 200, 50); }),
                "the series has 250");
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { PeriodDifferenceSquares(y, 0, 1); }),
                "periods of 1 samples");
}

TEST(NoiseFloorTest, SaturatedSamplesContributeTheirRoundingOnly) {
  CaseNoise n;
  n.quantum_deg = kQ;
  n.floor_rms_deg = 0.01;
  const std::vector<double> model = {1.0, 1.0, 1.0, 0.5, 0.2};  // first three clipped at b1 = 1
  const std::vector<double> meas = {1.0 - kQ, 1.0, 1.0 - 3 * kQ, 0.5,
                                    0.21};  // one level below; three below
  const double f = SaturationAwareFloor(n, meas, model, 1.0, -1.0);
  EXPECT_NEAR(f, std::sqrt((kQ * kQ + 0 + 3 * 0.01 * 0.01) / 5), 1e-12);
  PZ_EXPECT_HAS(pz::testing::InputErrorOf(
                    [&] { SaturationAwareFloor(n, meas, std::vector<double>{1.0}, 1.0, -1.0); }),
                "measured has 5");
}

}  // namespace
}  // namespace pz::records
