// Non-negative least squares for many unknowns (issue 37: the Preisach grid's 820 cells at 40
// levels): the Lawson–Hanson active set of NonNegativeLeastSquares (below), from a start and
// with the passive set's Cholesky factor updated as variables enter and leave it.
//
// NonNegativeLeastSquares solves every passive set afresh (an LDLᵀ of G_PP: O(p³) per step, and
// about one step per positive weight from w = 0), which at 820 unknowns is seconds per solve. Here
// the factor L (L Lᵀ = G_PP + εI, ε = 1e-13 max(1, max diag G): the same tiny ridge) is extended by
// one row when a variable enters (a triangular solve, O(p²)) and, when one leaves, its row and
// column are deleted and the trailing block restored by a rank-one update (O(p²)); and the
// iteration starts from a feasible point w₀ ≥ 0 with the passive set {w₀ > 0} — a solution of a
// neighbouring problem (the next strength of a validation, another block left out, another delay)
// is a few steps from this one's. The optimum is unique where G + εI is positive definite, so the
// result is NonNegativeLeastSquares's to rounding whatever the start; a fixed start keeps it
// deterministic.
#pragma once

#include <Eigen/Dense>
#include <vector>

namespace pz::records {

/// min ‖A w − b‖² subject to w ≥ 0, from the normal equations G = AᵀA, h = Aᵀb (Lawson–Hanson
/// active set). Returns w.
Eigen::VectorXd NonNegativeLeastSquares(const Eigen::MatrixXd& G, const Eigen::VectorXd& h);

/// min ‖A w − b‖², w ≥ 0, from G = AᵀA and h = Aᵀb, starting at max(start, 0) (empty: at the
/// positive part of the unconstrained solution of G + εI).
/// Falls back to NonNegativeLeastSquares where the factor cannot be formed.
Eigen::VectorXd NonNegativeLeastSquaresFrom(const Eigen::MatrixXd& G, const Eigen::VectorXd& h,
                                            const Eigen::VectorXd& start);

/// Lawson–Hanson's entering variable: the one outside the passive set with the largest gradient
/// g = h − G w above tol, or −1 (both active sets' step).
Eigen::Index EnteringVariable(const Eigen::VectorXd& g, const std::vector<char>& passive,
                              double tol);

/// Unknowns from which the regularisation's validation and a linear family's solve use
/// NonNegativeLeastSquaresFrom (fewer: NonNegativeLeastSquares, as before).
inline constexpr Eigen::Index kIncrementalNnlsFrom = 100;

}  // namespace pz::records
