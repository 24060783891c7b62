// Global fit of one model structure (base model + effects) on the training cases of a bench: the
// one fit of opt/fit.h (differential evolution through the BatchEvaluator seam and/or starts given
// by the caller, a bounded Levenberg–Marquardt polish on the residual vector, the uncertainty and
// identifiability table at the solution) over the layout's coordinates (γ searched as the ratio
// γ/β), plus every case's PI. A parameter whose column is zero has no effect on the output at all
// (β and γ when α = 0).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "opt/fit.h"
#include "diagnose/problem.h"

namespace pz::diagnose {

using opt::Identifiability;
using opt::IdentifiabilityName;
using opt::ParamEstimate;

/// Builds the evaluator of a fitness (e.g. an evaluation session on the service, which needs the
/// fitness's model, layout and residual mode to write the session's spec).
using EvaluatorFactory =
    std::function<std::unique_ptr<opt::BatchEvaluator>(const DiagnosisFitness&)>;

struct FitOptions {
  int threads = 2;  ///< evaluator threads and Jacobian columns, ≥ 1
  /// Builds the evaluators of the global search (cost) and of the refinement (residuals: every
  /// Jacobian one batch); null = ThreadPoolEvaluators with `threads` threads.
  EvaluatorFactory evaluator_factory;
  bool global_search = true;  ///< differential evolution before the refinement (one repetition)
  opt::DeOptions de;
  opt::LmOptions lm;
  /// Physical points seeding the global search's initial population.
  std::vector<std::vector<double>> seeds;
  /// Physical starting points of the refinement, refined besides the global search's best (the
  /// lowest cost wins). Without a global search at least one is needed.
  std::vector<std::vector<double>> starts;
  bool uncertainty = true;  ///< compute σ and the identifiability table
};

struct FitResult {
  std::vector<model::EffectKind> structure;
  std::string description;  ///< "base + creep"
  std::vector<double> x;    ///< physical parameters (layout order)
  std::vector<ParamEstimate> params;
  double train_pi = 0;          ///< Σ PI training [deg²]
  double withheld_pi = 0;       ///< Σ PI withheld [deg²]
  std::vector<double> case_pi;  ///< every case, in case order [deg²]
  int train_samples = 0, withheld_samples = 0;
  double residual_sigma = 0;            ///< s = √(train_pi / (N − p)) [deg]
  std::vector<double> singular_values;  ///< of J·diag(scale), descending
  std::string weakest_direction;        ///< the parameters of the smallest singular vector
  int64_t evaluations = 0;
  double wall_time_s = 0;
  std::string message;
  bool ok = false;
  int num_params() const { return static_cast<int>(x.size()); }
};

/// Fits the structure of `layout` on the training cases. Never throws for a failed simulation
/// (the result says !ok); throws InputError on invalid options.
FitResult FitGlobal(const DiagnosisModel& model, const ParameterLayout& layout,
                    const FitOptions& options);

/// Computes params (σ, sensitivity, identifiability) and the singular values at fit.x
/// (opt::ComputeUncertainty on the training residuals); its evaluations are added to fit's.
void ComputeUncertainty(const DiagnosisModel& model, const ParameterLayout& layout, FitResult& fit,
                        int threads, double fd_step = 1e-3);

/// The layout as the fit's parameter map: unit coordinates (what the evaluators get) ↔ physical,
/// γ through the ratio γ/β (its bounds at a point are the ratio's times β).
class LayoutMap final : public opt::ParameterMap {
 public:
  explicit LayoutMap(const ParameterLayout& layout) : layout_(layout) {}
  int size() const override { return layout_.size(); }
  std::string name(int i) const override { return layout_.specs()[i].name; }
  std::string unit(int i) const override { return layout_.specs()[i].unit; }
  std::vector<double> ToPhysical(std::span<const double> unit) const override {
    return layout_.FromUnit(unit);
  }
  std::vector<double> ToUnit(std::span<const double> physical) const override {
    return layout_.ToUnit(physical);
  }
  void Bounds(std::span<const double> x, int i, double* lower, double* upper) const override;
  double Scale(std::span<const double>, int i) const override { return layout_.specs()[i].scale; }
  bool physical_genomes() const override { return false; }
  opt::ParamBox SearchBox() const override { return opt::UnitBox(*this); }

 private:
  const ParameterLayout& layout_;
};

}  // namespace pz::diagnose
