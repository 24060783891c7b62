#include "records/fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <tuple>

#include "io/csv.h"
#include "model/format.h"
#include "opt/thread_pool_evaluator.h"
#include "records/excitation.h"
#include "records/nnls.h"
#include "records/preisach_family.h"
#include "records/registry.h"
#include "records/resonance.h"
#include "records/spectrum_solve.h"

namespace pz::records {

namespace {

/// The box of every parameter (or only the searched ones) and their units.
opt::ParamBox BoxOf(const std::vector<ParamInfo>& params, const std::vector<size_t>& searched,
                    bool only_searched, std::vector<std::string>& units) {
  opt::ParamBox box;
  units.clear();
  for (size_t i = 0; i < params.size(); ++i) {
    if (only_searched && std::find(searched.begin(), searched.end(), i) == searched.end()) continue;
    const ParamInfo& p = params[i];
    box.names.push_back(p.name);
    box.lower.push_back(p.lower);
    box.upper.push_back(p.upper);
    box.log_scale.push_back(p.log_scale);
    units.push_back(p.unit);
  }
  return box;
}

/// The search's budget sized to the number of searched parameters (one: the line search) unless
/// the user kept it; a line-search budget refused for another search.
void SizeSearch(const FitOptions::Sizing& k, size_t n_searched, opt::SearchOptions& so,
                FitResult& res) {
  if (k.enabled && so.algorithm == opt::SearchAlgorithm::kPso) {
    if (n_searched == 1 && !k.keep_algorithm && !k.keep_particles && !k.keep_iterations &&
        !k.keep_stall && !k.keep_repetitions) {
      so.algorithm = opt::SearchAlgorithm::kLine;  // one bounded scalar: a grid, then Brent
      so.repetitions = 1;
    } else {
      const SearchBudget b = SizedSearchBudget(n_searched);
      if (!k.keep_particles) so.pso.particles = b.particles;
      if (!k.keep_iterations) so.pso.iterations = b.iterations;
      if (!k.keep_stall) so.pso.stall_iterations = b.stall;
      if (!k.keep_repetitions) so.repetitions = b.repetitions;
      so.pso.converged_spread = b.converged_spread;
    }
    res.budget_sized = true;
  } else if (so.algorithm == opt::SearchAlgorithm::kLine && !k.keep_repetitions) {
    so.repetitions = 1;  // asked for by name: its one repetition
  }
  if (k.line_given && so.algorithm != opt::SearchAlgorithm::kLine)
    throw InputError(
        "--line-grid / --line-brackets / --line-tolerance: the line search's budget, for a "
        "search of one parameter with the sized budget; this fit searches " +
        std::to_string(n_searched) + " parameter" + (n_searched == 1 ? "" : "s") + " by " +
        opt::SearchAlgorithmName(so.algorithm) +
        (n_searched == 1 ? " (--algorithm or a PSO budget flag was given)" : ""));
}

/// Progress every 25 iterations of the search (or steps of the line search).
void SetProgress(const FitOptions& options, opt::SearchOptions& so) {
  const bool line = so.algorithm == opt::SearchAlgorithm::kLine;
  const int grid = so.line.grid;
  so.on_progress = [&options, line, grid](const opt::SearchProgress& p) {
    if (p.iteration % 25 != 0) return;
    const std::string where = !line ? "search repetition " + std::to_string(p.repetition) +
                                          " iteration " + std::to_string(p.iteration)
                              : p.iteration == 0
                                  ? "line search, the grid of " + std::to_string(grid)
                                  : "line search, Brent step " + std::to_string(p.iteration);
    options.progress(where + ": best MSE " + io::FormatNumber(p.overall_best_cost));
  };
}

bool HasBeamEffect(const RecordModel& model) {
  for (EffectKind e : model.effects())
    if (!e.none() && e->stage() == model::EffectStage::kBeam) return true;
  return false;
}

/// The fin's starts of a beam model (FitOptions::beam): polish_from with the last effect's
/// magnitude at each fraction of its range's upper end (either sign: the first fraction on each
/// side). Empty when that effect has no magnitude.
std::vector<std::vector<double>> BeamStarts(const FitOptions& o, const RecordModel& model) {
  if (o.beam.lm_iterations < 1)
    throw InputError(FieldError("beam.lm_iterations", o.beam.lm_iterations, "must be >= 1"));
  if (o.beam.start_fractions.empty())
    throw InputError("beam.start_fractions: needs at least one entry");
  for (double f : o.beam.start_fractions)
    if (!(f > 0 && f <= 1))
      throw InputError(FieldError("beam.start_fractions[]", f, "must be in (0, 1]"));
  const EffectKind last = model.effects().back();
  const int mp = GetFinEffectInfo(last).magnitude_param;
  if (mp < 0) return {};
  const size_t mag = model.EffectParams(last).first + static_cast<size_t>(mp);
  const ParamInfo& s = model.params()[mag];
  const bool both_signs = s.lower < 0 && s.upper > 0;
  std::vector<std::vector<double>> starts;
  for (size_t j = 0; j < o.beam.start_fractions.size(); ++j) {
    const double f = both_signs ? o.beam.start_fractions[0] : o.beam.start_fractions[j];
    std::vector<double> x = o.polish_from;
    x[mag] = both_signs && j % 2 == 1 ? f * s.lower : f * s.upper;
    starts.push_back(std::move(x));
  }
  return starts;
}

/// Hands an evaluator the physical values of the unit genomes of a map whose genomes are unit
/// coordinates (RecordMap): what the records fitness takes.
class PhysicalGenomes final : public opt::BatchEvaluator {
 public:
  PhysicalGenomes(std::unique_ptr<opt::BatchEvaluator> inner, const opt::ParameterMap& map)
      : inner_(std::move(inner)), map_(map) {}
  void Evaluate(const opt::EvalBatch& batch, std::span<opt::FitnessResult> out) override {
    std::vector<opt::Genome> g(batch.genomes.size());
    for (size_t i = 0; i < g.size(); ++i) g[i].reals = map_.ToPhysical(batch.genomes[i].reals);
    opt::EvalBatch b = batch;
    b.genomes = g;
    inner_->Evaluate(b, out);
  }
  int concurrency() const override { return inner_->concurrency(); }

 private:
  std::unique_ptr<opt::BatchEvaluator> inner_;
  const opt::ParameterMap& map_;
};

/// The map of the searched parameters: a model with search forms (a ratio: bimorph-fin's bench
/// form) the RecordMap, whose genomes are unit coordinates; else their box (null: none).
std::unique_ptr<opt::ParameterMap> SearchedMap(const RecordModel& model,
                                               const std::vector<size_t>& searched,
                                               const opt::ParamBox& search_box,
                                               const std::vector<std::string>& units) {
  if (model.has_ratio()) {
    if (searched.size() != model.params().size())
      throw InputError(model.Describe() +
                       ": a parameter searched as a ratio needs every parameter searched (no "
                       "solved weights)");
    return std::make_unique<RecordMap>(model);
  }
  if (search_box.size() == 0) return nullptr;
  return std::make_unique<opt::BoxMap>(search_box, units);
}

/// The evaluator as the map's genomes need it: handed physical values where they are unit
/// coordinates.
std::unique_ptr<opt::BatchEvaluator> Physical(std::unique_ptr<opt::BatchEvaluator> e,
                                              const opt::ParameterMap* map) {
  if (map == nullptr || map->physical_genomes()) return e;
  return std::make_unique<PhysicalGenomes>(std::move(e), *map);
}

/// The starts given: a polish from physical values (no search), and extra starts in unit
/// coordinates of every parameter; both reduced to the searched parameters.
void AddStarts(const FitOptions& options, const RecordModel& model,
               const std::vector<size_t>& searched, const opt::ParameterMap* searched_map,
               opt::FitOptions& fo, FitResult& res) {
  const size_t n_params = model.params().size();
  // Physical points of every parameter, reduced to the searched ones, in unit coordinates.
  auto unit = [&](const std::vector<double>& x, const std::string& what) {
    if (x.size() != n_params)
      throw InputError(FieldError(what, x.size(), "must have one value per parameter"));
    std::vector<double> sp;
    for (size_t i : searched) sp.push_back(x[i]);
    return searched_map->ToUnit(sp);
  };
  if (!options.polish_from.empty()) {  // no search: the polish from these physical values
    if (options.polish_from.size() != n_params)
      throw InputError(FieldError("polish_from", options.polish_from.size(),
                                  "must have one value per parameter"));
    fo.search = false;
    if (searched_map) fo.starts = {unit(options.polish_from, "polish_from")};
    if (searched_map && HasBeamEffect(model)) {  // the fin's refinement of a CVODE model
      std::vector<std::vector<double>> starts = BeamStarts(options, model);
      if (!starts.empty()) fo.starts.clear();
      for (size_t j = 0; j < starts.size(); ++j)
        fo.starts.push_back(unit(starts[j], "beam start " + std::to_string(j)));
      fo.lm.max_iterations = options.beam.lm_iterations;
      fo.lm.central = false;  // forward differences: half the CVODE runs per Jacobian
      res.lm_differences = fo.lm.central_to_finish ? "forward-central" : "forward";
    }
  }
  if (searched_map) {
    for (size_t j = 0; j < options.seed_points.size(); ++j)
      fo.search_options.seeds.push_back(
          unit(options.seed_points[j], "seed_points[" + std::to_string(j) + "]"));
    for (size_t j = 0; j < options.start_points.size(); ++j)
      fo.starts.push_back(unit(options.start_points[j], "start_points[" + std::to_string(j) + "]"));
  }
  for (const std::vector<double>& u :
       options.extra_starts) {  // unit coordinates of every parameter
    if (u.size() != n_params)
      throw InputError(FieldError("extra_starts", u.size(), "must have one value per parameter"));
    std::vector<double> su;
    for (size_t i : searched) su.push_back(u[i]);
    fo.starts.push_back(std::move(su));
  }
}

/// Every vector the search tried diverged (each cost the penalty), so the best is one of them: a
/// named error, not metrics and a fit.json of NaN.
[[noreturn]] void ThrowDiverged(const RecordModel& model,
                                const std::vector<const io::Record*>& train, int64_t evaluations) {
  std::string names;
  for (const io::Record* r : train) names += (names.empty() ? "" : ", ") + r->name;
  throw InputError(
      model.Describe() + ": the model's output on the training records (" + names +
      ") is not finite at any of the " + std::to_string(evaluations) +
      " parameter vectors evaluated in the search box (every simulation diverged): try more "
      "integration sub-steps (--substeps), a smoother drive, or another family");
}

/// The polish's options; the LM's differences forward, central to finish after a search, unless
/// the user chose.
void SetPolish(const FitOptions& options, opt::FitOptions& fo, FitResult& res) {
  fo.polish = options.polish;
  fo.lm = options.lm;
  if (options.lm_differences_auto) {
    fo.lm.central = false;
    fo.lm.central_to_finish = fo.search_options.algorithm != opt::SearchAlgorithm::kLine;
  }
  res.lm_differences = fo.lm.central             ? "central"
                       : fo.lm.central_to_finish ? "forward-central"
                                                 : "forward";
}

/// The search and polish's figures into the result; the best searched parameters returned.
std::vector<double> TakeFit(opt::FitResult fit, FitResult& res) {
  res.search = std::move(fit.search);
  res.evaluations = fit.evaluations;
  res.lm_iterations = fit.lm_iterations;
  res.stop_reason = res.search.stop_reason;
  res.polishes = fit.polishes;
  res.best_polish_repetition = fit.best_polish_repetition;
  res.polish_message = fit.message;
  res.uncertainty = std::move(fit.uncertainty);
  return std::move(fit.x);
}

/// A model with `resonance` (records/resonance.h): the mode placed where the training residual of
/// the fit without it (its share at zero), or a rest's ringing, shows a dominant band, polished
/// from there at share ½ and 1 besides the fit's best; the better training cost kept.
void RestartAtMode(const RecordModel& model, const RecordFitness& fitness,
                   const std::vector<const io::Record*>& train, const opt::ParameterMap& map,
                   const opt::FitProblem& problem, const opt::FitOptions& fo,
                   std::vector<double>& best_searched, FitResult& res) {
  const auto [first, count] = model.EffectParams(EffectKind::Named("resonance"));
  if (count != 3) return;
  const bool solved = fitness.spectrum_solved();
  const std::vector<double> full = solved ? fitness.Expand(best_searched) : best_searched;
  std::vector<double> without = full;
  without[first] = 0;
  const auto& box = model.params();
  const std::optional<ModeStart> start =
      FindModeStart(train, fitness.Run(without).yhat, box[first + 1].lower);
  if (!start) return;
  const model::SpectralBand& b = start->band;
  opt::FitOptions again = fo;
  again.search = false;
  again.starts = {map.ToUnit(best_searched)};
  for (double share : {0.5, 1.0}) {
    std::vector<double> x = full;
    x[first] = share;
    x[first + 1] = std::clamp(b.f_peak, box[first + 1].lower, box[first + 1].upper);
    x[first + 2] = std::clamp(b.zeta, box[first + 2].lower, box[first + 2].upper);
    std::vector<double> xs;
    for (size_t i : fitness.searched()) xs.push_back(x[i]);
    again.starts.push_back(map.ToUnit(xs));
  }
  opt::FitResult second = opt::Fit(problem, again);
  res.evaluations += second.evaluations;
  res.lm_iterations += second.lm_iterations;
  res.polishes += second.polishes;
  auto mse = [&](const std::vector<double>& xs) {
    return fitness.Run(solved ? fitness.Expand(xs) : xs, false).mse;
  };
  const bool kept = mse(second.x) < mse(best_searched);
  res.mode_start = "f_n " + FormatG(b.f_peak, 4) + " Hz, zeta " + FormatG(b.zeta, 2) + " from " +
                   start->source + " (band " + FormatG(b.f_lo, 3) + "-" + FormatG(b.f_hi, 3) +
                   " Hz, " + FormatG(100 * b.share, 3) + " % of its power)" +
                   (kept ? "" : "; the search's own fit was better");
  if (!kept) return;
  best_searched = std::move(second.x);
  res.uncertainty = std::move(second.uncertainty);
}

}  // namespace

namespace {

/// Every record of the set evaluated with the fit: its metrics and output.
void EvaluateEvery(const io::RecordSet& set, FitResult& res) {
  for (const io::Record& r : set.records) {
    std::vector<double> y;
    res.metrics.push_back(Evaluate(*res.model, res.params, res.weights, r, &y));
    res.yhat.push_back(std::move(y));
  }
}

}  // namespace

FitResult FitModel(const io::RecordSet& set, std::shared_ptr<RecordModel> model,
                   const FitOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  auto train = set.WithRole(model::CaseRole::kTrain);
  if (train.empty()) throw InputError(set.source.string() + ": no record has the role 'train'");
  if (options.threads < 1) throw InputError(FieldError("threads", options.threads, "must be >= 1"));
  if (const std::string e = RateCoverageError(set, model->effects()); !e.empty())
    throw InputError(e);
  RecordFitness fitness(*model, train);
  FitResult res;
  res.model = model;
  const auto& params = model->params();
  // Searched: the model's parameters (a linear family's weights are solved, not among them; with
  // the creep spectrum, its weights neither: records/spectrum_solve.h).
  const std::vector<size_t>& searched = fitness.searched();
  const bool solved = fitness.spectrum_solved();
  std::vector<double> best;  // every parameter
  if (!params.empty()) {
    std::vector<std::string> units;
    const opt::BoxMap map(BoxOf(params, searched, false, units), units);
    const opt::ParamBox search_box = BoxOf(params, searched, true, units);
    const std::unique_ptr<opt::ParameterMap> searched_map =
        SearchedMap(*model, searched, search_box, units);
    const opt::ParameterMap* m = searched_map.get();
    const RecordResidualFitness residual_fitness(fitness);
    opt::FitProblem problem;
    problem.map = m;
    // The factory's evaluators (the service's workers) rebuild the fitness as constructed: once a
    // revalidation below has changed its strengths, the polishes under them run here.
    bool revalidated = false;
    problem.cost_evaluator = [&]() -> std::unique_ptr<opt::BatchEvaluator> {
      if (options.evaluator_factory && !revalidated)
        return Physical(options.evaluator_factory(fitness, RecordEvaluation::kCost), m);
      return Physical(std::make_unique<opt::ThreadPoolEvaluator>(fitness, options.threads), m);
    };
    problem.residual_evaluator = [&]() -> std::unique_ptr<opt::BatchEvaluator> {
      if (options.evaluator_factory && !revalidated)
        return Physical(options.evaluator_factory(fitness, RecordEvaluation::kResiduals), m);
      return Physical(std::make_unique<opt::ThreadPoolEvaluator>(residual_fitness, options.threads),
                      m);
    };
    problem.physical_residuals = [&](std::span<const double> x, std::vector<double>& r) {
      return fitness.Residuals(x, r);
    };
    problem.residual_weight = fitness.ResidualWeight();
    opt::FitOptions fo;
    fo.search_options = options.search;
    res.searched_parameters = searched.size();
    res.spectrum_solved = solved;
    res.solved_parameters = params.size() - searched.size();  // the spectrum's weights where solved
    const FitOptions::Sizing& k = options.sizing;
    opt::SearchOptions& so = fo.search_options;
    SizeSearch(k, searched.size(), so, res);
    res.algorithm = so.algorithm;
    res.line = so.line;
    res.budget = BudgetOf(fo.search_options);
    fo.polish_repetitions =
        options.polish_repetitions ? std::max(0, fo.search_options.repetitions - 1) : 0;
    fo.concurrent_polishes =
        true;  // each polish its own ThreadPoolEvaluator over the const fitness
    if (options.progress) SetProgress(options, fo.search_options);
    SetPolish(options, fo, res);
    AddStarts(options, *model, searched, m, fo, res);
    fo.search_cost_is_sum_of_squares = true;  // the search's cost is the MSE = Σ r²
    // With the spectrum solved, the table covers every parameter (below), not the searched ones.
    fo.uncertainty = options.uncertainty && !solved;
    fo.uncertainty_fd_step = options.lm.fd_step;
    fo.threads = options.threads;
    std::vector<double> best_searched;
    if (searched_map) {
      best_searched = TakeFit(opt::Fit(problem, fo), res);
      if (options.polish && options.polish_from.empty())
        RestartAtMode(*model, fitness, train, *m, problem, fo, best_searched, res);
    }
    best = solved ? fitness.Expand(best_searched) : best_searched;
    // A regularised linear family with effects: its strength was chosen with the effects at their
    // neutral values; re-chosen at the solution, and where it changes the solution is polished
    // again under the new strength (locally: a polish, no search). A creep spectrum's roughness
    // penalty likewise (searched without it): chosen at the solution, polished under it (where
    // the spectrum is solved: solved again under it), and chosen once more at the result.
    const bool spectrum = fitness.spectrum_validation().used && options.spectrum_roughness;
    for (int round = 0; round < (spectrum ? 2 : 1) && options.polish; ++round) {
      bool changed = false;
      if (fitness.validation().used && model->params().size() > model->family_param_count())
        changed = fitness.Revalidate(best);
      if (spectrum) changed = fitness.RevalidateSpectrum(best, map, options.threads) || changed;
      if (!changed) break;
      revalidated = true;
      if (searched_map) {
        opt::FitOptions again = fo;
        again.search = false;
        again.starts = {m->ToUnit(best_searched)};
        opt::FitResult second = opt::Fit(problem, again);
        res.evaluations += second.evaluations;
        res.lm_iterations += second.lm_iterations;
        res.polishes += second.polishes;
        if (!solved) res.uncertainty = std::move(second.uncertainty);
        best_searched = std::move(second.x);
      }
      best = solved ? fitness.Expand(best_searched) : best_searched;
    }
    if (solved && options.uncertainty)
      res.uncertainty =
          opt::ComputeUncertainty(map, problem.physical_residuals, best, options.threads,
                                  options.lm.fd_step, problem.residual_weight);
  }
  const RecordFitness::Output out = fitness.Run(best);
  if (!std::isfinite(out.mse)) ThrowDiverged(*model, train, res.evaluations);
  res.params = best;
  res.weights = out.weights;
  res.regularisation = fitness.validation();
  res.spectrum_regularisation = fitness.spectrum_validation();
  res.spectrum_sigma = fitness.spectrum_sigma();
  const double n = static_cast<double>(fitness.samples());
  res.train_mse = model->family().sums_errors() ? out.mse / n : out.mse;
  res.train_sse = model->family().sums_errors() ? out.mse : out.mse * n;
  EvaluateEvery(set, res);
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return res;
}

std::string FitResult::SpectrumIdentification() const {
  const auto [first, count] = model->EffectParams(EffectKind::Named("creep-spectrum"));
  if (count == 0 || spectrum_sigma.size() != count) return "";
  double mean = 0;
  for (size_t i = 0; i < count; ++i) mean += params[first + i] / static_cast<double>(count);
  std::vector<size_t> loose;
  for (size_t i = 0; i < count; ++i)
    if (!(spectrum_sigma[i] <= mean)) loose.push_back(i);
  if (loose.empty()) return "";
  const auto& box = model->params();
  std::string names, sigmas;
  for (size_t i : loose) {
    names += (names.empty() ? "" : ", ") + box[first + i].name;
    sigmas += (sigmas.empty() ? "" : ", ") + FormatG(spectrum_sigma[i], 2);
  }
  return "the training excitation does not identify the creep spectrum's " + names + " (σ " +
         sigmas + " from the training records alone, above the mean fitted weight " +
         FormatG(mean, 2) +
         "): the roughness penalty holds them to their neighbours, and what they add to a withheld "
         "prediction "
         "is extrapolated (fast relaxations need steps and holds at several amplitudes in the "
         "training drive, "
         "slow ones a record several times longer than their time)";
}

namespace {

/// FitRecords for preisach at kAutoLevels: the effects searched on the coarsest grid, the levels
/// chosen at them (FitPreisachLevels), the chosen grid's weights solved there.
FitResult FitPreisachAuto(const io::RecordSet& set, const DataScale& scale,
                          const FitOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<const io::Record*> train = set.WithRole(model::CaseRole::kTrain);
  const std::vector<int>& levels = PreisachLevelCandidates();
  FitResult base;
  if (!options.effects.empty()) {
    FitOptions o = options;
    o.family_options.pi_operators = levels.front();
    base = FitRecords(set, o);
  }
  const PreisachLevelFits fits =
      FitPreisachLevels(train, scale, options.family_options, options.effects, base.params, levels);
  const size_t c = fits.choice.chosen;
  FitResult r;
  if (!options.effects.empty() && levels[c] == levels.front()) {
    r = std::move(base);
  } else {
    // The chosen grid: its weights at the coarse fit's effects (no search, no polish), every record
    // evaluated with the whole model.
    FamilyOptions fo = options.family_options;
    fo.pi_operators = levels[c];
    r = std::move(base);
    r.model = std::make_shared<RecordModel>(MakeFamily(options.family, scale, fo), options.effects,
                                            scale);
    if (r.params.empty()) r.params.assign(r.model->params().size(), 0.0);
    r.weights = fits.fitness[c]->Run(fits.params, false).weights;
    r.regularisation = fits.fitness[c]->validation();
    EvaluateResolved(set, r);
  }
  r.resolution = fits.choice;
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace

void EvaluateResolved(const io::RecordSet& set, FitResult& r) {
  r.metrics.clear();
  r.yhat.clear();
  double sse = 0;
  size_t n = 0;
  for (const io::Record& rec : set.records) {
    std::vector<double> y;
    r.metrics.push_back(Evaluate(*r.model, r.params, r.weights, rec, &y));
    r.yhat.push_back(std::move(y));
    if (rec.role == model::CaseRole::kTrain) {
      sse += r.metrics.back().rmse * r.metrics.back().rmse *
             static_cast<double>(r.metrics.back().samples);
      n += r.metrics.back().samples;
    }
  }
  r.train_sse = sse;
  r.train_mse = n > 0 ? sse / static_cast<double>(n) : 0;
  r.uncertainty = {};  // the coarse grid's: not this model's
}

FitResult FitRecords(const io::RecordSet& set, const FitOptions& options) {
  const DataScale scale = MeasureScale(set.WithRole(model::CaseRole::kTrain));
  if (options.family == "preisach" && options.family_options.pi_operators == kAutoLevels)
    return FitPreisachAuto(set, scale, options);
  std::shared_ptr<const Family> fam = MakeFamily(options.family, scale, options.family_options);
  auto model = std::make_shared<RecordModel>(fam, options.effects, scale);
  return FitModel(set, model, options);
}

}  // namespace pz::records
