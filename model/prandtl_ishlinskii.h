// The Prandtl–Ishlinskii (PI) hysteresis operator and its analytic inverse (Kuhnen & Janocha;
// Krejčí & Kuhnen 2001), the rate-independent model a piezo engineer uses for feed-forward
// compensation:
//
//   ŷ(t) = w₀ u(t) + Σ_{i=1..n} w_i F_{r_i}[u](t),       0 < r_1 < … < r_n
//   play  F_r[u](t_k) = max(u_k − r, min(u_k + r, F_r[u](t_{k−1}))),   F_r[u](t_0) = u_0
//
// (every play starts centred on the first sample: the operator is at rest at u_0, ŷ(t_0) =
// (w₀ + Σ w_i) u_0). With w₀ > 0 and w_i ≥ 0 the operator is strictly increasing on every branch
// and its inverse is again a PI operator, of the output, with
//
//   r'_j = w₀ r_j + Σ_{i<j} w_i (r_j − r_i),
//   w'_0 = 1 / w₀,   w'_j = −w_j / ((w₀ + Σ_{i≤j} w_i)(w₀ + Σ_{i<j} w_i)),
//
// started at rest at ŷ_0 = (w₀ + Σ w_i) u_0 (each inverse play centred on ŷ_0): then
// Inverse(Forward(u)) = u exactly, sample by sample (tests/model/prandtl_ishlinskii_test.cc).
// The play operators are exact on the samples (rate-independent: the drive between samples does
// not matter for a monotone piece). Pure; no allocation in Apply with a caller's state buffer.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "model/status.h"

namespace pz::model {

struct PiOperator {
  double w0 = 1;                   ///< linear weight, > 0 for an invertible operator
  std::vector<double> thresholds;  ///< r_1 < … < r_n, > 0
  std::vector<double> weights;     ///< w_1 … w_n (≥ 0 for an invertible operator)
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
void PiPlayOutputs(std::span<const double> thresholds, std::span<const double> u, std::span<double> out);

/// The inverse operator (formulas above). Throws InputError unless op.Invertible().
PiOperator InvertPi(const PiOperator& op);

}  // namespace pz::model
