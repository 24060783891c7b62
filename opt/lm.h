// Bounded Levenberg–Marquardt on a residual vector with a numeric Jacobian, whose columns are one
// batch (threads here, or the BatchEvaluator seam: the service's workers). The global searches are
// in opt/param_search.h; opt/fit.h chains the two and adds the uncertainty table. Socket-free;
// deterministic.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "opt/evaluator.h"
#include "model/status.h"

namespace pz::opt {

/// Runs fn(0 … n−1) on up to `threads` threads (≥ 1); returns when all are done.
void ParallelFor(int n, int threads, const std::function<void(int)>& fn);

/// r(x) into r; false if x cannot be evaluated (then r is ignored). Must be thread-safe.
using ResidualFunction = std::function<bool(std::span<const double> x, std::vector<double>& r)>;

/// Residual vectors of many points at once (a Jacobian's columns as one batch): rs[i] = r(xs[i]),
/// ok[i] = whether xs[i] could be evaluated. Each point's result must not depend on the batch.
using BatchResidualFunction =
    std::function<void(const std::vector<std::vector<double>>& xs,
                       std::vector<std::vector<double>>& rs, std::vector<char>& ok)>;

/// f on up to `threads` threads.
BatchResidualFunction ParallelResiduals(ResidualFunction f, int threads);
/// Through a BatchEvaluator whose fitness returns residuals (genome.reals = x; ok ⇔ status kOk),
/// e.g. the service's workers (svcclient/service_evaluator.h). The evaluator must outlive the
/// function.
BatchResidualFunction EvaluatorResiduals(opt::BatchEvaluator& evaluator);

struct LmOptions {
  int max_iterations = 40;  ///< Jacobian evaluations, ≥ 1
  double fd_step = 1e-3;  ///< finite-difference step in the coordinates of x, > 0 (large enough to
                          ///< step over the kinks of a backlash)
  bool central = true;    ///< central differences (else forward)
  /// With forward differences: where the polish stops by a rule (ftol, xtol, no descent step, every
  /// parameter held) rather than the iteration limit, go on from there with central differences
  /// until it stops again (the same iteration limit in all). Forward differences cost p + 1
  /// evaluations a Jacobian against 2p, and their O(step) error matters only near the end.
  bool central_to_finish = false;
  int threads = 2;        ///< Jacobian columns in parallel, ≥ 1
  double ftol = 1e-7;     ///< stop when an accepted step lowers the cost by less than ftol × cost
  double xtol = 1e-9;     ///< stop when the step is smaller than this (max norm)
  double lambda0 = 1e-3;  ///< initial damping (relative to diag JᵀJ)
  Status Validate() const;
};

struct LmResult {
  std::vector<double> x;     ///< solution (inside the bounds)
  double cost = 0;           ///< Σ r² at x
  std::vector<double> r;     ///< residuals at x
  Eigen::MatrixXd jacobian;  ///< ∂r/∂x at x (last computed; rows = residuals)
  int iterations = 0;
  int64_t evaluations = 0;
  bool converged = false;
  std::string message;
};

/// Bounded Levenberg–Marquardt (Marquardt scaling, variables at a bound whose gradient points out
/// are held). Requires x0 inside [lower, upper] (clamped) and f(x0) evaluable (else the result
/// carries the message and cost +inf).
LmResult LevenbergMarquardt(const ResidualFunction& f, std::vector<double> x0,
                            std::span<const double> lower, std::span<const double> upper,
                            const LmOptions& options);
/// The same with batched evaluations: every Jacobian is one batch (options.threads unused).
LmResult LevenbergMarquardt(const BatchResidualFunction& f, std::vector<double> x0,
                            std::span<const double> lower, std::span<const double> upper,
                            const LmOptions& options);

/// Numeric Jacobian at x with residuals r0 = f(x): central (or forward) differences, one-sided
/// at the bounds, columns in parallel. Returns false if a needed evaluation failed (that column
/// then uses whichever side worked, or zeros).
bool NumericJacobian(const ResidualFunction& f, std::span<const double> x,
                     std::span<const double> r0, std::span<const double> lower,
                     std::span<const double> upper, double step, bool central, int threads,
                     Eigen::MatrixXd& jacobian, int64_t* evaluations);
/// The same, every column's points evaluated as one batch.
bool NumericJacobian(const BatchResidualFunction& f, std::span<const double> x,
                     std::span<const double> r0, std::span<const double> lower,
                     std::span<const double> upper, double step, bool central,
                     Eigen::MatrixXd& jacobian, int64_t* evaluations);

}  // namespace pz::opt
