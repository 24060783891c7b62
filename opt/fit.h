// The one fit of physical parameters (issue 21): a global search (opt/param_search.h: PSO, real
// GA, binary GA or differential evolution), then a bounded Levenberg–Marquardt polish from the
// search's best and the caller's starts (opt/lm.h), then the uncertainty table at the solution.
// The record fits (records/fit.h, the fin bench's among them) are its adapter: they supply a
// ParameterMap, their evaluators and their options.
//
// Coordinates: the search and the polish run in unit coordinates u ∈ [0, 1]^p; the ParameterMap
// turns them into physical parameters x (a box, linear or log per parameter, or a custom map: the
// fin searches γ as the ratio γ/β). The evaluators (the BatchEvaluator seam: threads here, the
// service's workers there) get in Genome::reals the physical values when the map says so
// (physical_genomes()), else the unit coordinates.
//
// Uncertainty: J = ∂r/∂x at the solution (physical parameters, central differences in the scaled
// coordinates s_i = x_i / scale_i, one-sided at the bounds), with e = r / w the errors
// (w = residual_weight),
//
//   s² = Σ e² / (N − p),  Cov = s² (JᵀJ)⁺ (over the directions with σ_k > 1e-10 σ_max),
//   σ_i = √Cov_ii,  sensitivity_i = ‖J_i‖ · scale_i / (w √N)  (RMS output change per typical step),
//
// and the singular values of J·diag(scale): how many directions the data constrain, and the
// parameters of the weakest one. A parameter whose column is zero has no effect on the output.
//
// Deterministic: the result is a function of (problem, options) alone, bit for bit, whatever the
// evaluators or their thread counts.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "opt/evaluator.h"
#include "opt/lm.h"
#include "opt/param_search.h"

namespace pz::opt {

/// How strongly the data constrain one parameter.
enum class Identifiability : int {
  kWell = 0,      ///< relative uncertainty ≤ 30 %
  kPoorly = 1,    ///< larger uncertainty (flat or correlated direction)
  kNoEffect = 2,  ///< the output does not depend on it at this point
};
/// "well constrained", "poorly constrained", "no effect".
const char* IdentifiabilityName(Identifiability i);

/// One row of the uncertainty table.
struct ParamEstimate {
  std::string name, unit;
  double value = 0;        ///< physical
  double std_error = 0;    ///< σ_i (inf when not identifiable)
  double sensitivity = 0;  ///< RMS output change per `scale` of the parameter
  double scale = 1;
  Identifiability identifiability = Identifiability::kWell;
  std::string note;  ///< e.g. "correlated with delta (r = -0.980)"
};

/// The uncertainty table at a solution (empty when the residuals there could not be computed).
struct Uncertainty {
  std::vector<ParamEstimate> params;
  double residual_sigma = 0;            ///< s [output unit]
  std::vector<double> singular_values;  ///< of J·diag(scale), descending
  std::string weakest_direction;        ///< the parameters of the smallest singular vector
  int64_t evaluations = 0;              ///< of the Jacobian
};

/// Unit coordinates ↔ physical parameters, with each parameter's name, unit, bounds and scale.
class ParameterMap {
 public:
  virtual ~ParameterMap() = default;
  virtual int size() const = 0;
  virtual std::string name(int i) const = 0;
  virtual std::string unit(int i) const = 0;
  /// u ∈ [0, 1]^p (clamped) → x.
  virtual std::vector<double> ToPhysical(std::span<const double> unit) const = 0;
  /// x → u (clamped into [0, 1]).
  virtual std::vector<double> ToUnit(std::span<const double> physical) const = 0;
  /// The physical bounds of parameter i at the point x (a ratio parameter's depend on x).
  virtual void Bounds(std::span<const double> x, int i, double* lower, double* upper) const = 0;
  /// The typical magnitude of parameter i at x (finite-difference steps, sensitivities), > 0.
  virtual double Scale(std::span<const double> x, int i) const = 0;
  /// True: the evaluators get physical values, and the global search runs in SearchBox() = the
  /// map's box. False: they get unit coordinates, and the search runs in the unit box.
  virtual bool physical_genomes() const = 0;
  /// The box of the global search (its physical values are the genomes).
  virtual ParamBox SearchBox() const = 0;
};

/// The map of a box (linear or log10 per parameter); the evaluators get physical values. Scale:
/// the range (linear) or x · ln(upper / lower) (log), i.e. ∂x/∂u.
class BoxMap final : public ParameterMap {
 public:
  /// Throws InputError on an invalid box; `units` empty or one per parameter.
  BoxMap(ParamBox box, std::vector<std::string> units = {});
  int size() const override { return static_cast<int>(box_.size()); }
  std::string name(int i) const override { return box_.names[i]; }
  std::string unit(int i) const override { return units_.empty() ? std::string() : units_[i]; }
  std::vector<double> ToPhysical(std::span<const double> unit) const override;
  std::vector<double> ToUnit(std::span<const double> physical) const override;
  void Bounds(std::span<const double> x, int i, double* lower, double* upper) const override;
  double Scale(std::span<const double> x, int i) const override;
  bool physical_genomes() const override { return true; }
  ParamBox SearchBox() const override { return box_; }
  const ParamBox& box() const { return box_; }

 private:
  ParamBox box_;
  std::vector<std::string> units_;
};

/// The unit box [0, 1]^p with these names (the search box of a map whose genomes are unit
/// coordinates).
ParamBox UnitBox(const ParameterMap& map);

/// Builds an evaluator (a thread pool, or a session on the service); called when the fit needs it.
using EvaluatorMaker = std::function<std::unique_ptr<BatchEvaluator>()>;

/// What a fit needs of its problem. Everything must outlive the fit.
struct FitProblem {
  const ParameterMap* map = nullptr;
  /// The cost of a genome, for the global search.
  EvaluatorMaker cost_evaluator;
  /// The residual vector of a genome (FitnessResult::residuals, ok ⇔ kOk), for the polish: every
  /// Jacobian is one batch.
  EvaluatorMaker residual_evaluator;
  /// The residuals at physical points, on this machine (the uncertainty's Jacobian); thread-safe.
  ResidualFunction physical_residuals;
  /// The residuals are the errors times this (e.g. 1/√N, so that Σ r² is the mean squared error).
  double residual_weight = 1;
};

struct FitOptions {
  bool search = true;            ///< run the global search
  SearchOptions search_options;  ///< seeds: unit coordinates
  bool polish = true;            ///< Levenberg–Marquardt from the search's best and `starts`
  LmOptions lm;                  ///< lm.threads unused (the residual evaluator has its own)
  /// Starting points of the polish besides the search's best (unit coordinates), in this order.
  /// Without a search at least one is needed.
  std::vector<std::vector<double>> starts;
  /// Polish also the best points of up to this many other repetitions of the search (by their cost,
  /// skipping one within 1e-3 of an earlier start in every unit coordinate), after the search's
  /// best and `starts`: the search's best is one basin among the repetitions'. Such a polish
  /// replaces the one kept only when its cost is lower by more than the relative `basin_margin` (a
  /// polish of the same basin from elsewhere lands within it), so that where the repetitions agree
  /// the result is the search's best's polish. 0 = none.
  int polish_repetitions = 0;
  double basin_margin = 1e-4;  ///< ≥ 0
  /// Run the polishes side by side on up to `threads` threads, each with its own residual evaluator
  /// (problem.residual_evaluator called once per polish, concurrently: it must allow that); they
  /// are then taken in start order exactly as one after another, so the fit is the same bit for
  /// bit. A polish's trial steps are one evaluation each, so one polish at a time leaves a core
  /// idle.
  bool concurrent_polishes = false;
  /// The search's cost is Σ r² of the residuals: a polished point is then kept only where it
  /// lowers the search's cost, and the search's best stands when every polish fails. Otherwise the
  /// best polish wins whatever the search's cost, and a fit whose polishes all fail fails.
  bool search_cost_is_sum_of_squares = false;
  bool uncertainty = true;            ///< compute the uncertainty table at the solution
  double uncertainty_fd_step = 1e-3;  ///< in the scaled coordinates x / scale, > 0
  int threads = 2;                    ///< Jacobian columns of the uncertainty, ≥ 1
};

struct FitResult {
  bool ok = false;
  std::vector<double> x;  ///< physical parameters
  double cost = 0;        ///< Σ r² of the polished solution, or the search's cost
  bool searched = false;
  SearchResult search;    ///< when searched
  int lm_iterations = 0;  ///< all polishes
  int best_polish = -1;   ///< index of the polish kept (0 = from the search's best when
                         ///< searched, then `starts`, then the other repetitions' bests), −1 = none
  int polishes = 0;                 ///< polishes run
  int best_polish_repetition = -1;  ///< the search repetition whose best the kept polish started
                                    ///< from (−1: a caller's start, or none)
  int best_polish_iterations = 0;
  std::string polish_message;  ///< of the polish kept, or of the last one that failed
  int64_t evaluations = 0;     ///< search and polish (not the uncertainty's)
  Uncertainty uncertainty;
  std::string message;  ///< "global search: …; refinement: … after n iterations"
  double wall_time_s = 0;
};

/// Runs the fit. Throws InputError on invalid options or starts, or a problem missing what its
/// options need. A failure of the model is not thrown: the result says !ok.
FitResult Fit(const FitProblem& problem, const FitOptions& options);

/// The Jacobian of f (f0 = f(x)) at the physical point x in the scaled coordinates s_i = x_i /
/// map.Scale(x, i), where one step `fd_step` suits every parameter: central differences, one-sided
/// at a bound, columns on `threads` threads (opt::NumericJacobian). ∂f/∂x_i = js.col(i) / scale[i].
/// False if an evaluation failed (that column then from the side that worked, or zeros).
bool ScaledJacobian(const ParameterMap& map, const ResidualFunction& f, std::span<const double> x,
                    std::span<const double> f0, double fd_step, int threads, Eigen::MatrixXd& js,
                    std::vector<double>& scale, int64_t* evaluations = nullptr);

/// The uncertainty table of the parameters x of `map`, from the residuals at physical points.
/// Leaves it empty if the residuals at x cannot be computed.
Uncertainty ComputeUncertainty(const ParameterMap& map, const ResidualFunction& physical_residuals,
                               std::span<const double> x, int threads, double fd_step = 1e-3,
                               double residual_weight = 1);

}  // namespace pz::opt
