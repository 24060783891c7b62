#include "opt/fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <limits>
#include <utility>

namespace pz::opt {

const char* IdentifiabilityName(Identifiability i) {
  switch (i) {
    case Identifiability::kWell:
      return "well constrained";
    case Identifiability::kPoorly:
      return "poorly constrained";
    case Identifiability::kNoEffect:
      return "no effect";
  }
  return "?";
}

// ---- maps
// ------------------------------------------------------------------------------------------

BoxMap::BoxMap(ParamBox box, std::vector<std::string> units)
    : box_(std::move(box)), units_(std::move(units)) {
  ThrowIfError(box_.Validate());
  if (!units_.empty() && units_.size() != box_.size())
    throw InputError(
        FieldError("units.size()", units_.size(), "must be 0 or " + std::to_string(box_.size())));
}

std::vector<double> BoxMap::ToPhysical(std::span<const double> unit) const {
  std::vector<double> x(box_.size());
  box_.ToPhysical(unit.data(), x.data());
  return x;
}

std::vector<double> BoxMap::ToUnit(std::span<const double> physical) const {
  std::vector<double> u(box_.size());
  box_.ToUnit(physical.data(), u.data());
  return u;
}

void BoxMap::Bounds(std::span<const double>, int i, double* lower, double* upper) const {
  *lower = box_.lower[i];
  *upper = box_.upper[i];
}

double BoxMap::Scale(std::span<const double> x, int i) const {
  if (!box_.log_scale.empty() && box_.log_scale[i])
    return std::max(x[i], box_.lower[i]) * std::log(box_.upper[i] / box_.lower[i]);
  return box_.upper[i] - box_.lower[i];
}

ParamBox UnitBox(const ParameterMap& map) {
  ParamBox box;
  for (int i = 0; i < map.size(); ++i) {
    box.names.push_back(map.name(i));
    box.lower.push_back(0.0);
    box.upper.push_back(1.0);
  }
  return box;
}

// ---- uncertainty
// -----------------------------------------------------------------------------------

bool ScaledJacobian(const ParameterMap& map, const ResidualFunction& f, std::span<const double> x,
                    std::span<const double> f0, double fd_step, int threads, Eigen::MatrixXd& js,
                    std::vector<double>& scale, int64_t* evaluations) {
  const int n = map.size();
  // Scaled coordinates: x_i = scale_i s_i, so J_s = J diag(scale) with a uniform step.
  scale.assign(static_cast<size_t>(n), 0.0);
  std::vector<double> s0(n), slo(n), shi(n);
  for (int i = 0; i < n; ++i) {
    double lo, hi;
    map.Bounds(x, i, &lo, &hi);
    scale[i] = map.Scale(x, i);
    s0[i] = x[i] / scale[i];
    slo[i] = lo / scale[i];
    shi[i] = hi / scale[i];
  }
  ResidualFunction fs = [&](std::span<const double> s, std::vector<double>& r) {
    std::vector<double> xs(n);
    for (int i = 0; i < n; ++i) xs[i] = s[i] * scale[i];
    return f(xs, r);
  };
  return NumericJacobian(fs, s0, f0, slo, shi, fd_step, true, threads, js, evaluations);
}

Uncertainty ComputeUncertainty(const ParameterMap& map, const ResidualFunction& residuals,
                               std::span<const double> x, int threads, double fd_step,
                               double weight) {
  Uncertainty out;
  const int n = map.size();
  std::vector<double> r0;
  if (!residuals(x, r0)) return out;
  const int m = static_cast<int>(r0.size());
  std::vector<double> scale;
  Eigen::MatrixXd js;
  ScaledJacobian(map, residuals, x, r0, fd_step, threads, js, scale, &out.evaluations);
  double sse = 0;
  for (double e : r0) sse += e * e;
  const double dof = std::max(1, m - n);
  const double s2 = sse / dof;
  out.residual_sigma = std::sqrt(s2) / weight;
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(js, Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  out.singular_values.assign(sv.data(), sv.data() + sv.size());
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
    out.weakest_direction = buf;
    for (int k = 0; k < std::min(3, n); ++k) {
      std::snprintf(buf, sizeof buf, " %s%s %.2f", k ? "," : "", map.name(parts[k].second).c_str(),
                    w[parts[k].second]);
      out.weakest_direction += buf;
    }
  }
  const double colmax = n ? js.colwise().norm().maxCoeff() : 0.0;
  for (int i = 0; i < n; ++i) {
    ParamEstimate p;
    p.name = map.name(i);
    p.unit = map.unit(i);
    p.value = x[i];
    p.scale = scale[i];
    const double col = js.col(i).norm();
    p.sensitivity = col / std::sqrt(static_cast<double>(m)) / weight;
    if (!(col > 1e-9 * colmax) || col == 0.0) {
      p.identifiability = Identifiability::kNoEffect;
      p.std_error = std::numeric_limits<double>::infinity();
      p.note = "the output does not depend on it here";
    } else {
      p.std_error = std::sqrt(std::max(0.0, cov(i, i))) * scale[i];
      const double ref = std::max(std::abs(p.value), 0.1 * scale[i]);
      p.identifiability =
          p.std_error <= 0.3 * ref ? Identifiability::kWell : Identifiability::kPoorly;
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
        std::snprintf(buf, sizeof buf, "correlated with %s (r = %.3f)", map.name(bj).c_str(), best);
        p.note = buf;
      }
    }
    out.params.push_back(p);
  }
  return out;
}

// ---- the fit
// ---------------------------------------------------------------------------------------

namespace {

/// The residuals of unit points through the residual evaluator (physical values when the map
/// says so).
BatchResidualFunction UnitResiduals(const ParameterMap& map, BatchEvaluator& evaluator) {
  BatchResidualFunction f = EvaluatorResiduals(evaluator);
  if (!map.physical_genomes()) return f;
  return [&map, f](const std::vector<std::vector<double>>& us, std::vector<std::vector<double>>& rs,
                   std::vector<char>& ok) {
    std::vector<std::vector<double>> xs;
    xs.reserve(us.size());
    for (const auto& u : us) xs.push_back(map.ToPhysical(u));
    f(xs, rs, ok);
  };
}

/// The fit's problem and options checked, each bad field named.
void ValidateFit(const FitProblem& problem, const FitOptions& o, int n) {
  if (n < 1) throw InputError(FieldError("parameters", n, "must be >= 1"));
  if (o.polish) ThrowIfError(o.lm.Validate());
  if (o.threads < 1) throw InputError(FieldError("threads", o.threads, "must be >= 1"));
  if (!(o.uncertainty_fd_step > 0))
    throw InputError(FieldError("uncertainty_fd_step", o.uncertainty_fd_step, "must be > 0"));
  if (!(std::isfinite(problem.residual_weight) && problem.residual_weight > 0))
    throw InputError(
        FieldError("residual_weight", problem.residual_weight, "must be finite and > 0"));
  for (size_t i = 0; i < o.starts.size(); ++i) {
    if (o.starts[i].size() != static_cast<size_t>(n))
      throw InputError(FieldError("starts[" + std::to_string(i) + "].size()", o.starts[i].size(),
                                  "must be " + std::to_string(n)));
  }
  if (!o.search && (!o.polish || o.starts.empty()))
    throw InputError("fit: no global search and no starting point to polish");
  if (o.search && !problem.cost_evaluator)
    throw InputError("fit: a global search needs a cost evaluator");
  if (o.polish && !problem.residual_evaluator)
    throw InputError("fit: a polish needs a residual evaluator");
  if (o.polish_repetitions < 0)
    throw InputError(FieldError("polish_repetitions", o.polish_repetitions, "must be >= 0"));
  if (!(o.basin_margin >= 0 && std::isfinite(o.basin_margin)))
    throw InputError(FieldError("basin_margin", o.basin_margin, "must be finite and >= 0"));
  if (o.uncertainty && !problem.physical_residuals)
    throw InputError("fit: the uncertainty table needs the physical residuals");
}

/// The other repetitions' bests as starts of the polish, cheapest first (ties: the lower
/// repetition), distinct points, at most `count`.
void AddRepetitionStarts(const ParameterMap& map, const SearchResult& sr, int count,
                         std::vector<std::vector<double>>& starts,
                         std::vector<int>& start_repetition) {
  const int n = map.size();
  const ParamBox box = map.physical_genomes() ? map.SearchBox() : UnitBox(map);
  std::vector<int> order;
  for (int r = 0; r < static_cast<int>(sr.repetition_best.size()); ++r)
    if (r != sr.best_repetition && std::isfinite(sr.repetition_costs[static_cast<size_t>(r)]))
      order.push_back(r);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return sr.repetition_costs[static_cast<size_t>(a)] <
           sr.repetition_costs[static_cast<size_t>(b)];
  });
  int added = 0;
  for (int r : order) {
    if (added == count) break;
    std::vector<double> u(box.size());
    box.ToUnit(sr.repetition_best[static_cast<size_t>(r)].data(), u.data());
    const bool seen = std::any_of(starts.begin(), starts.end(), [&](const std::vector<double>& s) {
      for (int i = 0; i < n; ++i)
        if (std::abs(s[static_cast<size_t>(i)] - u[static_cast<size_t>(i)]) > 1e-3) return false;
      return true;
    });
    if (seen) continue;
    starts.push_back(std::move(u));
    start_repetition.push_back(r);
    ++added;
  }
}

/// LM from every start, in the unit box: concurrently (each polish its own residual evaluator)
/// when the options allow, else one after another through one evaluator.
std::vector<LmResult> Polish(const FitProblem& problem, const FitOptions& o,
                             const std::vector<std::vector<double>>& starts) {
  const ParameterMap& map = *problem.map;
  const int n = map.size();
  const std::vector<double> lo(n, 0.0), hi(n, 1.0);
  std::vector<LmResult> results(starts.size());
  if (o.concurrent_polishes && o.threads > 1 && starts.size() > 1) {
    std::vector<std::exception_ptr> errors(starts.size());
    ParallelFor(static_cast<int>(starts.size()), o.threads, [&](int s) {
      try {
        std::unique_ptr<BatchEvaluator> rev = problem.residual_evaluator();
        results[static_cast<size_t>(s)] = LevenbergMarquardt(
            UnitResiduals(map, *rev), starts[static_cast<size_t>(s)], lo, hi, o.lm);
      } catch (...) {
        errors[static_cast<size_t>(s)] = std::current_exception();
      }
    });
    for (const std::exception_ptr& e : errors)
      if (e) std::rethrow_exception(e);
  } else {  // one evaluator for every polish: a service evaluator opens a session per evaluator
    std::unique_ptr<BatchEvaluator> rev = problem.residual_evaluator();
    const BatchResidualFunction f = UnitResiduals(map, *rev);
    for (size_t s = 0; s < starts.size(); ++s)
      results[s] = LevenbergMarquardt(f, starts[s], lo, hi, o.lm);
  }
  return results;
}

}  // namespace

FitResult Fit(const FitProblem& problem, const FitOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  if (!problem.map) throw InputError("fit: no parameter map");
  const ParameterMap& map = *problem.map;
  const int n = map.size();
  ValidateFit(problem, o, n);

  FitResult fit;
  std::vector<double> best_unit;  // where the fit stands, unit coordinates
  double best_cost = std::numeric_limits<double>::infinity();
  std::vector<std::vector<double>> starts;
  std::vector<int> start_repetition;  // per start: its repetition (−1: a caller's start)
  size_t first_basin =
      0;  // starts from here on are other repetitions' bests (kept only by basin_margin)
  if (o.search) {
    const ParamBox box = map.physical_genomes() ? map.SearchBox() : UnitBox(map);
    std::unique_ptr<BatchEvaluator> ev = problem.cost_evaluator();
    fit.search = Search(box, o.search_options, *ev);
    fit.searched = true;
    fit.evaluations += fit.search.evaluations;
    fit.message = "global search: " + fit.search.stop_reason;
    std::vector<double> u(box.size());
    box.ToUnit(fit.search.best.data(), u.data());
    starts.push_back(u);
    start_repetition.push_back(fit.search.best_repetition);
    fit.cost = fit.search.best_cost;
    fit.x = map.physical_genomes() ? fit.search.best : map.ToPhysical(fit.search.best);
    fit.ok = std::isfinite(fit.cost);
    if (o.search_cost_is_sum_of_squares) best_cost = fit.search.best_cost;
  }
  if (o.polish) {
    starts.insert(starts.end(), o.starts.begin(), o.starts.end());
    start_repetition.resize(starts.size(), -1);
    first_basin = starts.size();
    if (fit.searched && o.polish_repetitions > 0) {
      AddRepetitionStarts(map, fit.search, o.polish_repetitions, starts, start_repetition);
    }
    std::vector<LmResult> results = Polish(problem, o, starts);
    bool polished = false;
    for (size_t s = 0; s < starts.size(); ++s) {
      LmResult& r = results[s];
      fit.evaluations += r.evaluations;
      fit.lm_iterations += r.iterations;
      ++fit.polishes;
      const double bar =
          s >= first_basin && polished ? best_cost * (1 - o.basin_margin) : best_cost;
      if (std::isfinite(r.cost) && r.cost < bar) {
        best_cost = r.cost;
        best_unit = std::move(r.x);
        fit.best_polish = static_cast<int>(s);
        fit.best_polish_repetition = start_repetition[s];
        fit.best_polish_iterations = r.iterations;
        fit.polish_message = r.message;
        polished = true;
      } else if (!polished) {
        fit.polish_message = r.message;
      }
    }
    if (!fit.message.empty()) fit.message += "; ";
    if (polished) {
      fit.cost = best_cost;
      fit.x = map.ToPhysical(best_unit);
      fit.ok = true;
      fit.message += "refinement: " + fit.polish_message + " after " +
                     std::to_string(fit.best_polish_iterations) + " iterations";
      if (fit.best_polish >= static_cast<int>(first_basin))
        fit.message += " from repetition " + std::to_string(fit.best_polish_repetition + 1) +
                       "'s best (" + std::to_string(fit.polishes) + " polishes)";
    } else if (o.search_cost_is_sum_of_squares && fit.searched) {
      fit.message += "refinement: no polish lowered the search's cost";
    } else {
      fit.ok = false;
      fit.message += "refinement failed: " + fit.polish_message;
    }
  }
  if (o.uncertainty && fit.ok)
    fit.uncertainty = ComputeUncertainty(map, problem.physical_residuals, fit.x, o.threads,
                                         o.uncertainty_fd_step, problem.residual_weight);
  fit.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return fit;
}

}  // namespace pz::opt
