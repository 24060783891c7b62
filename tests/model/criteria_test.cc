// Identification criteria (model/criteria.h) against hand-computed values.
#include "model/criteria.h"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "model/metrics.h"
#include "tests/testing/expect_error.h"

namespace pz::model {
namespace {

// Errors e = y − ŷ = {1, −2, 3, 0, −1} at dt = 0.5 s (t = 0, 0.5, 1, 1.5, 2).
const std::vector<double> kY = {2, 0, 4, 1, 0};
const std::vector<double> kYhat = {1, 2, 1, 1, 1};

TEST(Criteria, WholeRecord) {
  // SSE = 1 + 4 + 9 + 0 + 1 = 15; RMSE = √3; IAE = 0.5·(1.5 + 2.5 + 1.5 + 0.5) = 3.
  EXPECT_DOUBLE_EQ(Sse(kY, kYhat), 15.0);
  EXPECT_DOUBLE_EQ(Rmse(kY, kYhat), std::sqrt(3.0));
  EXPECT_DOUBLE_EQ(Iae(kY, kYhat, 0.5), 3.0);
  EXPECT_DOUBLE_EQ(MaxAbsError(kY, kYhat), 3.0);
}

TEST(Criteria, Windows) {
  // Samples in [0.5, 1.5]: e = −2, 3, 0.
  EXPECT_DOUBLE_EQ(Sse(kY, kYhat, 0.5, 0.5, 1.5), 13.0);
  EXPECT_DOUBLE_EQ(Rmse(kY, kYhat, 0.5, 0.5, 1.5), std::sqrt(13.0 / 3));
  EXPECT_DOUBLE_EQ(MaxAbsError(kY, kYhat, 0.5, 0.5, 1.5), 3.0);
  EXPECT_DOUBLE_EQ(Iae(kY, kYhat, 0.5, 0.5, 1.5), 0.5 * (2.5 + 1.5));
  // A window cutting intervals: [0.25, 1.25]. e at 0.25 = (1 − 2)/2 = −0.5, at 1.25 = 1.5.
  // ∫ = 0.25·(0.5+2)/2 + 0.5·(2+3)/2 + 0.25·(3+1.5)/2 = 0.3125 + 1.25 + 0.5625 = 2.125.
  EXPECT_DOUBLE_EQ(Iae(kY, kYhat, 0.5, 0.25, 1.25), 2.125);
  // Samples in [0.25, 1.25]: t = 0.5, 1 → e = −2, 3.
  EXPECT_DOUBLE_EQ(Sse(kY, kYhat, 0.5, 0.25, 1.25), 13.0);
  // Zero-width window: IAE 0, one sample for the others.
  EXPECT_DOUBLE_EQ(Iae(kY, kYhat, 0.5, 1.0, 1.0), 0.0);
  EXPECT_DOUBLE_EQ(MaxAbsError(kY, kYhat, 0.5, 1.0, 1.0), 3.0);
  // Agrees with the time-vector IAE of model/metrics.h.
  const std::vector<double> t = {0, 0.5, 1, 1.5, 2};
  EXPECT_NEAR(Iae(kY, kYhat, 0.5, 0.3, 1.9), IntegratedAbsError(t, kY, kYhat, 0.3, 1.9), 1e-15);
}

TEST(Criteria, BadInputNamed) {
  using pz::testing::InputErrorOf;
  const std::vector<double> short_y = {1, 2};
  PZ_EXPECT_HAS(InputErrorOf([&] { Sse(short_y, kYhat); }), "y has 2 samples, yhat has 5");
  std::vector<double> bad = kYhat;
  bad[3] = std::nan("");
  PZ_EXPECT_HAS(InputErrorOf([&] { Rmse(kY, bad); }), "yhat[3]");
  PZ_EXPECT_HAS(InputErrorOf([&] { Iae(kY, kYhat, 0.0); }), "dt = 0");
  PZ_EXPECT_HAS(InputErrorOf([&] { Iae(kY, kYhat, 0.5, 0.5, 3.0); }), "t1 = 3");
  PZ_EXPECT_HAS(InputErrorOf([&] { Sse(kY, kYhat, 0.5, 1.0, 0.5); }), "t1 = 0.5");
  PZ_EXPECT_HAS(InputErrorOf([&] { Sse(kY, kYhat, 0.5, 0.6, 0.9); }), "no sample in the window");
  PZ_EXPECT_HAS(InputErrorOf([&] { Sse(std::vector<double>{}, std::vector<double>{}); }), "empty");
}

}  // namespace
}  // namespace pz::model
