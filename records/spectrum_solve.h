// The creep spectrum solved with a linear family's weights (issue 22): a linear family (its weights
// θ ≥ 0 solved by non-negative least squares, regressors A) with `creep-spectrum` (weights w ≥ 0 of
// relaxations L_i of the output) has an output bilinear in (θ, w),
//
//   ŷ = L_w A θ = A θ − Σ_i w_i B_i θ,   B_i = (I − L_i) A,
//
// so for given drive-effect parameters (a delay) both are solved together instead of w being
// searched:
//
//   min_{θ ≥ 0, 0 ≤ w ≤ w_max}  ‖b − L_w A θ‖² + λ θᵀRθ + μ ‖D w‖²
//
// (R, λ: the family's regularisation and its strength; D, μ: the spectrum's roughness and its
// strength; b and the rows centred as the records' offsets have them, records/fit.h AddRecordRows).
// A projected Gauss–Newton iteration in (θ, w): at (θ, w) the output is linear in (θ', w') up to
// the product of the steps, ŷ ≈ C(w) θ' − Z (w' − w) with C(w) = L_w A and Z = [B_i θ]; the
// linearised problem is one non-negative least squares in m + n unknowns over the normal equations
// of [C(w) | −Z] (one pass over the samples: A's columns through the combined relaxations, then the
// Gram, as one evaluation of the searched spectrum costs; B_i θ = (I − L_i)(A θ) is one filtered
// signal per relaxation); the steps after the first reuse those normal equations (rebuilt after 3
// steps or a move of 0.02), and where a fit shares the reference's (SpectrumMetric) the first 8
// steps take those and none is built unless they do not converge — the gradient is exact in every
// step (the relaxations' adjoint on the residual, then Aᵀ), so the iteration still converges to the
// optimum of f. A step is kept only where the exact objective decreases (halved up to 30
// times; a weight leaving its upper bound shortens it), so the objective never increases; it stops
// when a step gains less than 1e-9 of the objective. The starts: w = 0 with θ solved there (the
// family's own solve) and log creep (equal weights), the lower kept; or one given start — a fit
// solves from both once, at the effects' neutral parameters, and starts every evaluation from that
// reference (fixed, so the result does not depend on the order of the evaluations), a few steps
// from the optimum at any delay.
//
// Deterministic: sums in a fixed order, no threads; the same result whatever the caller's thread.
#pragma once

#include <Eigen/Dense>
#include <span>
#include <vector>

#include "io/records.h"
#include "records/model.h"

namespace pz::records {

/// The normal equations of C(w) = L_w A built once for a reference (the records' scored rows of C,
/// centred, and CᵀC): a metric the steps of every solve of the same records can start in, before
/// they build their own (BuildSpectrumMetric).
struct SpectrumMetric {
  std::vector<Eigen::MatrixXd> C;  ///< per record
  Eigen::MatrixXd G;
};

/// What the joint solve needs; everything must outlive the call.
struct SpectrumProblem {
  const RecordModel* model = nullptr;
  std::span<const io::Record* const> records;
  size_t samples = 0;           ///< scored samples over the records
  size_t first = 0, count = 0;  ///< the spectrum's weights in the model's parameters
  const Eigen::MatrixXd* regularisation = nullptr;  ///< R (null or empty: none)
  double lambda = 0;                                ///< its strength
  const Eigen::MatrixXd* roughness = nullptr;       ///< D (n−1 × n)
  double mu = 0;                                    ///< its strength
  /// Also start from log creep (equal weights of this value, clamped to the box) and keep the lower
  /// optimum; ≤ 0: from w = 0 only.
  double log_creep_start = 0.01;
  bool zero_start = true;  ///< start from w = 0 (false: from log creep alone)
  /// Non-empty (count values in the box): start from these weights alone instead (a fit's
  /// reference: RecordFitness::spectrum_start).
  std::vector<double> start;
  /// With `start`: the family's weights solved there; the start is then the spectrum's weights
  /// best for them on this problem (one solve in the n weights), else `start` itself.
  std::vector<double> start_theta;
  /// With start and start_theta: the first steps from (start_theta, the weights best for it) in
  /// this metric (no build of the normal equations unless they do not converge in 8 steps).
  const SpectrumMetric* metric = nullptr;
};

struct SpectrumSolution {
  bool ok = false;            ///< false: the output was not finite
  std::vector<double> w;      ///< the spectrum's weights
  std::vector<double> theta;  ///< the family's weights at w (as the iteration has them)
  double sse = 0;             ///< Σ e² over the scored samples
  double roughness = 0;       ///< μ ‖D w‖²
  double objective = 0;       ///< sse + λ θᵀRθ + μ ‖D w‖²
  int iterations = 0;         ///< Gauss–Newton steps taken (all starts)
  int grams = 0;              ///< passes over the samples building normal equations
  int start = 0;              ///< the start kept: 0 = w = 0, 1 = log creep, 2 = the given one
  std::vector<double>
      objectives;  ///< of the kept start: at its start, then after every step (non-increasing)
};

/// True when a fit solves the model's creep spectrum with the family's weights instead of searching
/// it: a linear family whose only output effect is `creep-spectrum` (a non-linear output effect
/// after it would make the solved output not the model's).
bool SpectrumSolved(const RecordModel& model);
/// The indices in model.params() of the parameters a fit searches: all of them, or all but the
/// spectrum's weights where SpectrumSolved.
std::vector<size_t> SearchedParams(const RecordModel& model);

/// The metric of the problem's records at `params` and the spectrum's weights w.
SpectrumMetric BuildSpectrumMetric(const SpectrumProblem& problem, std::span<const double> params,
                                   std::span<const double> w);

/// Solves (θ, w) at the model parameters `params` (the spectrum's entries ignored). Throws
/// InputError on a model that is not a linear family with the spectrum among its leading linear
/// output effects, or a parameter count mismatch.
SpectrumSolution SolveSpectrum(const SpectrumProblem& problem, std::span<const double> params);

}  // namespace pz::records
