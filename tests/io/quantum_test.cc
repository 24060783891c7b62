// The quantum of a series (io/quantum.h): the grid of the readings, exact or printed.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "io/quantum.h"
#include "tests/testing/series.h"

namespace pz::io {
namespace {

using pz::testing::Quantise;
using pz::testing::Sine;
constexpr double kQ = pz::testing::kEncoderQuantum;

TEST(QuantumTest, QuantumIsTheGridOfTheReadings) {
  EXPECT_DOUBLE_EQ(EstimateQuantum(Quantise(Sine(600, 0.5, 2.0), kQ)), kQ);
  // A grid whose smallest visited step is two quanta still gives the quantum if some value is odd.
  EXPECT_DOUBLE_EQ(EstimateQuantum(std::vector<double>{0, 2 * kQ, 5 * kQ, 9 * kQ}), kQ);
  EXPECT_EQ(EstimateQuantum(Sine(600, 0.5, 2.0)), 0.0);  // continuous data
  EXPECT_EQ(EstimateQuantum(std::vector<double>{1.0, 1.0}), 0.0);
  // A recorder's export: a 2^-17 mm grid printed with 7 decimals (-1.6174316 µm …) over ±40 µm.
  const double q = 1000.0 / 131072.0;
  std::vector<double> printed;
  for (double x : Sine(5000, 0.5, 40.0))
    printed.push_back(std::round(std::round(x / q) * q * 1e7) / 1e7);
  EXPECT_NEAR(EstimateQuantum(printed), q, 1e-7 * q);
  // Continuous data printed with 7 decimals is not on a grid.
  std::vector<double> rounded;
  for (double x : Sine(5000, 0.5, 40.0)) rounded.push_back(std::round(x * 1e7) / 1e7);
  EXPECT_EQ(EstimateQuantum(rounded), 0.0);
}

}  // namespace
}  // namespace pz::io
