// Optimisers of the diagnosis: a real-coded global search (differential evolution) that evaluates
// whole generations through the BatchEvaluator seam (inline, thread pool, or the service), and a
// bounded Levenberg–Marquardt refinement on the residual vector with a numeric Jacobian (columns in
// parallel). Socket-free; deterministic for a seed (the master owns the only generator).
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

/// Differential evolution DE/rand-to-best/1/bin on the unit box [0, 1]^dim.
struct DeOptions {
  int population = 32;        ///< ≥ 4
  int generations = 60;       ///< generations after the initial one, ≥ 0
  int stall_generations = 15; ///< stop after this many generations without a relative gain > tol, ≥ 1
  double tolerance = 1e-4;    ///< relative gain that counts as progress, ≥ 0
  double f = 0.6;             ///< differential weight, in (0, 2]
  double cr = 0.9;            ///< crossover probability, in [0, 1]
  uint64_t seed = 1;
  Status Validate() const;
};

struct DeResult {
  std::vector<double> best;  ///< unit coordinates
  double best_cost = 0;
  int generations = 0;
  int64_t evaluations = 0;
  double wall_time_s = 0;
  std::string message;
};

/// Minimises the fitness behind `evaluator` (genome.reals = unit coordinates). `seeds` (each of
/// size dim, clamped into the box) take the first slots of the initial population, the rest is
/// drawn uniformly. Throws InputError on invalid options or seeds.
DeResult DifferentialEvolution(int dim, const DeOptions& options, opt::BatchEvaluator& evaluator,
                               std::span<const std::vector<double>> seeds = {});

/// r(x) into r; false if x cannot be evaluated (then r is ignored). Must be thread-safe.
using ResidualFunction = std::function<bool(std::span<const double> x, std::vector<double>& r)>;

/// Residual vectors of many points at once (a Jacobian's columns as one batch): rs[i] = r(xs[i]),
/// ok[i] = whether xs[i] could be evaluated. Each point's result must not depend on the batch.
using BatchResidualFunction =
    std::function<void(const std::vector<std::vector<double>>& xs, std::vector<std::vector<double>>& rs,
                       std::vector<char>& ok)>;

/// f on up to `threads` threads.
BatchResidualFunction ParallelResiduals(ResidualFunction f, int threads);
/// Through a BatchEvaluator whose fitness returns residuals (genome.reals = x; ok ⇔ status kOk),
/// e.g. the service's workers (client/service_evaluator.h). The evaluator must outlive the function.
BatchResidualFunction EvaluatorResiduals(opt::BatchEvaluator& evaluator);

struct LmOptions {
  int max_iterations = 40;   ///< Jacobian evaluations, ≥ 1
  double fd_step = 1e-3;     ///< finite-difference step in the coordinates of x, > 0 (large enough to
                             ///< step over the kinks of a backlash)
  bool central = true;       ///< central differences (else forward)
  int threads = 2;           ///< Jacobian columns in parallel, ≥ 1
  double ftol = 1e-7;        ///< stop when an accepted step lowers the cost by less than ftol × cost
  double xtol = 1e-9;        ///< stop when the step is smaller than this (max norm)
  double lambda0 = 1e-3;     ///< initial damping (relative to diag JᵀJ)
  Status Validate() const;
};

struct LmResult {
  std::vector<double> x;      ///< solution (inside the bounds)
  double cost = 0;            ///< Σ r² at x
  std::vector<double> r;      ///< residuals at x
  Eigen::MatrixXd jacobian;   ///< ∂r/∂x at x (last computed; rows = residuals)
  int iterations = 0;
  int64_t evaluations = 0;
  bool converged = false;
  std::string message;
};

/// Bounded Levenberg–Marquardt (Marquardt scaling, variables at a bound whose gradient points out
/// are held). Requires x0 inside [lower, upper] (clamped) and f(x0) evaluable (else the result
/// carries the message and cost +inf).
LmResult LevenbergMarquardt(const ResidualFunction& f, std::vector<double> x0, std::span<const double> lower,
                            std::span<const double> upper, const LmOptions& options);
/// The same with batched evaluations: every Jacobian is one batch (options.threads unused).
LmResult LevenbergMarquardt(const BatchResidualFunction& f, std::vector<double> x0, std::span<const double> lower,
                            std::span<const double> upper, const LmOptions& options);

/// Numeric Jacobian at x with residuals r0 = f(x): central (or forward) differences, one-sided
/// at the bounds, columns in parallel. Returns false if a needed evaluation failed (that column
/// then uses whichever side worked, or zeros).
bool NumericJacobian(const ResidualFunction& f, std::span<const double> x, std::span<const double> r0,
                     std::span<const double> lower, std::span<const double> upper, double step, bool central,
                     int threads, Eigen::MatrixXd& jacobian, int64_t* evaluations);
/// The same, every column's points evaluated as one batch.
bool NumericJacobian(const BatchResidualFunction& f, std::span<const double> x, std::span<const double> r0,
                     std::span<const double> lower, std::span<const double> upper, double step, bool central,
                     Eigen::MatrixXd& jacobian, int64_t* evaluations);

}  // namespace pz::opt
