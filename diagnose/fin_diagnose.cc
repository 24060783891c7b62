#include "diagnose/fin_diagnose.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <exception>

#include "io/fin_records.h"
#include "model/model_comparison.h"
#include "records/noise_floor.h"
#include "diagnose/verdict.h"
#include "model/saturation.h"

namespace pz::diagnose {

using opt::LevenbergMarquardt;
using opt::LmOptions;
using opt::LmResult;
using opt::ParallelFor;
using opt::ResidualFunction;
namespace {

std::string NextMeasurementHint(model::EffectKind a, model::EffectKind b) {
  return records::FinNextMeasurementHint(a, b);
}

using model::EffectKind;

std::string Fmt(const char* fmt, double a = 0, double b = 0, double c = 0, double d = 0,
                double e = 0, double f = 0) {
  char buf[512];
  std::snprintf(buf, sizeof buf, fmt, a, b, c, d, e, f);
  return buf;
}

void Say(const DiagnoseOptions& o, const std::string& msg) {
  if (o.progress) o.progress(msg);
}

// Per-case floor where `fit` sits on its saturations (records/noise_floor.h).
std::vector<double> CaseFloors(const DiagnosisModel& m, const FitResult& fit) {
  const ParameterLayout layout(fit.structure);
  std::vector<double> floors, y;
  for (size_t c = 0; c < m.cases().size(); ++c) {
    const DiagCase& dc = m.cases()[c];
    const model::SimulationSummary s = m.Simulate(layout, fit.x, c, y);
    floors.push_back(s.ok()
                         ? records::SaturationAwareFloor(dc.noise, dc.measured_deg, y, dc.b1, dc.b2)
                         : dc.noise.floor_rms_deg);
  }
  return floors;
}

std::vector<double> FeatureExcess(const model::GroupResidual& g) {
  return records::ResidualFeatureExcess(g);
}

// Fits a structure: fast structures get a global search seeded around `from`, beam structures are
// refined from `from` with a few starting magnitudes of the new effect.
FitResult FitStructure(const DiagnosisModel& m, const ParameterLayout& layout,
                       const ParameterLayout* from_layout, const std::vector<double>* from_x,
                       EffectKind added, const DiagnoseOptions& o) {
  FitOptions fo;
  fo.threads = o.threads;
  fo.evaluator_factory = o.evaluator_factory;
  fo.lm = o.lm;
  fo.lm.threads = o.threads;
  if (!from_x) {  // the base model: global search only
    fo.de = o.de_base;
    fo.de.seed = o.seed;
    return FitGlobal(m, layout, fo);
  }
  const std::vector<double> x0 = layout.Extend(*from_x, *from_layout);
  // The new effect's magnitude parameter.
  int mag = -1;
  const model::EffectInfo& info = model::GetEffectInfo(added);
  for (int i = ParameterLayout::kBase; i < layout.size(); ++i) {
    const ParamSpec& s = layout.specs()[i];
    if (s.effect == static_cast<int>(layout.structure().size()) - 1 &&
        s.effect_param == info.magnitude_param)
      mag = i;
  }
  // Starting magnitudes: fractions of the upper end of the range; for a parameter of either sign
  // the first fraction on both sides instead.
  std::vector<std::vector<double>> starts;
  if (mag >= 0) {
    const ParamSpec& s = layout.specs()[mag];
    const bool both_signs = s.lower < 0 && s.upper > 0;
    for (size_t j = 0; j < o.cvode_start_fractions.size(); ++j) {
      const double f = both_signs ? o.cvode_start_fractions[0] : o.cvode_start_fractions[j];
      std::vector<double> x = x0;
      x[mag] = both_signs && j % 2 == 1 ? f * s.lower : f * s.upper;
      starts.push_back(x);
    }
  }
  bool beam = false;
  for (EffectKind k : layout.structure())
    beam = beam || model::GetEffectInfo(k).stage == model::EffectStage::kBeam;
  if (beam) {
    fo.global_search = false;
    fo.lm.max_iterations = o.cvode_lm_iterations;
    fo.lm.central = false;  // forward differences: half the CVODE runs per Jacobian
    fo.starts = starts;
    if (fo.starts.empty()) fo.starts.push_back(x0);
  } else {
    fo.de = o.de_candidate;
    fo.de.seed = o.seed + 1000 * (static_cast<uint64_t>(model::FinIndex(added)) + 1) +
                 17 * layout.structure().size();
    fo.seeds = starts;
    fo.seeds.insert(fo.seeds.begin(), x0);
    fo.starts = {x0};
  }
  return FitGlobal(m, layout, fo);
}

double SumWithheld(const DiagnosisModel& m, std::span<const double> per_case) {
  double s = 0;
  for (size_t c = 0; c < m.cases().size(); ++c)
    if (!m.cases()[c].training) s += per_case[c];
  return s;
}

std::vector<double> CaseFloorVariance(const DiagnosisModel& m, std::span<const double> floors) {
  std::vector<double> v;
  for (size_t c = 0; c < m.cases().size(); ++c)
    v.push_back(floors[c] * floors[c] * static_cast<double>(m.cases()[c].measured_deg.size()));
  return v;
}

std::vector<Absorption> Compare(const FitResult& without, const FitResult& with) {
  return records::AbsorbedParameters(without.params, with.params, ParameterLayout::kBase);
}

// Fits every candidate effect on top of `start` (no scoring).
std::vector<CandidateResult> FitCandidates(const DiagnosisModel& m, const FitResult& start,
                                           const ParameterLayout& start_layout,
                                           const std::vector<EffectKind>& kinds,
                                           const DiagnoseOptions& o, int64_t* evals) {
  std::vector<EffectKind> todo;
  for (EffectKind k : kinds)
    if (std::find(start.structure.begin(), start.structure.end(), k) == start.structure.end())
      todo.push_back(k);
  std::vector<CandidateResult> out(todo.size());
  std::vector<std::string> lines(todo.size());
  std::vector<std::exception_ptr> errors(todo.size());
  // Each fit is independent of the others: concurrent fits give the same results.
  auto fit_one = [&](int i) {
    const EffectKind k = todo[i];
    std::vector<EffectKind> structure = start.structure;
    structure.push_back(k);
    const ParameterLayout layout(structure);
    const auto t0 = std::chrono::steady_clock::now();
    CandidateResult& c = out[i];
    c.kind = k;
    c.fit = FitStructure(m, layout, &start_layout, &start.x, k, o);
    c.added_params = layout.size() - start_layout.size();
    if (c.fit.ok && c.fit.train_pi > start.train_pi) {
      // The refinement ended above the nested model (effect at zero): keep the nested solution.
      FitResult nested = start;
      nested.structure = layout.structure();
      nested.description = layout.Describe();
      nested.x = layout.Extend(start.x, start_layout);
      nested.evaluations = c.fit.evaluations;
      nested.message =
          "refinement ended above the starting model (" + c.fit.message + "): effect kept at zero";
      ComputeUncertainty(m, layout, nested, o.threads);
      c.fit = std::move(nested);
    }
    const double wall =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    lines[i] = std::string("  ") + model::EffectName(k) +
               (c.fit.ok ? Fmt(": training RMS %.4f, withheld RMS %.4f deg",
                               std::sqrt(c.fit.train_pi / m.training_samples()),
                               std::sqrt(c.fit.withheld_pi / m.withheld_samples()))
                         : ": fit failed: " + c.fit.message) +
               Fmt(" (%.1f s)", wall);
    if (o.concurrent_fits <= 1) Say(o, lines[i]);
  };
  ParallelFor(static_cast<int>(todo.size()), o.concurrent_fits, [&](int i) {
    try {
      fit_one(i);
    } catch (...) {  // e.g. the service failed: rethrown on the calling thread
      errors[i] = std::current_exception();
    }
  });
  for (const auto& e : errors)
    if (e) std::rethrow_exception(e);
  for (size_t i = 0; i < out.size(); ++i) {
    *evals += out[i].fit.evaluations;
    if (o.concurrent_fits > 1) Say(o, lines[i]);
  }
  return out;
}

// The candidates of a round as the verdict names them (diagnose/verdict.h), in ranked order.
std::vector<records::VerdictCandidate> VerdictCandidates(
    const std::vector<CandidateResult>& ranked) {
  std::vector<records::VerdictCandidate> v;
  for (const CandidateResult& c : ranked) v.push_back({model::EffectName(c.kind), &c});
  return v;
}

// What the bench tells the verdict of a round: its starting model, unit and floor, and (for a tie)
// what would separate the two.
records::VerdictText RoundText(const RoundResult& round, const FitResult& start) {
  records::VerdictText t;
  t.model = start.structure.empty() ? "the base model" : start.description;
  t.unit = "deg";
  t.floor_source = "rounding, scatter and saturation plateaus per case";
  if (round.runner_up >= 0)
    t.next = NextMeasurementHint(round.candidates[static_cast<size_t>(round.named)].kind,
                                 round.candidates[static_cast<size_t>(round.runner_up)].kind);
  return t;
}

// The gap of `start` against the floors, and its candidates scored, ranked and judged by the rules
// of diagnose/decision.h; the bench supplies the floors, the localised excess and the squared
// errors.
RoundResult ScoreRound(const DiagnosisModel& m, const FitResult& start,
                       const model::ResidualAnalysis& start_analysis,
                       std::span<const double> floors, std::vector<CandidateResult> candidates,
                       const DiagnoseOptions& o) {
  RoundResult round;
  round.base_structure = start.structure;
  const double nw = m.withheld_samples(), nt = m.training_samples();
  const double s_floor = SumWithheld(m, CaseFloorVariance(m, floors));
  double s_floor_t = 0;
  for (size_t c = 0; c < m.cases().size(); ++c)
    if (m.cases()[c].training)
      s_floor_t += floors[c] * floors[c] * m.cases()[c].measured_deg.size();
  const records::Gap gap = records::MeasureGap(start.withheld_pi, start.train_pi, s_floor,
                                               s_floor / nw, s_floor_t / nt, nw, nt, o.rules);
  round.s0 = gap.s0;
  round.s_floor = gap.s_floor;
  round.rms_ratio = gap.rms_ratio;
  round.significant = gap.significant;
  Say(o,
      "  starting model: " + start.description +
          Fmt(" withheld RMS %.4f deg = %.2f x floor", std::sqrt(round.s0 / nw), round.rms_ratio));
  const std::vector<double> start_excess = FeatureExcess(start_analysis.withheld);
  for (CandidateResult& c : candidates) {
    if (!c.fit.ok) {
      records::FailCandidate(c.fit.message, c);
      continue;
    }
    const model::ResidualAnalysis ra = AnalyseFit(m, c.fit, floors);
    records::ScoreCandidate(gap, c.fit.withheld_pi, c.fit.train_pi, c.added_params,
                            records::PatternExplained(start_excess, FeatureExcess(ra.withheld)),
                            o.rules, c);
    Say(o, std::string("  ") + model::EffectName(c.kind) +
               Fmt(": withheld RMS %.4f deg, score %.1f, closed %.0f %%, pattern %.0f %%",
                   std::sqrt(c.s_withheld / nw), c.score, 100 * c.closed, 100 * c.pattern));
  }
  round.candidates = std::move(candidates);
  records::RankByScore(round.candidates);
  const std::vector<records::CandidateScore*> ranked = records::Scores(round.candidates);
  records::AssignWeights(gap, ranked);
  // The withheld squared errors of the starting model (−1) or of candidate i, for the paired block
  // tests (model/model_comparison.h).
  const records::SquaredErrors squares = [&](int i) {
    const FitResult& f = i < 0 ? start : round.candidates[static_cast<size_t>(i)].fit;
    std::vector<double> r;
    m.Residuals(ParameterLayout(f.structure), f.x, false, r);
    for (double& v : r) v *= v;
    return r;
  };
  const records::Naming naming = records::NameEffect(gap, ranked, squares, o.rules);
  round.named = naming.named;
  round.runner_up = naming.runner_up;
  round.z_runner_up = naming.z_runner_up;
  round.gap = gap;
  round.verdict = records::ComposeVerdict(gap, VerdictCandidates(round.candidates), naming, o.rules,
                                          RoundText(round, start));
  Say(o, "  => " + round.verdict);
  return round;
}

std::vector<ParamTrend> PerCaseTrends(const DiagnosisModel& m, const FitResult& base,
                                      const DiagnoseOptions& o, int64_t* evals) {
  const ParameterLayout layout({});
  const int n = layout.size();
  const size_t nc = m.cases().size();
  std::vector<std::vector<double>> per(nc);
  std::vector<int64_t> case_evals(nc, 0);
  ParallelFor(static_cast<int>(nc), o.threads, [&](int c) {
    ResidualFunction f = [&, c](std::span<const double> u, std::vector<double>& r) {
      const std::vector<double> x = layout.FromUnit(u);
      thread_local std::vector<double> y;
      const model::SimulationSummary s = m.Simulate(layout, x, c, y);
      if (!s.ok()) return false;
      const auto& meas = m.cases()[c].measured_deg;
      r.resize(meas.size());
      for (size_t k = 0; k < meas.size(); ++k) r[k] = meas[k] - y[k];
      return true;
    };
    LmOptions lo = o.lm;
    lo.threads = 1;
    lo.max_iterations = 25;
    std::vector<double> lb(n, 0.0), ub(n, 1.0);
    const LmResult r = LevenbergMarquardt(f, layout.ToUnit(base.x), lb, ub, lo);
    per[c] = layout.FromUnit(r.x);
    case_evals[static_cast<size_t>(c)] = r.evaluations;
  });
  for (int64_t e : case_evals) *evals += e;
  std::vector<ParamTrend> trends;
  std::vector<double> v, fr;
  for (const DiagCase& c : m.cases()) {
    v.push_back(c.drive.amplitude_v);
    fr.push_back(c.drive.frequency_hz);
  }
  for (int i = 0; i < n; ++i) {
    std::vector<double> per_case;
    for (size_t c = 0; c < nc; ++c) per_case.push_back(per[c][i]);
    trends.push_back(
        TrendOver(layout.specs()[i].name, layout.specs()[i].unit, std::move(per_case), v, fr));
  }
  return trends;
}

}  // namespace

Status DiagnoseOptions::Validate() const {
  if (threads < 1) return InvalidArgument(FieldError("threads", threads, "must be >= 1"));
  if (concurrent_fits < 1)
    return InvalidArgument(FieldError("concurrent_fits", concurrent_fits, "must be >= 1"));
  if (auto s = de_base.Validate(); !s.ok()) return InvalidArgument("de_base." + s.message());
  if (auto s = de_candidate.Validate(); !s.ok())
    return InvalidArgument("de_candidate." + s.message());
  if (auto s = lm.Validate(); !s.ok()) return InvalidArgument("lm." + s.message());
  if (cvode_lm_iterations < 1)
    return InvalidArgument(FieldError("cvode_lm_iterations", cvode_lm_iterations, "must be >= 1"));
  if (cvode_start_fractions.empty())
    return InvalidArgument("cvode_start_fractions: needs at least one entry");
  for (double f : cvode_start_fractions)
    if (!(f > 0 && f <= 1))
      return InvalidArgument(FieldError("cvode_start_fractions[]", f, "must be in (0, 1]"));
  if (auto s = sim.Validate(); !s.ok()) return InvalidArgument("sim." + s.message());
  if (auto s = rules.Validate(); !s.ok()) return InvalidArgument("rules." + s.message());
  for (EffectKind k : candidates)
    if (!model::IsFinEffect(k))
      return InvalidArgument(
          FieldError("candidates[]", std::string(k.name()), "not an effect of the fin bench"));
  return Status::Ok();
}

model::ResidualAnalysis AnalyseFit(const DiagnosisModel& m, const FitResult& fit,
                                   std::span<const double> floors) {
  const ParameterLayout layout(fit.structure);
  std::vector<std::vector<double>> ys(m.cases().size());
  std::vector<model::ResidualCaseInput> in;
  for (size_t c = 0; c < m.cases().size(); ++c) {
    const DiagCase& dc = m.cases()[c];
    const model::SimulationSummary s = m.Simulate(layout, fit.x, c, ys[c]);
    if (!s.ok()) ys[c].assign(dc.measured_deg.size(), 0.0);
    model::ResidualCaseInput r;
    r.number = dc.number;
    r.amplitude_v = dc.drive.amplitude_v;
    r.frequency_hz = dc.drive.frequency_hz;
    r.sample_rate_hz = dc.drive.sample_rate_hz;
    r.cycles = std::max(1, static_cast<int>(std::lround(dc.drive.cycles)));
    r.training = dc.training;
    r.measured = dc.measured_deg;
    r.model = ys[c];
    r.floor_rms_deg = floors[c];
    r.quantum_deg = dc.noise.quantum_deg;
    in.push_back(r);
  }
  return model::AnalyseResiduals(in);
}

namespace {

/// The floors' RMS over the training and the withheld samples, and the withheld floor's sum of
/// squares.
void SetFloorTotals(const DiagnosisModel& m, const std::vector<double>& floors, Diagnosis& d) {
  double st = 0, sw = 0;
  for (size_t c = 0; c < m.cases().size(); ++c) {
    const double v = floors[c] * floors[c] * m.cases()[c].measured_deg.size();
    (m.cases()[c].training ? st : sw) += v;
  }
  d.floor_train = std::sqrt(st / std::max(1, m.training_samples()));
  d.floor_withheld = std::sqrt(sw / std::max(1, m.withheld_samples()));
  d.withheld_floor = sw;
}

/// How far the final fit closed each case's gap over its floor.
void MeasureCaseGaps(const DiagnosisModel& m, const std::vector<double>& floors, Diagnosis& d) {
  for (size_t c = 0; c < m.cases().size(); ++c) {
    const DiagCase& dc = m.cases()[c];
    CaseGap g;
    g.number = dc.number;
    g.training = dc.training;
    g.amplitude_v = dc.drive.amplitude_v;
    g.frequency_hz = dc.drive.frequency_hz;
    g.floor_rms = floors[c];
    const double n = dc.measured_deg.size();
    g.pi_before = d.base.case_pi[c];
    g.pi_after = d.final_fit.case_pi[c];
    g.rms_before = std::sqrt(g.pi_before / n);
    g.rms_after = std::sqrt(g.pi_after / n);
    const double floor_c = n * floors[c] * floors[c];
    g.closed = g.pi_before > floor_c
                   ? std::clamp(records::ClosedShare(g.pi_before, g.pi_after, floor_c), -9.0, 1.0)
                   : 0.0;
    d.gaps.push_back(g);
  }
}

}  // namespace

Diagnosis RunDiagnosis(const DiagnosisModel& m, const DiagnoseOptions& o) {
  ThrowIfError(o.Validate());
  const auto start = std::chrono::steady_clock::now();
  Diagnosis d;
  d.cases = m.cases();
  for (const DiagCase& c : m.cases()) d.quantum_deg = std::max(d.quantum_deg, c.noise.quantum_deg);
  std::vector<EffectKind> kinds = o.candidates;
  if (kinds.empty())
    for (const auto& e : model::EffectLibrary()) kinds.push_back(e.kind);

  // 1. Base fit.
  Say(o, "base model: global fit on the training cases");
  const ParameterLayout base_layout({});
  d.base = FitStructure(m, base_layout, nullptr, nullptr, EffectKind(), o);
  d.evaluations += d.base.evaluations;
  if (!d.base.ok) throw InputError("the base model could not be fitted: " + d.base.message);
  // 2. Round-1 fits: every candidate on top of the base model.
  Say(o, "candidates: each effect added to the base model");
  std::vector<CandidateResult> first_fits =
      FitCandidates(m, d.base, base_layout, kinds, o, &d.evaluations);
  // 3. Floors where the best-fitting model (lowest training PI) sits on its saturations.
  const FitResult* floor_model = &d.base;
  for (const CandidateResult& c : first_fits)
    if (c.fit.ok && c.fit.train_pi < floor_model->train_pi) floor_model = &c.fit;
  const std::vector<double> floors = CaseFloors(m, *floor_model);
  d.floor_model = floor_model->description;
  SetFloorTotals(m, floors, d);
  d.base_residuals = AnalyseFit(m, d.base, floors);
  Say(o,
      Fmt("base model: train RMS %.4f, withheld RMS %.4f deg; floor %.4f / %.4f deg",
          std::sqrt(d.base.train_pi / m.training_samples()),
          std::sqrt(d.base.withheld_pi / m.withheld_samples()), d.floor_train, d.floor_withheld) +
          " (saturations of " + d.floor_model + ")");
  // 4. Trends of per-case fits.
  if (o.trends) {
    Say(o, "per-case fits (trends over the V x f grid)");
    d.trends = PerCaseTrends(m, d.base, o, &d.evaluations);
  }
  // 5. Rounds: score the first; greedily fit and score a second while the gap left is significant.
  FitResult current = d.base;
  model::ResidualAnalysis current_analysis = d.base_residuals;
  for (int r = 0; r < (o.second_effect ? 2 : 1); ++r) {
    std::vector<CandidateResult> fits;
    if (r == 0) {
      fits = std::move(first_fits);
    } else {
      const double ratio = std::sqrt(current.withheld_pi / std::max(d.withheld_floor, 1e-300));
      if (ratio > o.rules.significance_ratio) {
        Say(o, "second effect: the others on top of the first");
        fits =
            FitCandidates(m, current, ParameterLayout(current.structure), kinds, o, &d.evaluations);
      }
    }
    RoundResult round = ScoreRound(m, current, current_analysis, floors, std::move(fits), o);
    const bool named = round.named >= 0;
    if (named) {
      const CandidateResult& c = round.candidates[round.named];
      d.named.push_back(c.kind);
      if (r == 0) d.confidence = c.confidence;
      current = c.fit;
      current_analysis = AnalyseFit(m, current, floors);
    }
    d.rounds.push_back(std::move(round));
    if (!named) break;
  }
  d.final_fit = current;
  d.final_residuals = current_analysis;

  // 6. How far: per case and in total.
  d.withheld_before = d.base.withheld_pi;
  d.withheld_after = d.final_fit.withheld_pi;
  d.closed_total = records::ClosedShare(d.withheld_before, d.withheld_after, d.withheld_floor);
  d.remaining_ratio = std::sqrt(d.withheld_after / d.withheld_floor);
  MeasureCaseGaps(m, floors, d);
  // What the base terms absorb: the best candidate of the first round against the base fit.
  const RoundResult& first = d.rounds.front();
  if (!first.candidates.empty() && first.candidates[0].fit.ok) {
    const CandidateResult& best = first.candidates[0];
    d.absorbed = Compare(d.base, best.fit);
    d.absorbed_by = model::EffectName(best.kind);
  }
  // Verdict: the first round's, with what the base terms absorb and the second effect.
  d.verdict_kind =
      records::VerdictKind(first.significant, {.named = first.named, .runner_up = first.runner_up});
  records::VerdictText text = RoundText(first, d.base);
  for (const Absorption& a : d.absorbed)
    text.absorbed.push_back(a.name + Fmt(" (%.3g without it, %.3g with it)", a.without, a.with));
  if (d.named.size() > 1) {
    text.second = model::EffectName(d.named[1]);
    text.second_confidence =
        d.rounds[1].candidates[static_cast<size_t>(d.rounds[1].named)].confidence;
    text.s_final = d.withheld_after;
  }
  d.verdict = records::ComposeVerdict(first.gap, VerdictCandidates(first.candidates),
                                      {.named = first.named,
                                       .runner_up = first.runner_up,
                                       .z_runner_up = first.z_runner_up,
                                       .confidence = d.confidence},
                                      o.rules, text);
  d.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  Say(o, d.verdict);
  return d;
}

records::RecordDiagnoseOptions RecordOptionsOf(const DiagnoseOptions& o) {
  records::RecordDiagnoseOptions r = records::FinBenchOptions();
  if (!o.candidates.empty()) r.candidates = o.candidates;
  r.fit.threads = o.threads;
  r.fit.search.de = o.de_base;
  r.fit.search.de.seed = o.seed;
  r.bench_fits.de = o.de_candidate;
  r.bench_fits.seed = o.seed;
  r.fit.lm = o.lm;
  r.fit.lm.threads = o.threads;
  r.fit.beam.lm_iterations = o.cvode_lm_iterations;
  r.fit.beam.start_fractions = o.cvode_start_fractions;
  r.fit.family_options.fin_sim = o.sim;
  r.rules = o.rules;
  r.second_effect = o.second_effect;
  r.trends = o.trends;
  r.fit.progress = o.progress;
  if (o.records_service) r.fit.evaluator_factory = o.records_service(r.fit.family_options);
  return r;
}

io::RecordSet RecordsOfCases(const std::vector<DiagCase>& cases) {
  io::CaseSet set;
  set.dir = "bench";
  for (const DiagCase& c : cases) {
    io::BenchCase b;
    b.number = c.number;
    b.amplitude_v = c.drive.amplitude_v;
    b.frequency_hz = c.drive.frequency_hz;
    b.role = c.training ? io::CaseRole::kTrain : io::CaseRole::kValidate;
    b.file = "case" + std::to_string(c.number);
    b.sample_rate_hz = c.drive.sample_rate_hz;
    b.cycles = c.drive.cycles;
    b.angle_deg = c.measured_deg;
    for (size_t k = 0; k < c.measured_deg.size(); ++k) {
      b.t.push_back(static_cast<double>(k) / c.drive.sample_rate_hz);
      b.u.push_back(c.drive.Value(b.t.back()));
    }
    set.cases.push_back(std::move(b));
  }
  return io::RecordsFromCaseSet(set);
}

int64_t BenchEvaluations(const records::RecordDiagnosis& d) {
  auto fit = [](const records::FitResult& f) { return f.evaluations + f.uncertainty.evaluations; };
  int64_t n = fit(d.base) + d.trend_evaluations;
  for (const records::RecordCandidate& c : d.candidates) n += fit(c.fit);
  if (d.second)
    for (const records::RecordCandidate& c : d.second->candidates) n += fit(c.fit);
  return n;
}

BenchDiagnosis DiagnoseBench(const DiagnosisModel& m, const DiagnoseOptions& o) {
  ThrowIfError(o.Validate());
  if (o.evaluator_factory && !o.records_service)
    throw InputError(
        "DiagnoseBench: evaluator_factory is the fin engine's (RunDiagnosis); the "
        "records engine's fits on the service take records_service");
  const auto start = std::chrono::steady_clock::now();
  BenchDiagnosis d;
  d.set = RecordsOfCases(m.cases());
  d.records = records::DiagnoseRecords(d.set, RecordOptionsOf(o));
  // The grid's facts: each case's place, noise and saturations, and the floors pooled by role.
  double st = 0, sw = 0;
  for (size_t c = 0; c < m.cases().size(); ++c) {
    const DiagCase& dc = m.cases()[c];
    d.cases.push_back({dc.number, dc.training, dc.drive.amplitude_v, dc.drive.frequency_hz,
                       dc.noise, dc.b1, dc.b2});
    d.quantum_deg = std::max(d.quantum_deg, dc.noise.quantum_deg);
    const double f = d.records.record_floor[c];
    (dc.training ? st : sw) += f * f * dc.measured_deg.size();
  }
  d.floor_train = std::sqrt(st / std::max(1, m.training_samples()));
  d.floor_withheld = std::sqrt(sw / std::max(1, m.withheld_samples()));
  d.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return d;
}

}  // namespace pz::diagnose
