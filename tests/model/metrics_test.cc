// Metrics on hand-computed series, and the messages for misaligned or non-finite inputs.
#include "model/metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "tests/testing/expect_error.h"

namespace pz::model {
namespace {

using pz::testing::InputErrorOf;

constexpr double kTight = 1e-12;

// measured − model = e = {1, −2, 0, 3}; Σe² = 14, N = 4, max |e| = 3 at index 3.
const std::vector<double> kMeasured = {1, 0, 2, 5};
const std::vector<double> kModel = {0, 2, 2, 2};

TEST(PointMetrics, MatchHandComputedValues) {
  EXPECT_NEAR(PerformanceIndex(kMeasured, kModel), 14.0, kTight);
  EXPECT_NEAR(MeanSquaredError(kMeasured, kModel), 3.5, kTight);
  EXPECT_NEAR(RootMeanSquaredError(kMeasured, kModel), std::sqrt(3.5), kTight);
  EXPECT_NEAR(MaxAbsError(kMeasured, kModel), 3.0, kTight);
  // ȳ = 2, Σ(y − ȳ)² = 1 + 4 + 0 + 9 = 14 → R² = 1 − 14/14 = 0.
  EXPECT_NEAR(RSquared(kMeasured, kModel), 0.0, kTight);
  const ErrorMetrics m = CompareSeries(kMeasured, kModel);
  EXPECT_EQ(m.n, 4u);
  EXPECT_EQ(m.max_abs_index, 3u);
  EXPECT_NEAR(m.pi, 14.0, kTight);
  EXPECT_NEAR(m.rmse, std::sqrt(3.5), kTight);
}

TEST(PointMetrics, PerfectModelHasZeroErrorAndUnitRSquared) {
  const ErrorMetrics m = CompareSeries(kMeasured, kMeasured);
  EXPECT_EQ(m.pi, 0.0);
  EXPECT_EQ(m.max_abs, 0.0);
  EXPECT_EQ(m.r2, 1.0);
}

TEST(PointMetrics, ConstantMeasuredSeriesLeavesRSquaredUndefined) {
  const std::vector<double> flat = {2, 2, 2};
  const std::vector<double> model = {1, 2, 3};
  EXPECT_TRUE(std::isnan(CompareSeries(flat, model).r2));
  PZ_EXPECT_HAS(InputErrorOf([&] { (void)RSquared(flat, model); }), "constant");
}

TEST(PointMetrics, LengthMismatchNamesBothLengths) {
  const std::vector<double> shorter = {1, 2, 3};
  PZ_EXPECT_HAS(InputErrorOf([&] { (void)PerformanceIndex(kMeasured, shorter); }),
                "measured has 4 samples but model has 3");
  EXPECT_EQ(CheckAligned(kMeasured, shorter).code(), StatusCode::kInvalidArgument);
  EXPECT_FALSE(CheckAligned({}, {}).ok());
}

TEST(PointMetrics, NonFiniteValueIsNamedByIndex) {
  std::vector<double> model = kModel;
  model[2] = std::numeric_limits<double>::quiet_NaN();
  const Status s = CheckAligned(kMeasured, model);
  ASSERT_FALSE(s.ok());
  PZ_EXPECT_HAS(s.message(), "model[2] = nan is not finite");
  EXPECT_THROW((void)CompareSeries(kMeasured, model), InputError);
}

TEST(TimeGrid, FirstDifferingSampleIsNamed) {
  const std::vector<double> a = {0, 0.01, 0.02, 0.03};
  const std::vector<double> b = {0, 0.01, 0.025, 0.03};
  EXPECT_TRUE(CheckSameGrid(a, a, 1e-9).ok());
  const Status s = CheckSameGrid(a, b, 1e-9);
  ASSERT_FALSE(s.ok());
  PZ_EXPECT_HAS(s.message(), "differ first at sample 2: t = 0.02 s vs 0.025 s");
  PZ_EXPECT_HAS(InputErrorOf([&] { (void)CompareTraces(a, kMeasured, b, kModel, 1e-9); }),
                "sample 2");
  const std::vector<double> c = {0, 0.01, 0.02};
  PZ_EXPECT_HAS(CheckSameGrid(a, c, 1e-9).message(), "4 vs 3 samples");
}

TEST(TimeGrid, WithinToleranceIsTheSameGrid) {
  const std::vector<double> a = {0, 0.01, 0.02, 0.03};
  const std::vector<double> b = {0, 0.01 + 1e-13, 0.02, 0.03 - 1e-13};
  EXPECT_NEAR(CompareTraces(a, kMeasured, b, kModel, 1e-9).pi, 14.0, kTight);
}

TEST(IntegratedAbsError, TrapezoidOverTheWholeSeries) {
  // e = {1, −2, 0, 3} at t = 0, 1, 2, 3: trapezoid on |e| = (1+2)/2 + (2+0)/2 + (0+3)/2 = 4.
  const std::vector<double> t = {0, 1, 2, 3};
  EXPECT_NEAR(IntegratedAbsError(t, kMeasured, kModel, 0, 3), 4.0, kTight);
}

TEST(IntegratedAbsError, WindowCutsIntervalsByLinearInterpolation) {
  const std::vector<double> t = {0, 1, 2, 3};
  // [2, 2.5]: e goes 0 → 1.5, area 0.375. [0.5, 1]: e from −0.5 → −2, |e| trapezoid (0.5+2)/2·0.5.
  EXPECT_NEAR(IntegratedAbsError(t, kMeasured, kModel, 2, 2.5), 0.375, kTight);
  EXPECT_NEAR(IntegratedAbsError(t, kMeasured, kModel, 0.5, 1), 0.625, kTight);
  EXPECT_NEAR(IntegratedAbsError(t, kMeasured, kModel, 1.5, 1.5), 0.0, kTight);
}

TEST(IntegratedAbsError, WindowOutsideTheSeriesIsAnError) {
  const std::vector<double> t = {0, 1, 2, 3};
  PZ_EXPECT_HAS(InputErrorOf([&] { (void)IntegratedAbsError(t, kMeasured, kModel, 1, 4); }),
                "window [1, 4] s");
  EXPECT_THROW((void)IntegratedAbsError(t, kMeasured, kModel, 2, 1), InputError);
  const std::vector<double> back = {0, 1, 1, 3};
  EXPECT_THROW((void)IntegratedAbsError(back, kMeasured, kModel, 0, 3), InputError);
}

}  // namespace
}  // namespace pz::model
