// Global fit of one model structure (base model + effects) on the training cases of a bench:
// a global search (differential evolution through the BatchEvaluator seam) and/or starts given by
// the caller, then a bounded Levenberg–Marquardt refinement on the residual vector; then the
// parameter uncertainties and the identifiability table from the Jacobian at the solution:
//
//   J = ∂r/∂x (physical parameters, central differences),  s² = Σ r² / (N − p),
//   Cov = s² (JᵀJ)⁺,  σ_i = √Cov_ii,
//   sensitivity_i = ‖J_i‖ · scale_i / √N  (RMS change of the output [deg] per typical step),
//
// and the singular values of J·diag(scale) (how many directions the data constrain). A parameter
// whose column is zero has no effect on the output at all (β and γ when α = 0).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "opt/de_lm.h"
#include "diagnose/problem.h"

namespace pz::diagnose {

/// How strongly the data constrain one parameter.
enum class Identifiability : int {
  kWell = 0,       ///< relative uncertainty ≤ 30 %
  kPoorly = 1,     ///< larger uncertainty (flat or correlated direction)
  kNoEffect = 2,   ///< the output does not depend on it at this point
};
const char* IdentifiabilityName(Identifiability i);

struct ParamEstimate {
  std::string name, unit;
  double value = 0;        ///< physical
  double std_error = 0;    ///< σ_i (inf when not identifiable)
  double sensitivity = 0;  ///< RMS output change [deg] per `scale` of the parameter
  double scale = 1;
  Identifiability identifiability = Identifiability::kWell;
  std::string note;        ///< e.g. "correlated with delta (r = -0.98)"
};

/// Builds the evaluator of a fitness (e.g. an evaluation session on the service, which needs the
/// fitness's model, layout and residual mode to write the session's spec).
using EvaluatorFactory = std::function<std::unique_ptr<opt::BatchEvaluator>(const DiagnosisFitness&)>;

struct FitOptions {
  int threads = 2;                 ///< evaluator threads and Jacobian columns, ≥ 1
  /// Builds the evaluators of the global search (cost) and of the refinement (residuals: every
  /// Jacobian one batch); null = ThreadPoolEvaluators with `threads` threads.
  EvaluatorFactory evaluator_factory;
  bool global_search = true;       ///< differential evolution before the refinement
  opt::DeOptions de;
  opt::LmOptions lm;
  /// Physical points seeding the global search's initial population.
  std::vector<std::vector<double>> seeds;
  /// Physical starting points of the refinement, refined besides the global search's best (the
  /// lowest cost wins). Without a global search at least one is needed.
  std::vector<std::vector<double>> starts;
  bool uncertainty = true;         ///< compute σ and the identifiability table
};

struct FitResult {
  std::vector<model::EffectKind> structure;
  std::string description;          ///< "base + creep"
  std::vector<double> x;            ///< physical parameters (layout order)
  std::vector<ParamEstimate> params;
  double train_pi = 0;              ///< Σ PI training [deg²]
  double withheld_pi = 0;           ///< Σ PI withheld [deg²]
  std::vector<double> case_pi;      ///< every case, in case order [deg²]
  int train_samples = 0, withheld_samples = 0;
  double residual_sigma = 0;        ///< s = √(train_pi / (N − p)) [deg]
  std::vector<double> singular_values;  ///< of J·diag(scale), descending
  std::string weakest_direction;    ///< the parameters of the smallest singular vector
  int64_t evaluations = 0;
  double wall_time_s = 0;
  std::string message;
  bool ok = false;
  int num_params() const { return static_cast<int>(x.size()); }
};

/// Fits the structure of `layout` on the training cases. Never throws for a failed simulation
/// (the result says !ok); throws InputError on invalid options.
FitResult FitGlobal(const DiagnosisModel& model, const ParameterLayout& layout, const FitOptions& options);

/// Computes params (σ, sensitivity, identifiability) and the singular values at fit.x.
void ComputeUncertainty(const DiagnosisModel& model, const ParameterLayout& layout, FitResult& fit, int threads,
                        double fd_step = 1e-3);

/// Training residual function of the model in unit coordinates (for LM), or in physical ones.
opt::ResidualFunction UnitResiduals(const DiagnosisModel& model, const ParameterLayout& layout);

}  // namespace pz::diagnose
