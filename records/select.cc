#include "records/select.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>

#include "io/csv.h"
#include "model/format.h"
#include "model/status.h"
#include "records/excitation.h"
#include "records/model.h"
#include "records/preisach_family.h"
#include "records/registry.h"
#include "records/spectrum_solve.h"

namespace pz::records {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// Runs f(0) … f(n − 1) on `threads` threads (one after another for 1); rethrows the exception of
/// the lowest index that threw, after every task has ended.
template <class F>
void RunTasks(size_t n, int threads, const F& f) {
  std::vector<std::exception_ptr> errors(n);
  std::atomic<size_t> next{0};
  auto work = [&] {
    for (size_t i = next++; i < n; i = next++) {
      try {
        f(i);
      } catch (...) {
        errors[i] = std::current_exception();
      }
    }
  };
  const size_t t = std::min<size_t>(n, static_cast<size_t>(std::max(1, threads)));
  std::vector<std::thread> pool;
  for (size_t i = 1; i < t; ++i) pool.emplace_back(work);
  work();
  for (auto& th : pool) th.join();
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
}

bool Takes(const std::vector<std::string>& v, const std::string& x) {
  return std::find(v.begin(), v.end(), x) != v.end();
}

bool LinearFamily(const std::string& f) {
  const FamilyDef* def = FindFamily(f);
  return def != nullptr && def->linear;
}

/// One fold of the blocked cross-validation: the training records with block k masked (the pieces
/// before and after it, role train) and each training record whole (role validate) for scoring.
struct Fold {
  io::RecordSet set;
  std::vector<size_t> whole;                     ///< per training record: its index in set
  std::vector<std::pair<size_t, size_t>> block;  ///< per training record: the masked samples
};

std::vector<Fold> MakeFolds(const io::RecordSet& set, int K) {
  if (K < 2 || K > 50) throw InputError(FieldError("folds", K, "must be 2 … 50"));
  const auto train = set.WithRole(model::CaseRole::kTrain);
  if (train.empty()) throw InputError(set.source.string() + ": no record has the role 'train'");
  for (const io::Record* r : train)
    if (r->scored() < 2 * static_cast<size_t>(K))
      throw InputError(r->Label() + ": " + std::to_string(r->scored()) +
                       " scored samples, fewer than 2 × " + std::to_string(K) +
                       " (the folds of the cross-validation)");
  std::vector<Fold> folds(static_cast<size_t>(K));
  for (int k = 0; k < K; ++k) {
    Fold& f = folds[static_cast<size_t>(k)];
    f.set.source = set.source;
    f.set.format = set.format;
    f.set.drive_unit = set.drive_unit;
    f.set.response_unit = set.response_unit;
    for (const io::Record* r : train) {
      const size_t a = r->first_scored, n = r->scored();
      const size_t s = a + static_cast<size_t>(k) * n / static_cast<size_t>(K);
      const size_t e = a + static_cast<size_t>(k + 1) * n / static_cast<size_t>(K);
      f.block.emplace_back(s, e);
      if (s > a) {
        io::Record p = *r;
        p.name = r->name + "~before";
        p.end_scored = s;
        f.set.records.push_back(std::move(p));
      }
      if (e < r->end_scored) {
        io::Record p = *r;
        p.name = r->name + "~after";
        p.first_scored = e;
        f.set.records.push_back(std::move(p));
      }
    }
    for (const io::Record* r : train) {
      io::Record w = *r;
      w.role = model::CaseRole::kValidate;
      w.name = r->name + "~whole";
      f.whole.push_back(f.set.records.size());
      f.set.records.push_back(std::move(w));
    }
  }
  return folds;
}

/// The fold's RMSE over the masked blocks (offset `fit`: refitted on the fold's training samples of
/// each record); +inf when not finite.
double FoldRmse(const Fold& f, const FitResult& r) {
  double sse = 0;
  size_t n = 0;
  for (size_t j = 0; j < f.whole.size(); ++j) {
    const io::Record& rec = f.set.records[f.whole[j]];
    const std::vector<double>& yhat = r.yhat[f.whole[j]];
    const auto [s, e] = f.block[j];
    double o = 0;  // what to add to yhat
    if (rec.offset_mode == io::OffsetMode::kFit) {
      const double full = r.metrics[f.whole[j]].offset;
      double sum = 0;
      size_t m = 0;
      for (size_t k = rec.first_scored; k < rec.end_scored; ++k) {
        if (k >= s && k < e) continue;
        sum += rec.y[k] - (yhat[k] - full);
        ++m;
      }
      o = (m > 0 ? sum / static_cast<double>(m) : full) - full;
    }
    for (size_t k = s; k < e; ++k) {
      const double d = rec.y[k] - (yhat[k] + o);
      sse += d * d;
    }
    n += e - s;
  }
  const double rmse = std::sqrt(sse / static_cast<double>(std::max<size_t>(n, 1)));
  return std::isfinite(rmse) ? rmse : kInf;
}

/// A candidate made for the training records' scale (the folds' models share it).
struct Made {
  std::shared_ptr<RecordModel> model;
  FitOptions options;
  size_t searched = 0;
};

Made MakeCandidate(const DataScale& scale, const Candidate& c, const FitOptions& base,
                   const std::function<RecordEvaluatorFactory(const FamilyOptions&)>& service) {
  Made m;
  m.options = c.Options(base);
  if (service) m.options.evaluator_factory = service(m.options.family_options);
  std::shared_ptr<const Family> fam = MakeFamily(c.family, scale, m.options.family_options);
  m.model = std::make_shared<RecordModel>(fam, c.effects, scale);
  m.searched = SearchedParams(*m.model).size();
  return m;
}

size_t ParameterCount(const RecordModel& m) {
  return m.params().size() + (m.family().linear() ? m.family().regressors() : 0);
}

/// The screening round's fit options: a small search (the line search with a coarse grid for one
/// searched parameter), a short polish, no uncertainty.
FitOptions ScreenOptions(const SelectOptions& o, size_t searched) {
  FitOptions s = o.fit;
  s.sizing = {};
  s.sizing.enabled = true;
  s.search.algorithm = opt::SearchAlgorithm::kPso;
  if (searched == 1) {
    s.search.line.grid = o.screen_line_grid;
    s.search.line.brackets = 1;
  } else {
    s.sizing.keep_particles = s.sizing.keep_iterations = s.sizing.keep_stall =
        s.sizing.keep_repetitions = true;
    s.search.pso.particles = o.screen_particles;
    s.search.pso.iterations = o.screen_iterations;
    s.search.pso.stall_iterations = std::max(5, o.screen_iterations / 2);
    s.search.pso.converged_spread = 1e-3;
    s.search.repetitions = 1;
  }
  s.polish_repetitions = false;
  s.lm.max_iterations = o.screen_lm_iterations;
  s.uncertainty = false;
  s.progress = nullptr;
  return s;
}

/// The finalists' fit options: `fit`'s search with its repetitions and polish capped (one searched
/// parameter under the sized budget: its line search, as it is).
FitOptions FinalOptions(const SelectOptions& o, size_t searched) {
  FitOptions f = o.fit;
  const bool line = f.sizing.enabled && searched == 1;
  if (!line && f.sizing.enabled) {  // the sized budget, its swarm and iterations capped too
    const SearchBudget b = SizedSearchBudget(searched);
    if (!f.sizing.keep_particles) f.search.pso.particles = std::min(b.particles, o.final_particles);
    if (!f.sizing.keep_iterations)
      f.search.pso.iterations = std::min(b.iterations, o.final_iterations);
    if (!f.sizing.keep_stall)
      f.search.pso.stall_iterations = std::min(b.stall, o.final_iterations / 2);
    f.search.pso.converged_spread = b.converged_spread;
    f.sizing.keep_particles = f.sizing.keep_iterations = f.sizing.keep_stall = true;
  }
  if (!line) {
    if (f.sizing.enabled && !f.sizing.keep_repetitions)
      f.search.repetitions = SizedSearchBudget(searched).repetitions;
    f.search.repetitions = std::min(f.search.repetitions, o.final_repetitions);
    f.sizing.keep_repetitions = true;
  }
  f.lm.max_iterations = std::min(f.lm.max_iterations, o.final_lm_iterations);
  f.polish_repetitions = false;
  f.uncertainty = false;
  f.progress = nullptr;
  return f;
}

double ResolvedFoldRmse(const Fold& f, const DataScale& scale, const Candidate& c, int levels,
                        const std::vector<double>& params);

/// A linear family with effects at a resolution finer than `base`: its effects are searched at
/// `base` and its weights re-solved at its own (as `--pi-operators auto` does, records/fit.cc
/// FitPreisachAuto: each evaluation at 20 or 40 levels would build the finer grid's equations).
bool SearchedCoarse(const Candidate& c, int base) {
  return LinearFamily(c.family) && !c.effects.empty() && c.levels > base;
}

/// Cross-validates candidates: every (candidate, fold) fit as one task, side by side on
/// `threads` (each fit on one thread) or one after another with a service. options_of(i): the fit
/// options of candidate i. A candidate SearchedCoarse at `coarse` (> 0) is fitted at `coarse` in
/// each fold, its weights re-solved at its own resolution there.
std::vector<ModelScore> CrossValidateAll(
    const io::RecordSet& set, const std::vector<Candidate>& cands,
    const std::function<FitOptions(size_t, size_t)>& options_of, int K, int threads,
    const std::function<RecordEvaluatorFactory(const FamilyOptions&)>& service,
    const std::function<void(const std::string&)>& progress, size_t* fits,
    std::vector<std::vector<double>>* fold_params = nullptr, int coarse = 0) {
  const std::vector<Fold> folds = MakeFolds(set, K);
  const DataScale scale = MeasureScale(set.WithRole(model::CaseRole::kTrain));
  std::vector<ModelScore> out(cands.size());
  std::vector<Made> made(cands.size());
  for (size_t i = 0; i < cands.size(); ++i) {
    out[i].candidate = cands[i];
    try {
      FitOptions fold;  // the family made for the whole training scale, each fold's pieces in it
      fold.family_options.cross_validation_fold = true;
      out[i].parameters = ParameterCount(*MakeCandidate(scale, cands[i], fold, {}).model);
      Candidate searched = cands[i];
      if (coarse > 0 && SearchedCoarse(cands[i], coarse)) searched.levels = coarse;
      made[i] = MakeCandidate(scale, searched, fold, {});
      FitOptions o = options_of(i, made[i].searched);
      made[i].options = searched.Options(o);
      made[i].options.family_options.cross_validation_fold = true;
      if (service) made[i].options.evaluator_factory = service(made[i].options.family_options);
      made[i].options.threads = service ? std::max(1, threads) : 1;
      made[i].options.progress = nullptr;
    } catch (const InputError& e) {
      out[i].error = e.what();
      made[i].model.reset();
    }
  }
  std::vector<double> rmse(cands.size() * static_cast<size_t>(K), kInf);
  std::vector<std::string> errors(rmse.size());
  if (fold_params) fold_params->assign(rmse.size(), {});
  std::vector<int> done(cands.size(), 0);
  std::mutex mu;
  RunTasks(rmse.size(), service ? 1 : threads, [&](size_t t) {
    const size_t i = t / static_cast<size_t>(K), k = t % static_cast<size_t>(K);
    if (!made[i].model) return;
    try {
      const FitResult r = FitModel(folds[k].set, made[i].model, made[i].options);
      rmse[t] = coarse > 0 && SearchedCoarse(cands[i], coarse)
                    ? ResolvedFoldRmse(folds[k], scale, cands[i], cands[i].levels, r.params)
                    : FoldRmse(folds[k], r);
      if (fold_params) (*fold_params)[t] = r.params;
    } catch (const InputError& e) {
      errors[t] = e.what();
    }
    std::lock_guard<std::mutex> lock(mu);
    if (++done[i] == K && progress) {
      double mean = 0;
      for (int q = 0; q < K; ++q)
        mean += rmse[i * static_cast<size_t>(K) + static_cast<size_t>(q)] / K;
      progress(cands[i].Describe() + ": CV RMSE " + io::FormatNumber(mean));
    }
  });
  for (size_t i = 0; i < cands.size(); ++i) {
    if (!made[i].model) continue;
    ModelScore& s = out[i];
    double mean = 0;
    for (int k = 0; k < K; ++k) {
      const size_t t = i * static_cast<size_t>(K) + static_cast<size_t>(k);
      if (!errors[t].empty() && s.error.empty()) s.error = errors[t];
      s.fold_rmse.push_back(rmse[t]);
      mean += rmse[t] / K;
    }
    if (!std::isfinite(mean)) {
      s.cv_rmse = kInf;
      if (s.error.empty()) s.error = "a fold's output is not finite";
      continue;
    }
    double var = 0;
    for (double r : s.fold_rmse) var += (r - mean) * (r - mean);
    s.cv_rmse = mean;
    s.cv_se = std::sqrt(var / (K - 1) / K);
  }
  if (fits) *fits += rmse.size();
  return out;
}

/// The ladder of resolutions (SelectOptions::levels ascending, kAutoLevels alone: the default's).
std::vector<int> Ladder(const SelectOptions& o) {
  std::vector<int> l;
  for (int x : o.levels)
    if (x != kAutoLevels) l.push_back(x);
  if (l.empty()) l = SelectOptions{}.levels;
  std::sort(l.begin(), l.end());
  l.erase(std::unique(l.begin(), l.end()), l.end());
  return l;
}

/// The fold's RMSE of linear candidate c at `levels` with its effects at `params` (the fold's fit
/// at another resolution): the weights re-solved on the fold's training pieces (the penalty and its
/// strength validated there at `params`, as a fit's are at its solution; a Preisach grid's creep
/// spectrum undone on the responses, records/preisach_family.h FitPreisachLevels), each whole
/// record evaluated. +inf where the pieces cannot support that resolution.
double ResolvedFoldRmse(const Fold& f, const DataScale& scale, const Candidate& c, int levels,
                        const std::vector<double>& params) {
  FamilyOptions fo = c.Options(FitOptions{}).family_options;
  fo.pi_operators = levels;
  fo.cross_validation_fold = true;
  const std::vector<const io::Record*> train = f.set.WithRole(model::CaseRole::kTrain);
  FitResult r;
  try {
    r.model = std::make_shared<RecordModel>(MakeFamily(c.family, scale, fo), c.effects, scale);
    if (c.family == kPreisachFamily.name) {
      const PreisachLevelFits fits =
          FitPreisachLevels(train, scale, fo, c.effects, params, {levels});
      r.weights = fits.fitness.front()->Run(fits.params, false).weights;
    } else {
      const RecordFitness fitness(*r.model, train, opt::kDefaultErrorCost, params);
      r.weights = fitness.Run(params, false).weights;
    }
    r.metrics.resize(f.set.records.size());
    r.yhat.resize(f.set.records.size());
    for (size_t j : f.whole)
      r.metrics[j] = Evaluate(*r.model, params, r.weights, f.set.records[j], &r.yhat[j]);
  } catch (const InputError&) {
    return kInf;
  }
  return FoldRmse(f, r);
}

std::vector<size_t> UnexcitedRecords(const io::RecordSet& set, std::string* needs);

/// Why the folds do not choose the linear families' resolution ("" when they do): withheld drives
/// that need reversals or range the training lacks. A training drive of major loops alone gains
/// at every finer rung (its branches' shape), while the cells the finer grid adds inside are set
/// by the prior alone, and the folds cannot show how they extrapolate to the minor loops (the
/// P-885.91 stack's 1 Hz sine: CV RMSE of preisach + creep 0.242 µm at 8 levels, 0.193 at 40,
/// withheld 0.275 at 40; asymmetric-pi + creep 0.178 µm withheld at 8 plays, 0.200 at 12).
std::string LevelsNote(const io::RecordSet& set, const SelectOptions& options) {
  if (Ladder(options).size() < 2) return "";
  std::string needs;
  if (UnexcitedRecords(set, &needs).empty()) return "";
  return "the plays and levels stay at " + std::to_string(Ladder(options).front()) +
         " (not chosen by the folds): the withheld drives have loops the training lacks, where the "
         "cells of a finer grid are set by the prior alone and no fold shows how they extrapolate "
         "(ask for a resolution with --pi-operators)";
}

/// A finer rung of the resolutions' ladder is worth its weights when it lowers the CV RMSE by more
/// than this share (beside one paired SE): the folds of one periodic record agree on a small,
/// consistent gain of a finer grid (its SE tiny) that only extrapolation would show to matter (as
/// the creep spectrum's rule, records/fit.cc kSpectrumRule).
constexpr double kLevelsTolerance = 0.01;

/// The resolution of each linear candidate of the screening chosen by its folds
/// (SelectOptions::levels): fold_params[i K + k] is candidate i's fit in fold k at the ladder's
/// first rung. Each (candidate, fold, rung) re-solve is one task on `threads`, its result stored
/// at its index, so that the choice is the same whatever the threads. Sets each candidate's
/// resolution, its fold RMSEs, CV RMSE, SE and parameters to the chosen rung's, and its table.
void ChooseLevelsByFolds(const io::RecordSet& set, const SelectOptions& options,
                         const std::vector<std::vector<double>>& fold_params,
                         std::vector<ModelScore>& screen, size_t* fits) {
  const std::vector<int> ladder = Ladder(options);
  const size_t K = static_cast<size_t>(options.folds), R = ladder.size();
  if (R < 2 || !LevelsNote(set, options).empty()) return;
  const std::vector<Fold> folds = MakeFolds(set, options.folds);
  const DataScale scale = MeasureScale(set.WithRole(model::CaseRole::kTrain));
  // rmse[i][rung][k]; a rung not tried is empty.
  std::vector<std::vector<std::vector<double>>> rmse(screen.size());
  std::vector<size_t> top(screen.size(), 0);  // per candidate: the finest rung tried
  std::vector<std::pair<size_t, size_t>> pending;  // (candidate, rung)
  for (size_t i = 0; i < screen.size(); ++i) {
    const Candidate& c = screen[i].candidate;
    if (!LinearFamily(c.family) || c.levels != ladder.front() || !std::isfinite(screen[i].cv_rmse))
      continue;
    rmse[i].assign(R, {});
    rmse[i][0] = screen[i].fold_rmse;
    const size_t first = std::clamp<size_t>(static_cast<size_t>(options.levels_first), 1, R);
    for (size_t q = 1; q < first; ++q) pending.emplace_back(i, q);
    top[i] = first - 1;
  }
  auto cv = [&](size_t i, size_t q) {
    double m = 0;
    for (double x : rmse[i][q]) m += x / static_cast<double>(K);
    return std::isfinite(m) ? m : kInf;
  };
  while (!pending.empty()) {
    for (const auto& [i, q] : pending) rmse[i][q].assign(K, kInf);
    RunTasks(pending.size() * K, options.service ? 1 : std::max(1, options.fit.threads),
             [&](size_t t) {
               const auto [i, q] = pending[t / K];
               const size_t k = t % K;
               rmse[i][q][k] = ResolvedFoldRmse(folds[k], scale, screen[i].candidate, ladder[q],
                                                fold_params[i * K + k]);
             });
    if (fits) *fits += pending.size() * K;
    pending.clear();
    // Climb where the finest rung tried is lower than every other by more than kLevelsTolerance.
    for (size_t i = 0; i < screen.size(); ++i) {
      if (rmse[i].empty() || top[i] + 1 >= R) continue;
      double below = kInf;
      for (size_t q = 0; q < top[i]; ++q) below = std::min(below, cv(i, q));
      if (cv(i, top[i]) < (1 - kLevelsTolerance) * below) pending.emplace_back(i, ++top[i]);
    }
  }
  for (size_t i = 0; i < screen.size(); ++i) {
    if (rmse[i].empty()) continue;
    ModelScore& s = screen[i];
    auto regressors = [&](int levels) {
      FamilyOptions fo;
      fo.pi_operators = levels;
      fo.cross_validation_fold = true;
      return MakeFamily(s.candidate.family, scale, fo)->regressors();
    };
    const size_t base_regressors = regressors(ladder.front());
    std::vector<ModelScore> rungs;
    for (size_t q = 0; q <= top[i]; ++q) {
      ModelScore m;
      m.candidate = s.candidate;
      m.candidate.levels = ladder[q];
      m.parameters = s.parameters - base_regressors + regressors(ladder[q]);
      m.fold_rmse = rmse[i][q];
      m.cv_rmse = cv(i, q);
      if (std::isfinite(m.cv_rmse)) {
        double var = 0;
        for (double x : m.fold_rmse) var += (x - m.cv_rmse) * (x - m.cv_rmse);
        m.cv_se = std::sqrt(var / static_cast<double>((K - 1) * K));
      }
      rungs.push_back(std::move(m));
      s.level_candidates.push_back(ladder[q]);
      s.level_cv_rmse.push_back(rungs.back().cv_rmse);
    }
    size_t chosen = OneStandardErrorChoice(rungs);
    s.level_best = 0;
    for (size_t q = 1; q < rungs.size(); ++q)
      if (rungs[q].cv_rmse < rungs[s.level_best].cv_rmse) s.level_best = q;
    for (size_t q = 0; q < chosen; ++q)  // (the rungs ascend in parameters)
      if (rungs[q].cv_rmse <= (1 + kLevelsTolerance) * rungs[s.level_best].cv_rmse) {
        chosen = q;
        break;
      }
    s.level_chosen = chosen;
    s.candidate.levels = rungs[chosen].candidate.levels;
    s.parameters = rungs[chosen].parameters;
    s.fold_rmse = rungs[chosen].fold_rmse;
    s.cv_rmse = rungs[chosen].cv_rmse;
    s.cv_se = rungs[chosen].cv_se;
  }
}

bool SameModel(const Candidate& a, const Candidate& b) {
  return a.family == b.family && a.effects == b.effects && a.levels == b.levels;
}

}  // namespace

std::string Candidate::Describe() const {
  std::string s = family;
  if (levels > 0)
    s += " (" + std::to_string(levels) + (family == "preisach" ? " levels)" : " plays)");
  for (size_t i = 0; i < effects.size(); ++i)
    s += std::string(i == 0 ? " + " : ", ") + EffectName(effects[i]);
  if (TakesInitialState(family)) s += std::string(", ") + model::InitialStateName(initial_state);
  return s;
}

FitOptions Candidate::Options(const FitOptions& base) const {
  FitOptions o = base;
  o.family = family;
  o.effects = effects;
  if (levels > 0) o.family_options.pi_operators = levels;
  o.family_options.initial_state =
      TakesInitialState(family) ? initial_state : model::InitialState::kAuto;
  return o;
}

std::string ModelScore::LevelsDescribe() const {
  if (level_candidates.size() < 2 || level_chosen >= level_candidates.size()) return "";
  const std::string what = candidate.family == kPreisachFamily.name ? " levels" : " plays";
  std::string s = std::to_string(level_candidates[level_chosen]) + what + " by the folds (";
  s += level_chosen == level_best
           ? std::string("the lowest CV RMSE")
           : "the fewest within one SE or 1 % of the lowest, " +
                 std::to_string(level_candidates[level_best]);
  s += "): CV RMSE";
  for (size_t q = 0; q < level_candidates.size(); ++q)
    s += (q ? ", " : " ") + std::to_string(level_candidates[q]) + " → " +
         FormatG(level_cv_rmse[q], 3);
  return s;
}

std::string InitialStateEvidence::Describe(const std::string& unit) const {
  if (!note.empty()) return note;
  std::string s;
  const model::InitialState states[3] = {model::InitialState::kCentred,
                                         model::InitialState::kDescended,
                                         model::InitialState::kAscended};
  for (int i = 0; i < 3; ++i)
    s +=
        std::string(i ? ", " : "") + model::InitialStateName(states[i]) + " " + FormatG(rmse[i], 3);
  return s + " " + unit + " over samples " + std::to_string(from) + "–" + std::to_string(to) +
         ": " + model::InitialStateName(state);
}

std::vector<InitialStateEvidence> DetectInitialStates(const io::RecordSet& set,
                                                      const FitOptions& base) {
  FitOptions o = base;
  o.family = "prandtl-ishlinskii";
  o.effects.clear();
  o.family_options.pi_operators = 12;
  o.family_options.initial_state = model::InitialState::kCentred;
  o.uncertainty = false;
  o.progress = nullptr;
  o.evaluator_factory = nullptr;
  FitResult fit = FitRecords(set, o);  // nothing searched: the weights by NNLS
  // With a transport delay where it lowers the training RMSE by 30 % or more: a sensor's lag at the
  // jump from rest would swamp the branch (the line search of one parameter, local). Not for less:
  // a delay also takes up some of the misfit of an operator unlike the plant, and then reads the
  // first branch wrong.
  FitOptions od = o;
  od.effects = {EffectKind::Named("delay")};
  od.sizing = {};
  od.sizing.enabled = true;
  od.search.algorithm = opt::SearchAlgorithm::kPso;
  od.search.line = {};
  FitResult delayed = FitRecords(set, od);
  if (delayed.train_mse < 0.49 * fit.train_mse) {
    fit = std::move(delayed);
    o = od;
  }
  const DataScale& scale = fit.model->scale();
  const double range = scale.u_max - scale.u_min;
  const model::InitialState states[3] = {model::InitialState::kCentred,
                                         model::InitialState::kDescended,
                                         model::InitialState::kAscended};
  std::vector<std::shared_ptr<RecordModel>> models;
  for (model::InitialState s : states) {
    FamilyOptions fo = o.family_options;
    fo.initial_state = s;
    models.push_back(
        std::make_shared<RecordModel>(MakeFamily(o.family, scale, fo), o.effects, scale));
  }
  std::vector<InitialStateEvidence> out;
  for (const io::Record& r : set.records) {
    InitialStateEvidence ev;
    ev.record = r.name;
    ev.role = r.role;
    // The first branch: from the end of the rest until the drive has been within 5 % of both ends
    // of the training range (the memory at rest is wiped out then: every state gives one output).
    const size_t from = std::min(r.rest_samples, r.end_scored);
    const double margin = 0.05 * range;
    bool low = r.u[0] <= scale.u_min + margin, high = r.u[0] >= scale.u_max - margin;
    size_t to = r.end_scored;
    for (size_t k = from; k < r.end_scored; ++k) {
      low = low || r.u[k] <= scale.u_min + margin;
      high = high || r.u[k] >= scale.u_max - margin;
      if (low && high) {
        to = k + 1;
        break;
      }
    }
    ev.from = from;
    ev.to = to;
    if (to <= from + 2) {
      ev.note = "no first branch (the drive does not leave its rest before the window ends)";
      out.push_back(ev);
      continue;
    }
    ev.rise = r.u[to - 1] - r.u[0];
    double best = kInf;
    for (int s = 0; s < 3; ++s) {
      std::vector<double> yhat;
      Evaluate(*models[static_cast<size_t>(s)], fit.params, fit.weights, r, &yhat);
      double sse = 0;
      for (size_t k = from; k < to; ++k) sse += (r.y[k] - yhat[k]) * (r.y[k] - yhat[k]);
      ev.rmse[s] = std::sqrt(sse / static_cast<double>(to - from));
      if (!std::isfinite(ev.rmse[s])) ev.rmse[s] = kInf;
      if (ev.rmse[s] < best) {
        best = ev.rmse[s];
        ev.state = states[s];
      }
    }
    out.push_back(ev);
  }
  return out;
}

model::InitialState TrainingInitialState(const std::vector<InitialStateEvidence>& evidence) {
  int count[3] = {0, 0, 0};
  for (const auto& e : evidence)
    if (e.role == model::CaseRole::kTrain && e.note.empty()) ++count[static_cast<int>(e.state)];
  int best = 0;
  for (int s = 1; s < 3; ++s)
    if (count[s] > count[best]) best = s;
  return static_cast<model::InitialState>(best);
}

namespace {

std::vector<size_t> UnexcitedRecords(const io::RecordSet& set, std::string* needs);

/// An effect whose magnitude depends on the drive's rate.
bool RateEffect(EffectKind e) {
  const std::string n = EffectName(e);
  return n == "delay" || n == "driver-lowpass" || n == "rate-dependence";
}

/// The training records' rate span (records/excitation.h DriveExcitation::rate_span); 0 when the
/// report cannot be made.
double TrainingRateSpan(const io::RecordSet& set) {
  try {
    return AnalyseExcitation(set).training.rate_span();
  } catch (const InputError&) {
    return 0;
  }
}

}  // namespace

std::string GridNote(const io::RecordSet& set, const SelectOptions& options) {
  if (!options.effect_sets.empty()) return "";
  const double span = TrainingRateSpan(set);
  if (span >= kMinRateSpan) return "";
  std::string needs;
  if (UnexcitedRecords(set, &needs).empty()) return "";
  return "delay is left out of the grid: the training drive has one rate (its half cycles' peak "
         "rates span " +
         FormatG(span, 3) + "×, under " + FormatG(kMinRateSpan, 2) +
         "×), where a delay is a phase that a hysteretic family's loop width gives as well, and "
         "the withheld drives have loops the training lacks: the folds cannot tell the two apart, "
         "and a delay fitted there for loop width mispredicts the other loops (ask for it with "
         "--effects)";
}

std::vector<Candidate> CandidateGrid(const io::RecordSet& set, const SelectOptions& options,
                                     model::InitialState state) {
  std::vector<std::string> families = options.families;
  if (families.empty())
    for (const FamilyDef* f : Families())
      if (f->auto_grid) families.emplace_back(f->name);
  std::vector<std::vector<EffectKind>> sets = options.effect_sets;
  const bool default_sets = sets.empty();
  if (default_sets) {
    const EffectKind delay = ParseEffect("delay"), creep = ParseEffect("creep"),
                     spectrum = ParseEffect("creep-spectrum");
    sets = {{}, {delay}, {creep}, {creep, delay}, {spectrum}, {spectrum, delay}};
  }
  const bool one_rate = !GridNote(set, options).empty();
  const DataScale scale = MeasureScale(set.WithRole(model::CaseRole::kTrain));
  std::vector<std::string> unsupported;
  for (const EffectInfo& e : EffectLibrary(scale))
    if (!e.unsupported.empty()) unsupported.push_back(e.name);
  std::vector<Candidate> out;
  for (const std::string& f : families) {
    const auto family = MakeFamily(f, scale);
    for (const auto& effects : sets) {
      bool ok = true;
      for (EffectKind e : effects) {
        ok = ok && !family->Excludes(EffectName(e)) && !Takes(unsupported, EffectName(e));
        // By default: no rate effect on a training of one rate (GridNote); the creep spectrum on
        // the linear families only, whose weights it is solved with (records/spectrum_solve.h):
        // on the others each of its weights would be searched.
        ok = ok && !(default_sets && one_rate && RateEffect(e));
        ok = ok &&
             !(default_sets && std::string(EffectName(e)) == "creep-spectrum" && !LinearFamily(f));
      }
      if (!ok) continue;
      // A linear family at the ladder's first rung: its folds choose the others (SelectModel).
      out.push_back({f, effects, LinearFamily(f) ? Ladder(options).front() : 0, state});
    }
  }
  return out;
}

ModelScore CrossValidate(
    const io::RecordSet& set, const Candidate& c, const FitOptions& fit, int folds,
    const std::function<RecordEvaluatorFactory(const FamilyOptions&)>& service) {
  size_t fits = 0;
  return CrossValidateAll(
      set, {c}, [&](size_t, size_t) { return fit; }, folds, fit.threads, service, nullptr,
      &fits)[0];
}

size_t OneStandardErrorChoice(std::vector<ModelScore>& scores) {
  size_t best = scores.size();
  for (size_t i = 0; i < scores.size(); ++i)
    if (std::isfinite(scores[i].cv_rmse) &&
        (best == scores.size() || scores[i].cv_rmse < scores[best].cv_rmse))
      best = i;
  if (best == scores.size()) throw InputError("no candidate model could be fitted in every fold");
  const ModelScore& b = scores[best];
  for (ModelScore& s : scores) {
    s.within_one_se = false;
    s.se_vs_best = b.cv_se;
    if (!std::isfinite(s.cv_rmse)) continue;
    const size_t K = b.fold_rmse.size();
    if (K >= 2 && s.fold_rmse.size() == K) {
      double mean = 0, var = 0;
      for (size_t k = 0; k < K; ++k)
        mean += (s.fold_rmse[k] - b.fold_rmse[k]) / static_cast<double>(K);
      for (size_t k = 0; k < K; ++k) {
        const double d = s.fold_rmse[k] - b.fold_rmse[k] - mean;
        var += d * d;
      }
      s.se_vs_best = std::sqrt(var / static_cast<double>(K - 1) / static_cast<double>(K));
    }
    s.within_one_se = s.cv_rmse - b.cv_rmse <= s.se_vs_best;
  }
  size_t pick = best;
  for (size_t i = 0; i < scores.size(); ++i) {
    const ModelScore& s = scores[i];
    if (!s.within_one_se) continue;
    const ModelScore& p = scores[pick];
    if (s.parameters < p.parameters || (s.parameters == p.parameters && s.cv_rmse < p.cv_rmse))
      pick = i;
  }
  return pick;
}

namespace {

/// The initial states worth trying in the second round: the first and, unless the user gave one,
/// the rest-level rule where it differs for a training record.
std::vector<model::InitialState> StatesToTry(const io::RecordSet& set, const SelectOptions& options,
                                             model::InitialState first) {
  std::vector<model::InitialState> states = {first};
  if (!options.initial_state_given) {
    const DataScale scale = MeasureScale(set.WithRole(model::CaseRole::kTrain));
    for (const io::Record* r : set.WithRole(model::CaseRole::kTrain))
      if (model::ResolveInitialState(model::InitialState::kAuto, r->u[0], scale.u_min,
                                     scale.u_max) != first) {
        states.push_back(model::InitialState::kAuto);
        break;
      }
  }
  return states;
}

/// The refitted finalists' training and withheld RMSE.
void SetRefitErrors(const std::vector<FitResult>& refits, std::vector<ModelScore>& second) {
  for (size_t i = 0; i < refits.size(); ++i) {
    if (!refits[i].model) continue;
    double tr = 0, wh = 0;
    size_t nt = 0, nw = 0;
    for (const RecordMetrics& m : refits[i].metrics) {
      const double sse = m.rmse * m.rmse * static_cast<double>(m.samples);
      if (m.role == model::CaseRole::kTrain) {
        tr += sse;
        nt += m.samples;
      } else {
        wh += sse;
        nw += m.samples;
      }
    }
    second[i].train_rmse = nt ? std::sqrt(tr / static_cast<double>(nt)) : kInf;
    if (nw) second[i].withheld_rmse = std::sqrt(wh / static_cast<double>(nw));
  }
}

/// WeighUnexcited: a finalist whose prediction where the training lacks excitation parts from the
/// families' median by more than this × its CV RMSE extrapolates on its own.
constexpr double kOwnExtrapolation = 3;
/// …and only a finalist whose CV RMSE is within this factor of the best can take the choice over.
constexpr double kPlausible = 3;

/// The withheld records whose drives need what the training lacks in the hysteresis itself
/// (reversals the training's cells do not hold, or range beyond it: records/excitation.h), and what
/// each needs; none when the report cannot be made.
std::vector<size_t> UnexcitedRecords(const io::RecordSet& set, std::string* needs) {
  std::vector<size_t> out;
  try {
    const ExcitationReport ex = AnalyseExcitation(set);
    for (const WithheldExcitation& w : ex.withheld) {
      std::string what;  // "reversals 70 % uncovered", "range 4 % beyond"
      for (const ExcitationNeed& n : w.needs) {
        if (n.kind == ExcitationNeed::Kind::kReversals)
          what += (what.empty() ? "" : ", ") + FormatG(100 * n.amount, 2) +
                  " % of its reversals where the training has none";
        if (n.kind == ExcitationNeed::Kind::kRange)
          what += (what.empty() ? "" : ", ") + std::string("a drive ") +
                  FormatG(100 * n.amount, 2) + " % of the range beyond the training's";
      }
      if (what.empty()) continue;
      out.push_back(w.record);
      *needs += (needs->empty() ? "" : "; ") + set.records[w.record].name + ": " + what;
    }
  } catch (const InputError&) {
    out.clear();
  }
  return out;
}

/// Where the withheld drives need what the training lacks, no fold of the training shows how a
/// model extrapolates: the CV RMSE says nothing there, and a Preisach grid's interior, a dead
/// zone's knee, are set there by the prior alone. So the finalists' predictions on those drives
/// (their responses are not looked at: each prediction's mean over the window removed, the record's
/// offset being fitted) are compared with the median of the families' (the best finalist of each
/// family, three families at least): parting_i, the RMS of finalist i's less the median over those
/// samples, is how far it extrapolates on its own. A finalist that parts by more than
/// kOwnExtrapolation × its own CV RMSE — its prediction there is its prior's, not the data's — is
/// passed over, and the one-standard-error rule is applied to the others within kPlausible × the
/// best CV RMSE: the choice degrades gracefully (wrong there, it is wrong with the others, not
/// alone); when none is left, every plausible finalist extrapolates on its own and the one-SE
/// choice stands. Returns the chosen index (`chosen` when there is nothing to weigh or no finalist
/// is passed over) and sets each finalist's parting and the report's sentence.
size_t WeighUnexcited(const io::RecordSet& set, const std::vector<size_t>& unexcited,
                      const std::string& needs, const std::vector<FitResult>& refits,
                      std::vector<ModelScore>& second, size_t chosen, const std::string& unit,
                      std::string* sentence) {
  std::vector<size_t> reps;  // the best finalist of each family, refitted
  for (size_t i = 0; i < second.size(); ++i) {
    if (!refits[i].model || !std::isfinite(second[i].cv_rmse)) continue;
    bool placed = false;
    for (size_t& r : reps) {
      if (second[r].candidate.family != second[i].candidate.family) continue;
      if (second[i].cv_rmse < second[r].cv_rmse) r = i;
      placed = true;
    }
    if (!placed) reps.push_back(i);
  }
  if (unexcited.empty() || reps.size() < 3) return chosen;
  // Each finalist's predictions over the unexcited windows, mean removed per record.
  auto centred = [&](size_t i) {
    std::vector<double> v;
    for (size_t r : unexcited) {
      const io::Record& rec = set.records[r];
      const std::vector<double>& y = refits[i].yhat[r];
      double mean = 0;
      for (size_t k = rec.first_scored; k < rec.end_scored; ++k)
        mean += y[k] / static_cast<double>(rec.scored());
      for (size_t k = rec.first_scored; k < rec.end_scored; ++k) v.push_back(y[k] - mean);
    }
    return v;
  };
  std::vector<std::vector<double>> rep_pred;
  for (size_t r : reps) rep_pred.push_back(centred(r));
  const size_t n = rep_pred.front().size();
  std::vector<double> median(n), column(reps.size());
  for (size_t k = 0; k < n; ++k) {
    for (size_t j = 0; j < reps.size(); ++j) column[j] = rep_pred[j][k];
    std::sort(column.begin(), column.end());
    const size_t h = column.size() / 2;
    median[k] = column.size() % 2 ? column[h] : 0.5 * (column[h - 1] + column[h]);
  }
  double widest = 0;
  for (size_t i = 0; i < second.size(); ++i) {
    if (!refits[i].model || !std::isfinite(second[i].cv_rmse)) continue;
    const std::vector<double> v = centred(i);
    double ss = 0;
    for (size_t k = 0; k < n; ++k) ss += (v[k] - median[k]) * (v[k] - median[k]);
    second[i].parting = std::sqrt(ss / static_cast<double>(std::max<size_t>(n, 1)));
    if (std::isfinite(second[i].parting)) widest = std::max(widest, second[i].parting);
  }
  // A finalist whose prediction there departs from the families' median by more than
  // kOwnExtrapolation × its own CV RMSE extrapolates on its own (its prior's, not the data's):
  // the one-SE rule is applied to the others (to all when none is left).
  std::vector<ModelScore> kept;
  std::vector<size_t> index;
  std::string dropped;
  double best_cv = kInf;
  for (const ModelScore& m : second)
    if (m.round == 2) best_cv = std::min(best_cv, m.cv_rmse);
  for (size_t i = 0; i < second.size(); ++i) {
    if (!std::isfinite(second[i].parting) || !std::isfinite(second[i].cv_rmse)) continue;
    if (second[i].round != 2) continue;  // the median's reference only: not cross-validated again
    // Only a finalist near the best where the training shows it can take over (when every such
    // one parts on its own, all extrapolate there alike: the one-SE choice stands).
    if (second[i].cv_rmse > kPlausible * best_cv) continue;
    if (second[i].parting > kOwnExtrapolation * second[i].cv_rmse) {
      dropped += (dropped.empty() ? "" : ", ") + second[i].candidate.Describe() + " (" +
                 FormatG(second[i].parting, 3) + " against CV " + FormatG(second[i].cv_rmse, 3) +
                 ")";
      continue;
    }
    kept.push_back(second[i]);
    index.push_back(i);
  }
  const size_t pick =
      kept.empty() || dropped.empty() ? chosen : index[OneStandardErrorChoice(kept)];
  const ModelScore &was = second[chosen], &now = second[pick];
  *sentence =
      "**The choice rests on an unexcited region.** The withheld drives need excitation "
      "the training lacks (" +
      needs +
      "): no fold of the training shows how a model extrapolates there. The "
      "finalists' predictions there (their responses not used) part from the median of "
      "the " +
      std::to_string(reps.size()) + " families' best by up to " + FormatG(widest, 3) + " " + unit +
      " RMS (\"parting\"); ";
  if (!dropped.empty() && kept.empty()) {
    *sentence += "every finalist within " + FormatG(kPlausible, 2) +
                 "× the best CV RMSE parts by more than " + FormatG(kOwnExtrapolation, 2) +
                 "× its own (" + dropped +
                 "): they all extrapolate there on their own, and the one-standard-error choice "
                 "stands: " +
                 now.candidate.Describe() + ".";
  } else if (dropped.empty()) {
    *sentence +=
        "none parts by more than " + FormatG(kOwnExtrapolation, 2) +
        "× its own CV RMSE, so the one-standard-error choice stands: " + now.candidate.Describe() +
        " (parting " + FormatG(now.parting, 3) + " " + unit + ").";
  } else {
    *sentence +=
        "those that part by more than " + FormatG(kOwnExtrapolation, 2) +
        "× their own CV RMSE extrapolate on their own (the prior's, not the data's) "
        "and are passed over: " +
        dropped + "; the one-standard-error rule over the others chooses " +
        now.candidate.Describe() + " (CV " + FormatG(now.cv_rmse, 3) + ", parting " +
        FormatG(now.parting, 3) + " " + unit + ")" +
        (pick != chosen ? ", the one that degrades gracefully, over " + was.candidate.Describe() +
                              " (CV " + FormatG(was.cv_rmse, 3) + ")"
                        : std::string()) +
        ".";
  }
  return pick;
}

/// FitRecords of candidate c with options f (c's), but a candidate SearchedCoarse at `base`: its
/// effects searched at `base`, its weights re-solved at its own resolution with the effects there
/// (the penalty and strength validated there; FitPreisachLevels for a Preisach grid), every record
/// evaluated with the whole model.
FitResult FitCandidate(const io::RecordSet& set, const Candidate& c, FitOptions f, int base) {
  if (!SearchedCoarse(c, base)) return FitRecords(set, f);
  const int levels = f.family_options.pi_operators;
  f.family_options.pi_operators = base;
  FitResult r = FitRecords(set, f);
  const DataScale scale = MeasureScale(set.WithRole(model::CaseRole::kTrain));
  const std::vector<const io::Record*> train = set.WithRole(model::CaseRole::kTrain);
  FamilyOptions fo = f.family_options;
  fo.pi_operators = levels;
  r.model = std::make_shared<RecordModel>(MakeFamily(c.family, scale, fo), c.effects, scale);
  if (c.family == kPreisachFamily.name) {
    const PreisachLevelFits fits =
        FitPreisachLevels(train, scale, fo, c.effects, r.params, {levels});
    r.weights = fits.fitness.front()->Run(fits.params, false).weights;
    r.regularisation = fits.fitness.front()->validation();
  } else {
    const RecordFitness fitness(*r.model, train, opt::kDefaultErrorCost, r.params);
    r.weights = fitness.Run(r.params, false).weights;
    r.regularisation = fitness.validation();
  }
  EvaluateResolved(set, r);
  return r;
}

/// The chosen candidate refitted on every training record with `fit`'s own search (its threads).
FitResult RefitChosen(const io::RecordSet& set, const Candidate& c, const SelectOptions& options) {
  FitOptions f = c.Options(options.fit);
  if (options.service) f.evaluator_factory = options.service(f.family_options);
  f.progress = nullptr;
  return FitCandidate(set, c, f, Ladder(options).front());
}

/// The finalists refitted on every training record: the chosen one (none: finals.size()) by
/// RefitChosen first, the others side by side with the finalists' search (their errors in `second`
/// when they cannot be fitted).
std::vector<FitResult> RefitFinalists(const io::RecordSet& set,
                                      const std::vector<Candidate>& finals, size_t chosen,
                                      const SelectOptions& options,
                                      std::vector<ModelScore>& second) {
  const int threads = std::max(1, options.fit.threads);
  std::vector<FitResult> refits(finals.size());
  if (chosen < finals.size()) refits[chosen] = RefitChosen(set, finals[chosen], options);
  const DataScale scale = MeasureScale(set.WithRole(model::CaseRole::kTrain));
  RunTasks(finals.size(), options.service ? 1 : threads, [&](size_t i) {
    if (i == chosen) return;
    FitOptions f = finals[i].Options(
        FinalOptions(options, MakeCandidate(scale, finals[i], FitOptions{}, {}).searched));
    if (options.service) f.evaluator_factory = options.service(f.family_options);
    f.threads = options.service ? threads : 1;
    f.progress = nullptr;
    f.uncertainty = false;
    try {
      refits[i] = FitCandidate(set, finals[i], f, Ladder(options).front());
    } catch (const InputError& e) {
      second[i].error = e.what();
    }
  });
  return refits;
}

/// The ranking: the finalists by CV RMSE, then the screened-only ones by theirs (res.ranking,
/// res.chosen).
void RankCandidates(const std::vector<ModelScore>& second, size_t chosen,
                    const std::vector<ModelScore>& screen, const std::vector<size_t>& order,
                    const std::vector<Candidate>& finals,
                    SelectionResult& res) {
  std::vector<size_t> o2(second.size());
  for (size_t i = 0; i < o2.size(); ++i) o2[i] = i;
  std::stable_sort(o2.begin(), o2.end(),
                   [&](size_t a, size_t b) { return second[a].cv_rmse < second[b].cv_rmse; });
  for (size_t i : o2) {
    if (i == chosen) res.chosen = res.ranking.size();
    res.ranking.push_back(second[i]);
  }
  for (size_t i : order) {
    bool final = false;
    for (const Candidate& c : finals) final = final || SameModel(c, screen[i].candidate);
    if (!final) res.ranking.push_back(screen[i]);
  }
}

/// The finalists' round: each cross-validated again with the finalists' search (but those only
/// the families' median needs, `reference`, which keep their screening), the one-SE rule's choice
/// among them in `chosen`; each carries its screening's CV RMSE and resolution table.
std::vector<ModelScore> CrossValidateFinalists(const io::RecordSet& set,
                                               const SelectOptions& options,
                                               const std::vector<Candidate>& finals,
                                               const std::vector<const ModelScore*>& final_screen,
                                               const std::vector<bool>& reference, size_t& fits,
                                               size_t& chosen) {
  auto say = [&](const std::string& s) {
    if (options.progress) options.progress(s);
  };
  std::vector<Candidate> cv_finals;
  for (size_t i = 0; i < finals.size(); ++i)
    if (!reference[i]) cv_finals.push_back(finals[i]);
  say("cross-validating " + std::to_string(cv_finals.size()) + " finalists with the full search" +
      (cv_finals.size() < finals.size()
           ? " (" + std::to_string(finals.size() - cv_finals.size()) +
                 " more families' best refitted for the median where the training lacks "
                 "excitation)"
           : std::string()));
  std::vector<ModelScore> cvd = CrossValidateAll(
      set, cv_finals, [&](size_t, size_t searched) { return FinalOptions(options, searched); },
      options.folds, std::max(1, options.fit.threads), options.service, options.progress, &fits,
      nullptr, Ladder(options).front());
  // 4. The choice: the one-SE rule over the finalists (the withheld records not seen yet).
  const size_t chosen_cv = OneStandardErrorChoice(cvd);
  std::vector<ModelScore> second(finals.size());
  for (size_t i = 0, j = 0; i < finals.size(); ++i) {
    if (reference[i]) {
      second[i] = *final_screen[i];
      second[i].candidate = finals[i];
      second[i].within_one_se = false;
    } else {
      if (j == chosen_cv) chosen = i;
      second[i] = std::move(cvd[j++]);
      second[i].round = 2;
    }
    second[i].screen_cv_rmse = final_screen[i]->cv_rmse;
    second[i].level_candidates = final_screen[i]->level_candidates;
    second[i].level_cv_rmse = final_screen[i]->level_cv_rmse;
    second[i].level_best = final_screen[i]->level_best;
    second[i].level_chosen = final_screen[i]->level_chosen;
  }
  return second;
}

}  // namespace

SelectionResult SelectModel(const io::RecordSet& set, const SelectOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  SelectionResult res;
  res.folds = options.folds;
  auto say = [&](const std::string& s) {
    if (options.progress) options.progress(s);
  };
  const int threads = std::max(1, options.fit.threads);
  // 1. The memory at rest the records' first rises show (reported per record; the training
  // records' choose), unless the user gave one.
  res.initial_states = DetectInitialStates(set, options.fit);
  res.detected = TrainingInitialState(res.initial_states);
  const model::InitialState first =
      options.initial_state_given ? options.fit.family_options.initial_state : res.detected;
  // The other state worth trying in the second round: the rest-level rule where it differs for a
  // training record.
  const std::vector<model::InitialState> states = StatesToTry(set, options, first);
  // 2. Screening: every candidate, a small search.
  const std::vector<Candidate> grid = CandidateGrid(set, options, first);
  res.grid_note = GridNote(set, options);
  if (const std::string l = LevelsNote(set, options); !l.empty())
    res.grid_note += (res.grid_note.empty() ? "" : "; ") + l;
  say("screening " + std::to_string(grid.size()) + " candidates by " +
      std::to_string(options.folds) + "-fold blocked cross-validation on the training records");
  std::vector<std::vector<double>> fold_params;
  std::vector<ModelScore> screen = CrossValidateAll(
      set, grid, [&](size_t, size_t searched) { return ScreenOptions(options, searched); },
      options.folds, threads, options.service, options.progress, &res.fold_fits, &fold_params);
  // The linear families' resolutions: chosen by the same folds (their weights re-solved).
  ChooseLevelsByFolds(set, options, fold_params, screen, &res.fold_fits);
  for (size_t i = 0; i < screen.size(); ++i) {
    screen[i].screen_cv_rmse = screen[i].cv_rmse;
    if (!screen[i].level_candidates.empty())
      say(screen[i].candidate.Describe() + ": " + screen[i].LevelsDescribe());
  }
  // 3. The finalists: the best of the screening and the simplest within one SE of its best,
  // each with every initial state worth trying, with the full search.
  std::vector<size_t> order(screen.size());
  for (size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::stable_sort(order.begin(), order.end(),
                   [&](size_t a, size_t b) { return screen[a].cv_rmse < screen[b].cv_rmse; });
  std::vector<size_t> picked;
  for (size_t i : order)
    if (picked.size() < options.finalists && std::isfinite(screen[i].cv_rmse)) picked.push_back(i);
  if (picked.empty())
    throw InputError("no candidate model could be fitted in every fold of the screening");
  const size_t simplest = OneStandardErrorChoice(screen);
  for (auto& s : screen) s.within_one_se = false;  // (the finals' rule is reported)
  if (std::find(picked.begin(), picked.end(), simplest) == picked.end()) picked.push_back(simplest);
  std::vector<Candidate> finals;
  std::vector<const ModelScore*> final_screen;  // each finalist's screening
  std::vector<bool> reference;                  // only the families' median (below)
  auto add = [&](const ModelScore& screened, bool every_state, bool only_reference) {
    Candidate c = screened.candidate;
    for (const Candidate& f : finals)
      if (SameModel(f, c)) return;
    for (model::InitialState s : states) {
      if (s != first && (!every_state || !TakesInitialState(c.family))) continue;
      c.initial_state = s;
      finals.push_back(c);
      final_screen.push_back(&screened);
      reference.push_back(only_reference);
    }
  };
  for (size_t i : picked) add(screen[i], i == picked.front(), false);
  // Where the withheld drives need what the training lacks, the best of every family too: their
  // predictions there are weighed after the choice (WeighUnexcited).
  std::string needs;
  const std::vector<size_t> unexcited = UnexcitedRecords(set, &needs);
  if (!unexcited.empty()) {
    std::vector<std::string> seen;
    for (size_t i : order) {
      if (!std::isfinite(screen[i].cv_rmse) || Takes(seen, grid[i].family)) continue;
      seen.push_back(grid[i].family);
      // One screened beyond kPlausible × the best can never take the choice over (WeighUnexcited):
      // it joins the families' median there, refitted, without its folds again.
      add(screen[i], false, screen[i].cv_rmse > kPlausible * screen[order.front()].cv_rmse);
    }
  }
  size_t chosen = 0;
  std::vector<ModelScore> second = CrossValidateFinalists(set, options, finals, final_screen,
                                                          reference, res.fold_fits, chosen);
  res.best_cv_rmse = second[chosen].cv_rmse;
  for (const auto& s : second)
    if (s.round == 2) res.best_cv_rmse = std::min(res.best_cv_rmse, s.cv_rmse);
  say("chosen: " + finals[chosen].Describe() + " (CV RMSE " +
      io::FormatNumber(second[chosen].cv_rmse) + " ± " + io::FormatNumber(second[chosen].cv_se) +
      ")");
  // 5. After the choice: the finalists refitted on every training record; the withheld errors.
  // Where the withheld drives are unexcited the choice may still change (6.): every finalist is
  // refitted with the finalists' search first (their predictions weighed alike), and the chosen
  // one with `fit`'s own once it is final.
  const bool weigh = !unexcited.empty();
  std::vector<FitResult> refits =
      RefitFinalists(set, finals, weigh ? finals.size() : chosen, options, second);
  SetRefitErrors(refits, second);
  // 6. An unexcited region: the finalists' predictions there weighed (their drives only).
  if (weigh) {
    const size_t weighed = WeighUnexcited(set, unexcited, needs, refits, second, chosen,
                                          set.response_unit, &res.unexcited);
    if (weighed != chosen) say("weighed where the training lacks excitation: " +
                               finals[weighed].Describe());
    chosen = weighed;
    refits[chosen] = RefitChosen(set, finals[chosen], options);
    SetRefitErrors(refits, second);
  }
  res.fit = std::move(refits[chosen]);
  res.fit_options = finals[chosen].Options(options.fit);
  RankCandidates(second, chosen, screen, order, finals, res);
  res.noise = EstimateNoiseFloor(set);
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return res;
}

}  // namespace pz::records
