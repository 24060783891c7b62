// e^x with +, × and integer bit operations only, so that a loop calling it vectorises (GCC, with
// -fno-trapping-math on the calling file for the selects around it): x = n ln2 + r with |r| ≤ ln2/2
// (n by the 1.5·2⁵² rounding trick), e^r by its Taylor series to r¹³ (remainder < 5e−18 relative),
// 2ⁿ assembled in the exponent bits. Within 2 ulp of std::exp for |x| ≤ 700 (the caller keeps x
// there). Used by the tansig kernel (model/ffnet.cc) and the modal simulator's z batches.
#pragma once

#include <bit>
#include <cstdint>

namespace pz::model {

inline double ExpReduced(double x) {
  constexpr double kLog2e = 1.4426950408889634;
  constexpr double kLn2Hi = 6.93147180369123816490e-01;
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  constexpr double kRound = 6755399441055744.0;  // 2^52 + 2^51: adding it rounds to an integer
  const double kr = x * kLog2e + kRound;         // its low mantissa bits hold n
  const double n = kr - kRound;
  const double r = (x - n * kLn2Hi) - n * kLn2Lo;
  double p = 1.0 / 6227020800.0;  // 1/13!
  p = p * r + 1.0 / 479001600.0;
  p = p * r + 1.0 / 39916800.0;
  p = p * r + 1.0 / 3628800.0;
  p = p * r + 1.0 / 362880.0;
  p = p * r + 1.0 / 40320.0;
  p = p * r + 1.0 / 5040.0;
  p = p * r + 1.0 / 720.0;
  p = p * r + 1.0 / 120.0;
  p = p * r + 1.0 / 24.0;
  p = p * r + 1.0 / 6.0;
  p = p * r + 0.5;
  p = p * r + 1.0;
  p = p * r + 1.0;
  return p * std::bit_cast<double>((std::bit_cast<uint64_t>(kr) + 1023u) << 52);
}

}  // namespace pz::model
