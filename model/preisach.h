// Rate-independent hysteresis with exact return-point memory for real piezo stacks (issue 22): a
// discrete Preisach model on a triangular grid and an asymmetric Prandtl–Ishlinskii operator, both
// linear in their weights, with their exact inverses.
//
// Discrete Preisach model (Mayergoyz), written through its play representation (Krejčí; Brokate &
// Sprekels): a relay R_{α,β} (α ≥ β, on when u ≥ α, off when u ≤ β, else unchanged) with centre
// c = (α+β)/2 and half-width r = (α−β)/2 is on exactly when the play of half-width r is above its
// centre, p_r(t) > c, p_r = max(u − r, min(u + r, p_r(t⁻))). The grid over the drive range
// [u_min, u_max] (the training records'), n levels, Δ = (u_max − u_min)/n:
//
//   widths      r_i = i Δ / 2,                                  i = 0 … n−1   (r_0 = 0: reversible)
//   cells       centres [c_ij, c_ij + Δ], c_ij = u_min + r_i + j Δ, j = 0 … n−1−i
//
// — every relay of a cell has α ≤ u_max and β ≥ u_min, so the cells fill the Preisach triangle:
// n(n+1)/2 cells. Each cell carries a uniform line density of relays along its centre interval,
// weight w_ij ≥ 0 per unit of centre, so its output is continuous (piecewise linear in u on a
// monotone piece, not a staircase of relays):
//
//   ŷ = Σ_ij w_ij φ_ij(p_{r_i}),   φ_ij(p) = clamp(p, c_ij, c_ij + Δ) − c_ij + (u_min + r_i)/(n −
//   i)
//
// (the constant makes a density constant along the centre exactly the PI play Σ_j φ_ij = p_{r_i}
// while p_{r_i} stays inside the grid). Every play starts at rest at the first sample u_0 in the
// initial state given (model/prandtl_ishlinskii.h InitialState): centred on u_0 (relays with centre
// below u_0 on, the demagnetised state of the PI operator), descended (p_r = u_0 + r: the drive
// came down to u_0 from the top, only relays with β < u_0 on) or ascended (p_r = u_0 − r: relays
// with α ≤ u_0 on). A rest at or below the grid has every relay off in all three. Wiping-out and
// return-point memory are those of the plays: exact. Beyond the grid's drive range the output is
// flat (relays outside the grid are not modelled): a prediction there is an extrapolation.
//
// Asymmetric PI ("asymmetric-pi"): the PI operator plus a memoryless monotone piecewise-linear
// curve built from one-sided dead zones of the drive,
//
//   ŷ = w₀ u + Σ_i w_i F_{r_i}[u] + Σ_j a_j max(u − z_j, 0) + Σ_j b_j min(u − z_j, 0)
//
// all weights ≥ 0: the slope on any branch is w₀ + Σ_{moving plays} w_i + Σ_{z_j < u} a_j +
// Σ_{z_j > u} b_j ≥ 0 (any monotone, convex or concave, bend of the loop's centre line: ascending
// and descending branches are no longer point-symmetric), so the operator is monotone on every
// branch and unbounded: every reference has a drive (strictly unique when w₀ > 0).
//
// Inverses: both operators are monotone non-decreasing on each step — given the play states after
// sample k−1, the output at sample k is a non-decreasing, piecewise-linear function of u_k. The
// inverse solves that one-step map for the reference by bisection to adjacent doubles (about 60
// halvings: the result is exact to the last bits of u; the forward model run on the returned drive
// reproduces the reference to rounding, tests/model/preisach_test.cc), then commits the plays. The
// first sample is solved for a rest state (plays centred on the solution). A Preisach reference
// outside what the grid can reach is met at the drive limit given, and counted.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "model/prandtl_ishlinskii.h"
#include "model/status.h"

namespace pz::model {

struct PreisachGrid {
  double u_min = 0, u_max = 1;  ///< drive range covered by the relays
  int levels = 12;              ///< n: widths and centre cells per side, 1 … 200
  /// Finite u_min < u_max, levels in range; the error names the field.
  Status Validate() const;
  double step() const { return (u_max - u_min) / levels; }
  size_t cells() const { return static_cast<size_t>(levels) * static_cast<size_t>(levels + 1) / 2; }
  double half_width(int i) const { return 0.5 * i * step(); }
  /// Index of cell (i, j) in the weight vector (widths in order, centres in order within a width).
  size_t cell(int i, int j) const;
  /// "w(a=…,b=…)": the cell's relay thresholds at its centre (α, β) in drive units.
  std::string CellName(int i, int j) const;
};

/// The cell regressors φ_ij(p_{r_i}[u]) (row-major, rows = samples, columns = grid.cells()).
/// Throws InputError on an invalid grid or sizes.
void PreisachRegressors(const PreisachGrid& grid, std::span<const double> u, std::span<double> out,
                        InitialState start = InitialState::kCentred);

/// Runs the model (weights: grid.cells() values) over u into y. Throws InputError on sizes.
void ApplyPreisach(const PreisachGrid& grid, std::span<const double> weights,
                   std::span<const double> u, std::span<double> y,
                   InitialState start = InitialState::kCentred);

/// The roughness of the density along the centre axis, Σ_i Σ_j (w_{i,j+1} − w_{i,j})², as its
/// m×m Gram matrix R (row-major, m = cells): the regularisation λ wᵀRw of the weights' least
/// squares. λ → ∞ leaves a density constant along every width: the PI operator on the grid's
/// widths; the data bend it where they show asymmetry.
std::vector<double> PreisachRoughness(const PreisachGrid& grid);
/// The roughness of the density over the whole triangle: PreisachRoughness's squared differences
/// along the centre plus, between the hysteron widths i ≥ 1, those along α, (w_{i+1,j} − w_{i,j})²
/// (α + Δ, the same β), and along β, (w_{i+1,j−1} − w_{i,j})² (β − Δ, the same α) — every neighbour
/// of the triangular grid alike (the reversible cells of width 0, a line density on the diagonal,
/// are smoothed along the centre only). λ → ∞ leaves the hysterons' density uniform. A major loop
/// identifies the density's integrals along α and along β (its ascending and descending branches),
/// not how the mass lies inside the triangle, which the minor loops use: this penalty fills the
/// interior in smoothly from the branches, PreisachRoughness towards the PI operator (a density of
/// the width alone); the validation keeps the one the training records contradict less
/// (records/regularisation.h ChoosePenalty).
std::vector<double> PreisachTriangleRoughness(const PreisachGrid& grid);

/// What an inverse met: samples whose reference lay beyond the reachable output (set to the drive
/// limit), and the largest such shortfall.
struct InverseReport {
  size_t saturated = 0;
  double max_shortfall = 0;
};

/// The exact inverse: u such that ApplyPreisach(grid, weights, u) = y_ref (to rounding), u within
/// [u_lo, u_hi] (the amplifier's range; u_lo < u_hi), the first sample a rest in state `start`.
/// Weights must be ≥ 0 (a monotone operator); throws InputError otherwise or on sizes.
InverseReport InvertPreisach(const PreisachGrid& grid, std::span<const double> weights,
                             std::span<const double> y_ref, double u_lo, double u_hi,
                             std::span<double> u, InitialState start = InitialState::kCentred);

struct AsymmetricPi {
  double w0 = 1;
  std::vector<double> thresholds;               ///< play half-widths r_1 < … < r_n, > 0
  std::vector<double> weights;                  ///< w_i ≥ 0
  std::vector<double> knots;                    ///< z_1 < … < z_K (drive units)
  std::vector<double> up;                       ///< a_j ≥ 0 on max(u − z_j, 0)
  std::vector<double> down;                     ///< b_j ≥ 0 on min(u − z_j, 0)
  InitialState start = InitialState::kCentred;  ///< the plays at rest at u_0
  /// Finite values, matching sizes, increasing thresholds and knots; the error names the field.
  Status Validate() const;
  /// Validate() and every weight ≥ 0 (monotone on every branch; strictly when w0 > 0).
  bool Monotone() const;
};

/// K knots evenly inside (u_min, u_max): z_j = u_min + (u_max − u_min) j / (K + 1). Throws
/// InputError on K < 1 or an empty range.
std::vector<double> AsymmetricPiKnots(int count, double u_min, double u_max);

/// The regressors [u, F_{r_1} … F_{r_n}, max(u − z_j, 0)…, min(u − z_j, 0)…] (row-major,
/// 1 + n + 2K columns).
void AsymmetricPiRegressors(std::span<const double> thresholds, std::span<const double> knots,
                            std::span<const double> u, std::span<double> out,
                            InitialState start = InitialState::kCentred);

/// Runs the operator over u into y. Throws InputError on an invalid operator or sizes.
void ApplyAsymmetricPi(const AsymmetricPi& op, std::span<const double> u, std::span<double> y);

/// The exact inverse (one-step bisection above; unbounded, so every reference is met). Throws
/// InputError unless op.Monotone() and some weight is > 0.
void InvertAsymmetricPi(const AsymmetricPi& op, std::span<const double> y_ref, std::span<double> u);

}  // namespace pz::model
