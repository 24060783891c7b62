// Exact discretisation of one modal oscillator of the fast path (spec "bimorph-fin model", §6):
//
//   η̈ + c η̇ + ω² η = f(t),   x = [η, η̇]ᵀ,   ẋ = A x + b f,   A = [[0, 1], [−ω², −c]],  b = [0,
//   1]ᵀ
//
// Over a step τ with a polynomial input f(t₀ + s) = Σ_j f_j s^j / j!,
//
//   x(τ) = E x(0) + Σ_j f_j τ^{j+1} φ_{j+1}(τA) b,        E = e^{τA},
//   τ^{j+1} φ_{j+1}(τA) b = [τ^{j+1} D_{j+1},  τ^j D_j]ᵀ,   D_j = φ_j(τ·)[λ₁, λ₂]  (divided
//   difference)
//
// where φ_0(z) = e^z, φ_j(z) = Σ_m z^m / (m + j)! and λ₁,₂ are the roots of λ² + c λ + ω² = 0.
// The D_j and E are computed without cancellation in every regime the plant reaches: underdamped
// (δ = 0, nearly undamped upper modes), overdamped with a huge root ratio (δ > 0: λ₁ ≈ −δω² down to
// −1e10 1/s, λ₂ ≈ −1/δ), near-critical (λ₁ ≈ λ₂) and tiny steps (|τλ| ≪ 1).
#pragma once

namespace pz::model::modal {

/// Highest φ index returned: D_0 … D_kMaxPhi (a quintic input hold needs φ_1 … φ_6 and D_0 … D_6).
inline constexpr int kMaxPhi = 6;

/// Roots of λ² + c λ + ω² = 0 for c ≥ 0, ω² ≥ 0 (so Re λ ≤ 0).
struct ModePoles {
  double omega2 = 0;     ///< ω² [1/s²], ≥ 0
  double c = 0;          ///< damping coefficient μ + δ ω² [1/s], ≥ 0
  bool complex = false;  ///< true when c < 2ω (underdamped)
  double l1 = 0;         ///< real roots (when !complex): l1 ≤ l2 ≤ 0 [1/s]
  double l2 = 0;
  double re = 0;  ///< complex pair re ± i·im (when complex), im > 0 [1/s]
  double im = 0;
};

/// Computes the roots stably (no cancellation for c ≫ ω or c ≈ 2ω).
ModePoles MakePoles(double omega2, double c);

/// One step τ of one mode: E = e^{τA} and the divided differences D_j [s].
struct ModeStep {
  double e11 = 1, e12 = 0, e21 = 0, e22 = 1;
  double d[kMaxPhi + 1] = {};
};

/// Fills `out` for a step τ ≥ 0 [s]. Accurate to a few ulps of the entries' scale in all regimes.
void Discretise(const ModePoles& poles, double tau, ModeStep& out);

/// Discretise for the n modes poles[0 … n) over one step τ, into out[0 … n): the same values to a
/// few ulps. The modes with real, well separated roots (every mode once δ ω² ≫ ω, the usual case)
/// go through one branch-free loop over the modes (vectorised); the others through Discretise.
/// `scratch` holds 16 n doubles, `idx` n ints.
void DiscretiseBatch(int n, const ModePoles* poles, double tau, ModeStep* out, double* scratch,
                     int* idx);

/// Scalar φ_0 … φ_kMaxPhi at a real x (x ≤ 0 in use; stable for any sign of moderate size).
void PhiReal(double x, double* phi);

}  // namespace pz::model::modal
