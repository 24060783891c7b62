// The Prandtl–Ishlinskii (PI) hysteresis operator and its analytic inverse (Kuhnen & Janocha;
// Krejčí & Kuhnen 2001), the rate-independent model a piezo engineer uses for feed-forward
// compensation:
//
//   ŷ(t) = w₀ u(t) + Σ_{i=1..n} w_i F_{r_i}[u](t),       0 < r_1 < … < r_n
//   play  F_r[u](t_k) = max(u_k − r, min(u_k + r, F_r[u](t_{k−1}))),   F_r[u](t_0) = z_0(u_0, r)
//
// The operator is at rest at u_0; its memory there is the initial state (InitialState):
//   centred    z_0 = u_0        the demagnetised (virgin) state, ŷ(t_0) = (w₀ + Σ w_i) u_0;
//   descended  z_0 = u_0 + r    the drive came down to u_0 from at least 2r above (a stack resting
//                               at the bottom of its range after use: the next rise follows the
//                               major loop's ascending branch);
//   ascended   z_0 = u_0 − r    the drive came up to u_0 from at least 2r below;
//   auto       descended when u_0 is at the bottom of the data's drive range (u_0 ≤ u_min + 5 % of
//              the range: the drive came down to its rest), ascended at its top, else centred
//              (ResolveInitialState; the families resolve it on each simulation's first drive).
// With w₀ > 0 and w_i ≥ 0 the operator is strictly increasing on every branch
// and its inverse is again a PI operator, of the output, with
//
//   r'_j = w₀ r_j + Σ_{i<j} w_i (r_j − r_i),
//   w'_0 = 1 / w₀,   w'_j = −w_j / ((w₀ + Σ_{i≤j} w_i)(w₀ + Σ_{i<j} w_i)),
//
// started at rest at ŷ_0, the forward operator's output at rest, in the same initial state (each
// inverse play at ŷ_0, ŷ_0 + r'_j or ŷ_0 − r'_j: a descent of the drive is a descent of the
// output): then Inverse(Forward(u)) = u exactly, sample by sample
// (tests/model/prandtl_ishlinskii_test.cc). The play operators are exact on the samples
// (rate-independent: the drive between samples does not matter for a monotone piece). Pure; no
// allocation in Apply with a caller's state buffer.
#pragma once

#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "model/status.h"

namespace pz::model {

/// The memory of a hysteresis operator at rest at the first sample's drive u_0 (above; for the
/// Bouc–Wen-type stack families, model/stack_models.h StackRestState: the state after the drive
/// rose from u_0 by the data's full range and came back down to u_0, or the mirror of it).
enum class InitialState : int { kCentred = 0, kDescended = 1, kAscended = 2, kAuto = 3 };
/// "centred", "descended", "ascended", "auto".
const char* InitialStateName(InitialState s);
/// Parses a name of InitialStateName; throws InputError naming `field`, the value and the allowed
/// ones.
InitialState ParseInitialState(std::string_view name, std::string_view field);
/// The play of half-width r at rest at u0 in state s: u0, u0 + r or u0 − r (s resolved, not kAuto).
inline double PlayRest(double u0, double r, InitialState s) {
  return s == InitialState::kDescended ? u0 + r : s == InitialState::kAscended ? u0 - r : u0;
}
/// Throws InputError for kAuto (an operator needs a resolved state), naming `what`.
void RequireResolved(InitialState s, std::string_view what);
/// The state `s` at rest at u0 for a drive range [u_min, u_max]: kAuto resolved (above), any other
/// state itself.
inline InitialState ResolveInitialState(InitialState s, double u0, double u_min, double u_max) {
  if (s != InitialState::kAuto) return s;
  const double margin = 0.05 * (u_max - u_min);
  return u0 <= u_min + margin
             ? InitialState::kDescended
             : (u0 >= u_max - margin ? InitialState::kAscended : InitialState::kCentred);
}

struct PiOperator {
  double w0 = 1;                                ///< linear weight, > 0 for an invertible operator
  std::vector<double> thresholds;               ///< r_1 < … < r_n, > 0
  std::vector<double> weights;                  ///< w_1 … w_n (≥ 0 for an invertible operator)
  InitialState start = InitialState::kCentred;  ///< the plays at rest at u_0
  /// Finite values, equal sizes, thresholds positive and strictly increasing. The error names the
  /// field ("pi.thresholds[2] = …").
  Status Validate() const;
  /// w₀ > 0 and every w_i ≥ 0 (and Validate()).
  bool Invertible() const;
};

/// n thresholds evenly spread inside (0, R), R the drive's half range: r_i = R · i / (n + 1),
/// i = 1 … n (a play with r ≥ R never moves in a steady loop of half-range R). n ≥ 1, R > 0 finite;
/// throws InputError otherwise.
std::vector<double> PiThresholds(int n, double half_range);

/// Runs the operator over u into y (same length, may not alias). Throws InputError on an invalid
/// operator or lengths.
void ApplyPi(const PiOperator& op, std::span<const double> u, std::span<double> y);

/// The play outputs F_{r_i}[u] (column i of an n-column matrix in row-major order, rows = samples)
/// — the regressors of a linear least-squares fit of the weights. out.size() == u.size() · n.
void PiPlayOutputs(std::span<const double> thresholds, std::span<const double> u,
                   std::span<double> out, InitialState start = InitialState::kCentred);

/// The inverse operator (formulas above), in op's initial state. Throws InputError unless
/// op.Invertible().
PiOperator InvertPi(const PiOperator& op);

}  // namespace pz::model
