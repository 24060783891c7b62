// Regression pins of iterative results (fits, SVDs, ODE solves, GA trajectories over them). A pin
// names the arithmetic it was made on — model::ArithmeticDigest(), the measured fingerprint of the
// C library's maths, Eigen, the dense backend and the kernels (model/arithmetic.h) — and is checked
// exactly there and to its tolerance on any other machine; it is never skipped. The tolerance is
// the problem's: how far another summation order or libm's other variant can move the result
// given its conditioning, stated beside each pin. What the code itself makes exact (1 thread vs 2,
// local vs service, resume vs run) is compared with EXPECT_EQ, not pinned.
//
// CI runs the numerical tests a second time under another arithmetic (scripts/test.sh: OpenBLAS's
// other core, glibc's non-FMA maths), where every pin takes its tolerance path.
#pragma once

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "model/arithmetic.h"

namespace pz::testing {

/// The arithmetic this tree's regression pins were made on: model::ArithmeticDigest() of an AMD
/// EPYC (Zen 4, AVX-512: x86-64-v3 copies of the cloned kernels, glibc 2.36's FMA maths, OpenBLAS
/// core Cooperlake), GCC 12, Eigen 3.4 without CPUID. `piezoid doctor` prints a machine's digest.
inline constexpr const char* kPinnedArithmetic = "653f8a0ad1576e95";

class Pins {
 public:
  /// `digest`: model::ArithmeticDigest() of the machine the pins were made on (`piezoid doctor`).
  explicit Pins(std::string digest) : digest_(std::move(digest)) {}

  /// True when this process computes as the pins' machine did: the pins hold bit for bit.
  bool exact() const { return model::ArithmeticDigest() == digest_; }

  /// `actual` equals `pinned` bit for bit on the pins' arithmetic, and is within `tolerance` of it
  /// (absolute) on any other.
  ::testing::AssertionResult Near(double actual, double pinned, double tolerance) const {
    const bool same = std::memcmp(&actual, &pinned, sizeof actual) == 0;
    if (exact()) {
      if (same) return ::testing::AssertionSuccess();
      return ::testing::AssertionFailure()
             << "on the pins' own arithmetic " << digest_ << " the value must be exact: "
             << Hex(actual) << " (" << Dec(actual) << ") against the pinned " << Hex(pinned)
             << " (" << Dec(pinned) << ")";
    }
    if (std::isfinite(actual) && std::abs(actual - pinned) <= tolerance)
      return ::testing::AssertionSuccess();
    if (same) return ::testing::AssertionSuccess();  // ±inf pinned as such
    return ::testing::AssertionFailure()
           << "on arithmetic " << model::ArithmeticDigest() << " (pins made on " << digest_
           << "): " << Dec(actual) << " is " << Dec(std::abs(actual - pinned))
           << " from the pinned " << Dec(pinned) << ", beyond the tolerance " << Dec(tolerance);
  }

  /// Near() with the tolerance relative to the pinned value: rel · |pinned| + abs.
  ::testing::AssertionResult Rel(double actual, double pinned, double rel, double abs = 0) const {
    return Near(actual, pinned, rel * std::abs(pinned) + abs);
  }

  /// Element by element, each within rel · |pinned_i| + abs; the sizes must agree.
  ::testing::AssertionResult Rel(const std::vector<double>& actual,
                                 const std::vector<double>& pinned, double rel,
                                 double abs = 0) const {
    if (actual.size() != pinned.size())
      return ::testing::AssertionFailure()
             << actual.size() << " values against " << pinned.size() << " pinned";
    for (size_t i = 0; i < actual.size(); ++i) {
      ::testing::AssertionResult r = Rel(actual[i], pinned[i], rel, abs);
      if (!r) return ::testing::AssertionFailure() << "element " << i << ": " << r.message();
    }
    return ::testing::AssertionSuccess();
  }

  const std::string& digest() const { return digest_; }

 private:
  static std::string Hex(double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%a", v);
    return b;
  }
  static std::string Dec(double v) {
    char b[40];
    std::snprintf(b, sizeof b, "%.17g", v);
    return b;
  }
  std::string digest_;
};

}  // namespace pz::testing
