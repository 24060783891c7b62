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
    u.push_back(20 + 80 * std::sin(2 * std::numbers::pi * 1.3 * t + 0.7) * (0.4 + 0.6 * std::cos(0.9 * t)) +
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

TEST(PrandtlIshlinskii, InverseUndoesTheOperatorExactly) {
  PiOperator op;
  op.w0 = 0.08;
  op.thresholds = PiThresholds(10, 90);
  for (size_t i = 0; i < op.thresholds.size(); ++i) op.weights.push_back(0.01 + 0.004 * std::sin(double(i)));
  const std::vector<double> u = MinorLoopDrive();
  std::vector<double> y(u.size()), back(u.size());
  ApplyPi(op, u, y);
  const PiOperator inv = InvertPi(op);
  ApplyPi(inv, y, back);
  double worst = 0;
  for (size_t k = 0; k < u.size(); ++k) worst = std::max(worst, std::abs(back[k] - u[k]));
  EXPECT_LT(worst, 1e-10);
}

TEST(PrandtlIshlinskii, ExportedCHeaderCompilesAndCompensates) {
  if (std::system("command -v cc >/dev/null 2>&1") != 0) GTEST_SKIP() << "no C compiler";
  PiOperator op{0.1, PiThresholds(6, 100), {0.02, 0.01, 0.03, 0.0, 0.015, 0.005}};
  char tmpl[] = "/tmp/pz_pi_XXXXXX";
  ASSERT_NE(mkdtemp(tmpl), nullptr);
  const std::filesystem::path dir = tmpl;
  std::ofstream(dir / "pi_inverse.h") << PiInverseCHeader(op, "pzpi", "test operator");
  const std::vector<double> u = MinorLoopDrive();
  std::vector<double> y(u.size());
  ApplyPi(op, u, y);
  {
    std::ofstream c(dir / "main.c");
    c << "#include <stdio.h>\n#include \"pi_inverse.h\"\nint main(void) {\n  pzpi_state s; double y;\n"
      << "  int first = 1;\n  while (scanf(\"%lf\", &y) == 1) {\n    if (first) { pzpi_init(&s, y); first = 0; }\n"
      << "    printf(\"%.17g\\n\", pzpi_step(&s, y));\n  }\n  return 0;\n}\n";
    std::ofstream in(dir / "y.txt");
    in.precision(17);
    for (double v : y) in << v << "\n";
  }
  const std::string cmd = "cd " + dir.string() + " && cc -std=c99 -Wall -Werror -O2 -o inv main.c && ./inv < y.txt > u.txt";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  std::ifstream out(dir / "u.txt");
  double v, worst = 0;
  size_t k = 0;
  while (out >> v) worst = std::max(worst, std::abs(v - u[k++]));
  EXPECT_EQ(k, u.size());
  EXPECT_LT(worst, 1e-9);
  std::filesystem::remove_all(dir);
}

TEST(PrandtlIshlinskii, InvalidOperatorsAreNamed) {
  using pz::testing::InputErrorOf;
  PZ_EXPECT_HAS(InputErrorOf([] { InvertPi(PiOperator{0.1, {1, 2}, {0.1, -0.2}}); }), "not invertible");
  PZ_EXPECT_HAS(InputErrorOf([] {
                  std::vector<double> y(2);
                  ApplyPi(PiOperator{0.1, {2, 1}, {0.1, 0.2}}, std::vector<double>{0, 1}, y);
                }),
                "pi.thresholds[1] = 1: must be finite, > 0 and above the previous one");
  PZ_EXPECT_HAS(InputErrorOf([] { PiThresholds(5, 0); }), "half range 0 must be finite and > 0");
}

}  // namespace
}  // namespace pz::model
