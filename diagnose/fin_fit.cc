#include "diagnose/fin_fit.h"

#include <chrono>
#include <cmath>
#include <memory>

#include "opt/thread_pool_evaluator.h"

namespace pz::diagnose {

void LayoutMap::Bounds(std::span<const double> x, int i, double* lower, double* upper) const {
  const ParamSpec& s = layout_.specs()[i];
  *lower = s.ratio ? s.lower * x[3] : s.lower;  // γ within [−0.98 β, β], the bounded region
  *upper = s.ratio ? s.upper * x[3] : s.upper;
}

namespace {

opt::ResidualFunction TrainingResiduals(const DiagnosisModel& model,
                                        const ParameterLayout& layout) {
  return [&model, &layout](std::span<const double> x, std::vector<double>& r) {
    return model.Residuals(layout, x, true, r);
  };
}

void SetUncertainty(opt::Uncertainty u, FitResult& fit) {
  for (ParamEstimate& p : u.params) {
    if (p.identifiability == Identifiability::kNoEffect &&
        (p.name == "beta" || p.name == "gamma") && fit.x[2] == 0.0)
      p.note += " (alpha = 0: z stays 0)";
  }
  fit.params = std::move(u.params);
  fit.residual_sigma = u.residual_sigma;
  fit.singular_values = std::move(u.singular_values);
  fit.weakest_direction = std::move(u.weakest_direction);
  fit.evaluations += u.evaluations;
}

}  // namespace

void ComputeUncertainty(const DiagnosisModel& model, const ParameterLayout& layout, FitResult& fit,
                        int threads, double fd_step) {
  const LayoutMap map(layout);
  SetUncertainty(
      opt::ComputeUncertainty(map, TrainingResiduals(model, layout), fit.x, threads, fd_step), fit);
}

FitResult FitGlobal(const DiagnosisModel& model, const ParameterLayout& layout,
                    const FitOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  ThrowIfError(o.de.Validate());
  ThrowIfError(o.lm.Validate());
  if (o.threads < 1) throw InputError(FieldError("threads", o.threads, "must be >= 1"));
  const int n = layout.size();
  FitResult fit;
  fit.structure = layout.structure();
  fit.description = layout.Describe();
  fit.train_samples = model.training_samples();
  fit.withheld_samples = model.withheld_samples();

  auto to_unit = [&](const std::vector<std::vector<double>>& pts, const char* what) {
    std::vector<std::vector<double>> u;
    for (const auto& s : pts) {
      if (s.size() != static_cast<size_t>(n))
        throw InputError(
            FieldError(std::string(what) + "[].size()", s.size(), "must be " + std::to_string(n)));
      u.push_back(layout.ToUnit(s));
    }
    return u;
  };
  const LayoutMap map(layout);
  // The search's cost CF = Σ PI and the polish's training residuals, both over unit coordinates
  // (DiagnosisFitness), through the same seam: every generation and every Jacobian is one batch.
  const DiagnosisFitness fitness(model, layout);
  const DiagnosisFitness residual_fitness(model, layout, /*residuals=*/true);
  opt::FitProblem problem;
  problem.map = &map;
  problem.cost_evaluator = [&]() -> std::unique_ptr<opt::BatchEvaluator> {
    if (o.evaluator_factory) return o.evaluator_factory(fitness);
    return std::make_unique<opt::ThreadPoolEvaluator>(fitness, o.threads);
  };
  problem.residual_evaluator = [&]() -> std::unique_ptr<opt::BatchEvaluator> {
    if (o.evaluator_factory) return o.evaluator_factory(residual_fitness);
    return std::make_unique<opt::ThreadPoolEvaluator>(residual_fitness, o.lm.threads);
  };
  opt::FitOptions fo;
  fo.search = o.global_search;
  fo.search_options.algorithm = opt::SearchAlgorithm::kDe;
  fo.search_options.de = o.de;
  fo.search_options.repetitions = 1;
  fo.search_options.seeds = to_unit(o.seeds, "seeds");
  fo.lm = o.lm;
  fo.starts = to_unit(o.starts, "starts");
  fo.uncertainty = false;  // below, once every case's PI is known to be finite
  const opt::FitResult r = opt::Fit(problem, fo);
  fit.evaluations = r.evaluations;
  fit.message = r.message;
  if (!r.ok) {
    fit.wall_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return fit;
  }
  fit.x = r.x;
  fit.case_pi = model.CasePi(layout, fit.x);
  fit.ok = true;
  for (size_t c = 0; c < model.cases().size(); ++c) {
    if (!std::isfinite(fit.case_pi[c])) fit.ok = false;
    (model.cases()[c].training ? fit.train_pi : fit.withheld_pi) += fit.case_pi[c];
  }
  if (o.uncertainty && fit.ok) ComputeUncertainty(model, layout, fit, o.threads);
  fit.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return fit;
}

}  // namespace pz::diagnose
