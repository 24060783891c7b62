#include "diagnose/fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>

#include "opt/thread_pool_evaluator.h"

namespace pz::diagnose {

using opt::BatchResidualFunction;
using opt::DeResult;
using opt::DifferentialEvolution;
using opt::EvaluatorResiduals;
using opt::LevenbergMarquardt;
using opt::LmResult;
using opt::NumericJacobian;
using opt::ResidualFunction;

const char* IdentifiabilityName(Identifiability i) {
  switch (i) {
    case Identifiability::kWell: return "well constrained";
    case Identifiability::kPoorly: return "poorly constrained";
    case Identifiability::kNoEffect: return "no effect";
  }
  return "?";
}

ResidualFunction UnitResiduals(const DiagnosisModel& model, const ParameterLayout& layout) {
  return [&model, &layout](std::span<const double> u, std::vector<double>& r) {
    const std::vector<double> x = layout.FromUnit(u);
    return model.Residuals(layout, x, true, r);
  };
}

void ComputeUncertainty(const DiagnosisModel& model, const ParameterLayout& layout, FitResult& fit, int threads,
                        double fd_step) {
  const int n = layout.size();
  const auto& specs = layout.specs();
  std::vector<double> r0;
  if (!model.Residuals(layout, fit.x, true, r0)) return;
  const int m = static_cast<int>(r0.size());
  // Physical bounds (γ within [−0.98 β, β], the bounded region).
  std::vector<double> lo(n), hi(n), step(n);
  for (int i = 0; i < n; ++i) {
    lo[i] = specs[i].ratio ? specs[i].lower * fit.x[3] : specs[i].lower;
    hi[i] = specs[i].ratio ? specs[i].upper * fit.x[3] : specs[i].upper;
    step[i] = fd_step * specs[i].scale;
  }
  // Scaled coordinates: x_i = scale_i s_i, so J_s = J diag(scale) with a uniform step.
  std::vector<double> s0(n), slo(n), shi(n);
  for (int i = 0; i < n; ++i) {
    s0[i] = fit.x[i] / specs[i].scale;
    slo[i] = lo[i] / specs[i].scale;
    shi[i] = hi[i] / specs[i].scale;
  }
  ResidualFunction fs = [&](std::span<const double> s, std::vector<double>& r) {
    std::vector<double> x(n);
    for (int i = 0; i < n; ++i) x[i] = s[i] * specs[i].scale;
    return model.Residuals(layout, x, true, r);
  };
  Eigen::MatrixXd js;
  NumericJacobian(fs, s0, r0, slo, shi, fd_step, true, threads, js, &fit.evaluations);
  double sse = 0;
  for (double e : r0) sse += e * e;
  const double dof = std::max(1, m - n);
  const double s2 = sse / dof;
  fit.residual_sigma = std::sqrt(s2);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(js, Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  fit.singular_values.assign(sv.data(), sv.data() + sv.size());
  const double smax = sv.size() ? sv[0] : 0;
  // Pseudo-inverse of JᵀJ over the directions the data see (σ_k > 1e-10 σ_max).
  const Eigen::MatrixXd v = svd.matrixV();
  Eigen::MatrixXd cov = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < sv.size(); ++k)
    if (sv[k] > 1e-10 * smax) cov += (v.col(k) * v.col(k).transpose()) / (sv[k] * sv[k]);
  cov *= s2;
  // Weakest direction: the parameters carrying the smallest singular vector.
  if (sv.size()) {
    const Eigen::VectorXd w = v.col(sv.size() - 1);
    std::vector<std::pair<double, int>> parts;
    for (int i = 0; i < n; ++i) parts.push_back({std::abs(w[i]), i});
    std::sort(parts.rbegin(), parts.rend());
    char buf[160];
    std::snprintf(buf, sizeof buf, "singular value %.3g (of %.3g):", sv[sv.size() - 1], smax);
    fit.weakest_direction = buf;
    for (int k = 0; k < std::min(3, n); ++k) {
      std::snprintf(buf, sizeof buf, " %s%s %.2f", k ? "," : "", specs[parts[k].second].name.c_str(),
                    w[parts[k].second]);
      fit.weakest_direction += buf;
    }
  }
  fit.params.clear();
  for (int i = 0; i < n; ++i) {
    ParamEstimate p;
    p.name = specs[i].name;
    p.unit = specs[i].unit;
    p.value = fit.x[i];
    p.scale = specs[i].scale;
    const double col = js.col(i).norm();
    p.sensitivity = col / std::sqrt(static_cast<double>(m));
    const double colmax = js.colwise().norm().maxCoeff();
    if (!(col > 1e-9 * colmax) || col == 0.0) {
      p.identifiability = Identifiability::kNoEffect;
      p.std_error = std::numeric_limits<double>::infinity();
      p.note = "the output does not depend on it here";
      if ((p.name == "beta" || p.name == "gamma") && fit.x[2] == 0.0) p.note += " (alpha = 0: z stays 0)";
    } else {
      p.std_error = std::sqrt(std::max(0.0, cov(i, i))) * specs[i].scale;
      const double ref = std::max(std::abs(p.value), 0.1 * specs[i].scale);
      p.identifiability = p.std_error <= 0.3 * ref ? Identifiability::kWell : Identifiability::kPoorly;
      // Strongest correlation with another parameter.
      double best = 0;
      int bj = -1;
      for (int j = 0; j < n; ++j) {
        if (j == i || cov(i, i) <= 0 || cov(j, j) <= 0) continue;
        const double r = cov(i, j) / std::sqrt(cov(i, i) * cov(j, j));
        if (std::abs(r) > std::abs(best)) {
          best = r;
          bj = j;
        }
      }
      if (bj >= 0 && std::abs(best) > 0.9) {
        char buf[128];
        std::snprintf(buf, sizeof buf, "correlated with %s (r = %.3f)", specs[bj].name.c_str(), best);
        p.note = buf;
      }
    }
    fit.params.push_back(p);
  }
}

FitResult FitGlobal(const DiagnosisModel& model, const ParameterLayout& layout, const FitOptions& o) {
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
        throw InputError(FieldError(std::string(what) + "[].size()", s.size(), "must be " + std::to_string(n)));
      u.push_back(layout.ToUnit(s));
    }
    return u;
  };
  const std::vector<std::vector<double>> unit_seeds = to_unit(o.seeds, "seeds");
  std::vector<std::vector<double>> lm_starts = to_unit(o.starts, "starts");
  if (o.global_search) {
    DiagnosisFitness fitness(model, layout);
    std::unique_ptr<opt::BatchEvaluator> ev =
        o.evaluator_factory ? o.evaluator_factory(fitness)
                            : std::make_unique<opt::ThreadPoolEvaluator>(fitness, o.threads);
    const DeResult de = DifferentialEvolution(n, o.de, *ev, unit_seeds);
    fit.evaluations += de.evaluations;
    lm_starts.insert(lm_starts.begin(), de.best);
    fit.message = "global search: " + de.message + "; ";
  }
  if (lm_starts.empty()) throw InputError("FitGlobal: no global search and no starting point");

  // The refinement's residuals through the same seam (DiagnosisFitness with residuals: the
  // training residuals at FromUnit(u), as UnitResiduals), so every Jacobian is one batch.
  const DiagnosisFitness residual_fitness(model, layout, /*residuals=*/true);
  std::unique_ptr<opt::BatchEvaluator> rev =
      o.evaluator_factory ? o.evaluator_factory(residual_fitness)
                          : std::make_unique<opt::ThreadPoolEvaluator>(residual_fitness, o.lm.threads);
  const BatchResidualFunction f = EvaluatorResiduals(*rev);
  std::vector<double> lo(n, 0.0), hi(n, 1.0);
  LmResult best;
  best.cost = std::numeric_limits<double>::infinity();
  for (const auto& s : lm_starts) {
    LmResult r = LevenbergMarquardt(f, s, lo, hi, o.lm);
    fit.evaluations += r.evaluations;
    if (r.cost < best.cost) best = std::move(r);
  }
  if (!std::isfinite(best.cost)) {
    fit.message += "refinement failed: " + best.message;
    fit.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return fit;
  }
  fit.message += "refinement: " + best.message + " after " + std::to_string(best.iterations) + " iterations";
  fit.x = layout.FromUnit(best.x);
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
