// The GA's only random generator (conventions 9): MT19937-64 with portable integer → uniform and
// integer → Bernoulli mappings, so that one seed gives the same run bit for bit on every platform.
//
// The engine is the standard's std::mt19937_64 (same seeding, same output sequence; a test checks
// it against the standard library), written out here because the textual state of
// std::mt19937_64 is implementation-defined (libstdc++ appends its position index, libc++ does
// not), and a checkpoint must restore on any platform. The state is a plain struct: 312 words +
// position. The std:: distributions are not used: their algorithms are implementation-defined.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "model/status.h"

namespace pz::opt {

/// The complete state of the generator; plain data for checkpoints.
struct RngState {
  static constexpr int kWords = 312;
  std::array<uint64_t, kWords> words{};  ///< the Mersenne-Twister state vector
  uint32_t position = kWords;            ///< next word to temper, 0 … 312 (312 = twist first)
  bool operator==(const RngState&) const = default;

  /// position ≤ 312 and not all words zero (the all-zero state is degenerate).
  Status Validate() const {
    if (position > static_cast<uint32_t>(kWords)) {
      return InvalidArgument(FieldError("rng.position", position, "must be <= 312"));
    }
    for (uint64_t w : words) {
      if (w != 0) return Status::Ok();
    }
    return InvalidArgument("rng.words: all zero, not a reachable generator state");
  }
};

/// Precomputed Bernoulli(p) test: a draw x succeeds iff x < threshold (or always, for p ≥ 1).
struct BernoulliThreshold {
  uint64_t threshold = 0;
  bool always = false;
  /// p in [0, 1] (checked): threshold = ⌊p · 2⁶⁴⌋, exact in IEEE arithmetic.
  explicit BernoulliThreshold(double p) {
    PZ_CHECK_MSG(p >= 0 && p <= 1, "Bernoulli probability outside [0, 1]");
    const double scaled = std::ldexp(p, 64);
    if (scaled >= 18446744073709551616.0) {
      always = true;
    } else {
      threshold = static_cast<uint64_t>(scaled);
    }
  }
};

/// Precomputed inverse CDF of the gap between two successes of independent Bernoulli(p) trials,
/// for drawing the positions of mutated bits instead of testing every bit. The gap G (the number of
/// failures before the next success) has P(G ≥ k) = (1 − p)^k; the table holds
/// T_k = ⌊(1 − p)^k · 2⁶⁴⌋ for k = 1 … max_gap, and a draw x gives G = #{k : x < T_k}, i.e. G ≥ k
/// iff x < T_k, exactly as k successive Bernoulli(1 − p) tests with the thresholds' ratios would.
/// (1 − p)^k is formed by repeated IEEE multiplication, so the table — and every run — is the same
/// on every platform (no libm call). Draws beyond max_gap are returned as max_gap: the caller's "no
/// further success in this block". One draw per gap; p = 0 and p = 1 need none.
class GeometricGaps {
 public:
  /// p in [0, 1] (checked), max_gap ≥ 0.
  GeometricGaps(double p, int max_gap) : p_(p), max_gap_(max_gap) {
    PZ_CHECK_MSG(p >= 0 && p <= 1, "mutation probability outside [0, 1]");
    PZ_CHECK(max_gap >= 0);
    if (p == 0 || p == 1) return;
    const double q = 1 - p;
    double qk = 1;
    thresholds_.reserve(static_cast<size_t>(max_gap));
    for (int k = 1; k <= max_gap; ++k) {
      qk *= q;
      const double scaled = std::ldexp(qk, 64);  // qk = 1 when p < 2⁻⁵³: clamp
      const uint64_t t =
          scaled >= 18446744073709551616.0 ? ~uint64_t{0} : static_cast<uint64_t>(scaled);
      if (t == 0) break;  // P(G ≥ k) < 2⁻⁶⁴: never reached, the table ends here
      thresholds_.push_back(t);
    }
  }
  double probability() const { return p_; }
  int max_gap() const { return max_gap_; }
  bool never() const { return p_ == 0; }
  bool always() const { return p_ == 1; }
  /// The gap for the 64-bit draw x, in [0, min(max_gap, table size)].
  int GapFor(uint64_t x) const {
    // Thresholds decrease with k: G = the number of them above x.
    const auto it = std::lower_bound(thresholds_.begin(), thresholds_.end(), x,
                                     [](uint64_t t, uint64_t v) { return t > v; });
    return static_cast<int>(it - thresholds_.begin());
  }

 private:
  double p_;
  int max_gap_;
  std::vector<uint64_t> thresholds_;  ///< T_1 … T_m, strictly positive, non-increasing
};

/// The seed of stream `stream` of a run seeded `seed`: the seed itself for stream 0, otherwise
/// SplitMix64's finaliser of seed + stream · φ·2⁶⁴ (independent-looking generators per island).
inline uint64_t StreamSeed(uint64_t seed, uint64_t stream) {
  if (stream == 0) return seed;
  uint64_t z = seed + stream * 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

class Rng {
 public:
  /// Seeds as std::mt19937_64(seed) does.
  explicit Rng(uint64_t seed = 5489u) {
    s_.words[0] = seed;
    for (int i = 1; i < RngState::kWords; ++i) {
      const uint64_t prev = s_.words[i - 1];
      s_.words[i] = 6364136223846793005ULL * (prev ^ (prev >> 62)) + static_cast<uint64_t>(i);
    }
    s_.position = RngState::kWords;
  }
  /// Restores a saved state. Throws InputError if it is invalid.
  explicit Rng(const RngState& state) : s_(state) { ThrowIfError(state.Validate()); }

  const RngState& state() const { return s_; }
  bool operator==(const Rng&) const = default;

  /// The next 64-bit output (identical to std::mt19937_64's).
  uint64_t NextU64() {
    if (s_.position >= static_cast<uint32_t>(RngState::kWords)) Twist();
    uint64_t x = s_.words[s_.position++];
    x ^= (x >> 29) & 0x5555555555555555ULL;
    x ^= (x << 17) & 0x71D67FFFEDA60000ULL;
    x ^= (x << 37) & 0xFFF7EEE000000000ULL;
    x ^= x >> 43;
    return x;
  }

  /// Uniform in [0, 1) on the 2⁻⁵³ grid: (x >> 11) · 2⁻⁵³.
  double Uniform01() { return static_cast<double>(NextU64() >> 11) * 0x1.0p-53; }

  /// Uniform integer in [0, n), n ≥ 1 (checked); unbiased by rejection of the lowest 2⁶⁴ mod n
  /// values, so the number of draws consumed is itself deterministic.
  uint64_t UniformBelow(uint64_t n) {
    PZ_CHECK(n >= 1);
    const uint64_t reject_below = (0 - n) % n;  // 2^64 mod n
    uint64_t x;
    do {
      x = NextU64();
    } while (x < reject_below);
    return x % n;
  }

  /// One draw; true with probability p (exactly ⌊p · 2⁶⁴⌋ / 2⁶⁴). Always consumes one draw.
  bool Bernoulli(const BernoulliThreshold& t) {
    const uint64_t x = NextU64();
    return t.always || x < t.threshold;
  }
  bool Bernoulli(double p) { return Bernoulli(BernoulliThreshold(p)); }

  /// The failures before the next success of Bernoulli(p) trials, capped at gaps.max_gap() (the
  /// table has at most max_gap entries); one draw (none if p = 0: returns max_gap; none if p = 1:
  /// returns 0).
  int Gap(const GeometricGaps& gaps) {
    if (gaps.never()) return gaps.max_gap();
    if (gaps.always()) return 0;
    return gaps.GapFor(NextU64());
  }

 private:
  void Twist() {
    constexpr int n = RngState::kWords, m = 156;
    constexpr uint64_t upper = 0xFFFFFFFF80000000ULL, lower = 0x7FFFFFFFULL;
    constexpr uint64_t matrix_a = 0xB5026F5AA96619E9ULL;
    auto& w = s_.words;
    auto mix = [&](int i, int next, int far) {
      const uint64_t y = (w[i] & upper) | (w[next] & lower);
      w[i] = w[far] ^ (y >> 1) ^ ((y & 1u) ? matrix_a : 0);
    };
    int i = 0;
    for (; i < n - m; ++i) mix(i, i + 1, i + m);
    for (; i < n - 1; ++i) mix(i, i + 1, i + m - n);
    mix(n - 1, 0, m - 1);
    s_.position = 0;
  }

  RngState s_;
};

}  // namespace pz::opt
