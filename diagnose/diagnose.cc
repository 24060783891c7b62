#include "diagnose/diagnose.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "io/csv.h"
#include "model/format.h"
#include "model/model_comparison.h"
#include "records/fin_effects.h"
#include "records/resonance.h"

namespace pz::diagnose {
namespace {

using model::CaseRole;

bool Withheld(const io::Record& r) { return r.role != CaseRole::kTrain; }

std::string Fmt(double x, int prec = 3) { return FormatG(x, prec); }

/// Σe² of record i over its scored window.
double RecordSse(const io::Record& r, const std::vector<double>& yhat) {
  double s = 0;
  for (size_t k = r.first_scored; k < r.end_scored; ++k) {
    const double e = r.y[k] - yhat[k];
    s += e * e;
  }
  return s;
}

/// Σe² over the withheld (or training) scored samples of a fit: each record's sum, added in set
/// order (a bench's Σ PI over its cases, added case by case).
double Sse(const io::RecordSet& set, const records::FitResult& f, bool withheld) {
  double s = 0;
  for (size_t i = 0; i < set.records.size(); ++i)
    if (Withheld(set.records[i]) == withheld) s += RecordSse(set.records[i], f.yhat[i]);
  return s;
}

/// Per-sample squared errors over the withheld samples, in set order.
std::vector<double> WithheldSquares(const io::RecordSet& set, const records::FitResult& f) {
  std::vector<double> out;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& r = set.records[i];
    if (!Withheld(r)) continue;
    for (size_t k = r.first_scored; k < r.end_scored; ++k) {
      const double e = r.y[k] - f.yhat[i][k];
      out.push_back(e * e);
    }
  }
  return out;
}

/// Localised excess over drive-level × direction bins of the withheld samples, against the pooled
/// σ² (`floors` empty) or each record's σ_c².
std::vector<double> BinExcess(const io::RecordSet& set, const records::FitResult& f, double sigma2,
                              const std::vector<double>& floors, const records::DataScale& s) {
  constexpr int kLevels = 10;
  std::vector<double> sse(2 * kLevels, 0.0), n(2 * kLevels, 0.0), fv(2 * kLevels, 0.0);
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& r = set.records[i];
    if (!Withheld(r)) continue;
    const double v = floors.empty() ? sigma2 : floors[i] * floors[i];
    for (size_t k = std::max<size_t>(r.first_scored, 1); k < r.end_scored; ++k) {
      const double x = (r.u[k] - s.u_min) / (2 * s.u_half);
      const int level = std::clamp(static_cast<int>(x * kLevels), 0, kLevels - 1);
      const int dir = r.u[k] >= r.u[k - 1] ? 0 : 1;
      const double e = r.y[k] - f.yhat[i][k];
      const auto b = static_cast<size_t>(dir * kLevels + level);
      sse[b] += e * e;
      n[b] += 1;
      fv[b] += v;
    }
  }
  std::vector<double> ex(sse.size());
  for (size_t b = 0; b < sse.size(); ++b)
    ex[b] = std::max(0.0, sse[b] - (floors.empty() ? n[b] * sigma2 : fv[b]));
  return ex;
}

/// Whole drive cycles in a record's scored window at its stated frequency (1 without one).
int ScoredCycles(const io::Record& r) {
  if (r.sinusoid.stated() && r.first_scored == 0 && r.end_scored == r.size())
    return std::max(1, static_cast<int>(std::lround(r.sinusoid.cycles)));
  if (!(r.frequency_hz > 0)) return 1;
  return std::max(
      1, static_cast<int>(std::lround(static_cast<double>(r.scored()) * r.dt * r.frequency_hz)));
}

}  // namespace

std::vector<double> PredictOnShape(const records::FitResult& fit, const synth::DriveShape& shape,
                                   io::Record* out) {
  io::Record r = synth::RecordOfDrive(shape);
  const size_t n = r.u.size();
  r.first_scored =
      std::min(n - 1, r.rest_samples + static_cast<size_t>(shape.fs_hz / shape.frequency_hz));
  r.end_scored = n;
  std::vector<double> y(n);
  fit.model->Simulate(r, fit.params, fit.weights, n, y);
  for (double& v : y) v *= fit.model->scale().polarity;
  if (out) *out = std::move(r);
  return y;
}

ProposedExperiment ProposeExperiment(const io::RecordSet& set, const records::FitResult& a,
                                     const records::FitResult& b, double sigma) {
  const records::DataScale& s = a.model->scale();
  const double fs = s.fs;
  ProposedExperiment best;
  best.ratio_to_noise = -1;
  for (synth::Waveform w :
       {synth::Waveform::kSine, synth::Waveform::kTriangle, synth::Waveform::kSquare}) {
    for (double fm : {0.25, 0.5, 1.0, 2.0, 4.0, 8.0}) {
      const double f = s.f_dom * fm;
      if (f > fs / 20) continue;
      for (double am : {0.5, 1.0}) {
        synth::DriveShape d;
        d.waveform = w;
        d.amplitude = s.u_half * am;
        d.bias = (s.u_min + s.u_max) / 2;
        d.frequency_hz = f;
        d.phase_rad = 0;
        d.rest_s = 0.1;
        d.duration_s = std::max(4 / f, std::min(1.0, 20 / f));
        d.fs_hz = fs;
        io::Record r;
        const auto ya = PredictOnShape(a, d, &r);
        const auto yb = PredictOnShape(b, d);
        double mean = 0;
        for (size_t k = r.first_scored; k < r.end_scored; ++k) mean += ya[k] - yb[k];
        mean /= static_cast<double>(r.scored());
        double ss = 0;
        for (size_t k = r.first_scored; k < r.end_scored; ++k)
          ss += (ya[k] - yb[k] - mean) * (ya[k] - yb[k] - mean);
        const double rms = std::sqrt(ss / static_cast<double>(r.scored()));
        if (std::isfinite(rms) && rms / sigma > best.ratio_to_noise) {
          best.shape = d;
          best.rms_difference = rms;
          best.ratio_to_noise = rms / sigma;
        }
      }
    }
  }
  const synth::DriveShape& d = best.shape;
  best.description = std::string("a ") + WaveformName(d.waveform) + " of ±" + Fmt(d.amplitude, 4) +
                     " " + set.drive_unit + " around " + Fmt(d.bias, 4) + " " + set.drive_unit +
                     " at " + Fmt(d.frequency_hz, 4) + " Hz for " + Fmt(d.duration_s, 3) +
                     " s (sampled at " + Fmt(d.fs_hz, 5) + " Hz), where " + a.model->Describe() +
                     " and " + b.model->Describe() + " differ by " + Fmt(best.rms_difference, 3) +
                     " " + set.response_unit + " RMS = " + Fmt(best.ratio_to_noise, 3) +
                     " × the noise floor";
  return best;
}

namespace {

/// The noise floor from the base fit's residuals; refuses a base fit whose prediction is not
/// finite on a withheld record.
records::NoiseFloor BaseNoiseFloor(const io::RecordSet& set, const records::FitResult& base) {
  std::vector<std::vector<double>> base_res;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& r = set.records[i];
    std::vector<double> e;
    for (size_t k = r.first_scored; k < r.end_scored; ++k) e.push_back(r.y[k] - base.yhat[i][k]);
    base_res.push_back(std::move(e));
  }
  if (const double s = Sse(set, base, true); !std::isfinite(s)) {
    std::string names;
    for (size_t i = 0; i < set.records.size(); ++i)
      if (Withheld(set.records[i]) && !std::isfinite(base.metrics[i].rmse))
        names += (names.empty() ? "" : ", ") + set.records[i].name;
    throw InputError(
        base.model->Describe() + ": the fitted model's prediction is not finite on the withheld " +
        "record(s) " + names + " (it diverges there): no gap to diagnose; train on records that " +
        "cover their drive, or try more integration sub-steps or another family");
  }
  return records::EstimateNoiseFloor(set, &base_res);
}

/// True when a record's residual under the fit has a mode-like band above f_min (records/
/// resonance.h: dominant and narrow): where a mode shows.
bool ResidualHasBand(const io::RecordSet& set, const records::FitResult& fit, double f_min) {
  for (size_t i = 0; i < set.records.size() && i < fit.yhat.size(); ++i)
    if (records::ResidualBand(set.records[i], fit.yhat[i], f_min).mode_like()) return true;
  return false;
}

/// The candidates that apply to the family: those asked for, or by default the effects the family
/// does not hold and the records can support (creep-spectrum needs a window of a decade above its
/// fastest relaxation); asked for by name, such an effect is an error (its model throws); so does
/// rate dependence on training records at one rate (records/excitation.h, the rate span). The
/// resonance is offered by default where a record's residual under the base model has a mode-like
/// band in its range of f_n, above a periodic drive's first harmonics (a mode there; elsewhere its
/// fit would only bend the loop, as a lag the family lacks).
std::vector<model::EffectKind> CandidateEffects(const io::RecordSet& set, const RecordDiagnosis& d,
                                                const RecordDiagnoseOptions& o) {
  std::vector<model::EffectKind> cands = o.candidates;
  if (!cands.empty()) return cands;
  const auto lib = records::EffectLibrary(d.base.model->scale());
  const records::Family& family = d.base.model->family();
  const bool rates = d.excitation.training.rate_span() >= records::kMinRateSpan;
  const model::EffectKind resonance = model::EffectKind::Named("resonance");
  for (const records::EffectInfo& e : lib)
    if (!family.Excludes(e.name) && e.unsupported.empty() &&
        (rates || !records::NeedsRateCoverage(e.kind)) &&
        (e.kind != resonance || ResidualHasBand(set, d.base, e.params[1].lower)))
      cands.push_back(e.kind);
  return cands;
}

/// Extra starts of a candidate's fit: the base fit with the effect at small magnitudes (unit
/// coordinates).
void AddExtraStarts(const records::RecordModel& model, const std::vector<double>& base_params,
                    model::EffectKind e, const records::DataScale& scale, records::FitOptions& ce) {
  const auto& params = model.params();
  opt::ParamBox box;
  for (const records::ParamInfo& p : params) {
    box.names.push_back(p.name);
    box.lower.push_back(p.lower);
    box.upper.push_back(p.upper);
    box.log_scale.push_back(p.log_scale);
  }
  for (double frac : {0.02, 0.1, 0.3}) {
    std::vector<double> phys = base_params;
    for (const records::ParamInfo& p : e->Params(scale)) {
      const double mid = p.lower <= 0 && p.upper >= 0 ? frac * (p.upper > 0 ? p.upper : p.lower)
                                                      : p.lower * std::pow(p.upper / p.lower, frac);
      phys.push_back(mid);
    }
    std::vector<double> unit(box.size());
    box.ToUnit(phys.data(), unit.data());
    ce.extra_starts.push_back(unit);
  }
}

/// The effect names of a round's ranked candidates, as the verdict names them.
std::vector<VerdictCandidate> Named(const std::vector<RecordCandidate>& ranked) {
  std::vector<VerdictCandidate> out;
  for (const RecordCandidate& c : ranked) out.push_back({EffectName(c.kind), &c});
  return out;
}

/// Where the verdict's floor comes from and its σ (per record: √(S_floor / N_w)).
void SetFloorText(const RecordDiagnoseOptions& o, const RecordDiagnosis& d, VerdictText& text) {
  const bool per_record = o.floor == RecordFloor::kPerRecord;
  text.floor_source = !o.floor_source.empty() ? o.floor_source
                      : per_record ? "rounding, scatter and saturation plateaus per record"
                                   : d.noise.used;
  text.floor = per_record ? -1 : d.noise.sigma;
}

/// The named effect, the proposed experiment, the excitation note and the verdict's text.
void ComposeRecordVerdict(const io::RecordSet& set, const RecordDiagnoseOptions& o, const Gap& gap,
                          const Naming& naming, RecordDiagnosis& d) {
  d.named = naming.named;
  d.runner_up = naming.runner_up;
  d.z_runner_up = naming.z_runner_up;
  d.confidence = naming.confidence;
  d.verdict_kind = VerdictKind(d.significant, naming);
  VerdictText text;
  text.model = o.model_label.empty() ? o.family : o.model_label;
  text.unit = set.response_unit;
  SetFloorText(o, d, text);
  if (d.runner_up >= 0 && o.next_hint) {
    text.next = o.next_hint(d.candidates[static_cast<size_t>(d.named)].kind,
                            d.candidates[static_cast<size_t>(d.runner_up)].kind);
  } else if (d.runner_up >= 0 && o.propose) {
    d.next = ProposeExperiment(set, d.candidates[static_cast<size_t>(d.named)].fit,
                               d.candidates[static_cast<size_t>(d.runner_up)].fit, d.noise.sigma);
    text.next = d.next->description;
  }
  d.round_verdict = ComposeVerdict(gap, Named(d.candidates), naming, o.rules, text);
  std::vector<double> ratios;
  for (size_t i = 0; i < d.base.metrics.size(); ++i)
    ratios.push_back(d.base.metrics[i].rmse / d.record_floor[i]);
  if (d.significant && d.noise.sigma > 0 && o.excitation_note)
    d.excitation_note = ExcitationGapNote(set, d.excitation, ratios, o.rules.significance_ratio);
  text.closing = d.excitation_note;
  if (o.absorbed_in_verdict) {
    for (const Absorption& a : d.absorbed)
      text.absorbed.push_back(a.name + " (" + Fmt(a.without) + " without it, " + Fmt(a.with) +
                              " with it)");
  }
  if (d.second && d.second->named >= 0) {
    text.second = EffectName(d.named_effects[1]);
    text.second_confidence = d.second->confidence;
    text.s_final = d.withheld_after;
  }
  d.verdict = ComposeVerdict(gap, Named(d.candidates), naming, o.rules, text);
  if (!d.diverged.empty()) {
    std::string names;
    for (const auto& n : d.diverged) names += (names.empty() ? "" : ", ") + n;
    d.verdict += " Left out: " + names +
                 " (the fitted model's prediction is not finite on the withheld records: it " +
                 "diverges there).";
  }
}

/// Per-record floors (RecordDiagnoseOptions::floor kPerRecord): each record's rounding and scatter
/// over its scored window, saturation-aware where `fit` sits on the record's measured extremes.
std::vector<double> PerRecordFloors(const io::RecordSet& set, const records::FitResult& fit) {
  std::vector<double> floors;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& r = set.records[i];
    const auto y = std::span<const double>(r.y).subspan(r.first_scored, r.scored());
    const records::CaseNoise noise = records::EstimateCaseNoise(y, ScoredCycles(r), r.quantum);
    const auto yh = std::span<const double>(fit.yhat[i]).subspan(r.first_scored, r.scored());
    bool finite = true;
    for (double v : yh) finite = finite && std::isfinite(v);
    const auto [lo, hi] = std::minmax_element(r.y.begin(), r.y.end());
    floors.push_back(finite ? SaturationAwareFloor(noise, y, yh, *hi, *lo) : noise.floor_rms_deg);
  }
  return floors;
}

/// The residual analysis of a fit over every record's scored window (RecordPattern::
/// kResidualAnalysis); InputError naming a record that states no frequency.
model::ResidualAnalysis AnalyseRecordResiduals(const io::RecordSet& set,
                                               const records::FitResult& fit,
                                               const std::vector<double>& floors) {
  std::vector<model::ResidualCaseInput> in;
  std::vector<std::vector<double>> zeros(set.records.size());
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& r = set.records[i];
    if (!(r.frequency_hz > 0)) {
      throw InputError(r.Label() + ": states no frequency (frequency_Hz), which the residual " +
                       "analysis's phase bins and harmonics need");
    }
    model::ResidualCaseInput c;
    c.number = r.sinusoid.stated() ? r.sinusoid.case_number : static_cast<int>(i) + 1;
    c.amplitude_v = std::max(pz::diagnose::DriveAmplitude(r), 1e-300);
    c.frequency_hz = r.frequency_hz;
    c.sample_rate_hz = r.sinusoid.stated() ? r.sinusoid.sample_rate_hz : r.sample_rate_hz();
    c.cycles = ScoredCycles(r);
    c.training = !Withheld(r);
    c.measured = std::span<const double>(r.y).subspan(r.first_scored, r.scored());
    c.model = std::span<const double>(fit.yhat[i]).subspan(r.first_scored, r.scored());
    bool finite = true;
    for (double v : c.model) finite = finite && std::isfinite(v);
    if (!finite) {  // a diverging model: analysed as zero output (every sample's error counts)
      zeros[i].assign(r.scored(), 0.0);
      c.model = zeros[i];
    }
    c.floor_rms_deg = floors[i];
    c.quantum_deg = r.quantum;
    in.push_back(c);
  }
  return model::AnalyseResiduals(in);
}

/// What the options need of the data shape: the floors, the localised excess, the squared errors.
struct Shape {
  const io::RecordSet& set;
  const RecordDiagnoseOptions& o;
  const records::DataScale& scale;
  double sigma2 = 0;
  std::vector<double> floors;  ///< empty: the pooled σ

  std::vector<double> Excess(const records::FitResult& f,
                             model::ResidualAnalysis* keep = nullptr) const {
    if (o.pattern == RecordPattern::kDriveBins) return BinExcess(set, f, sigma2, floors, scale);
    model::ResidualAnalysis ra =
        AnalyseRecordResiduals(set, f, floors.empty() ? PooledFloors() : floors);
    std::vector<double> ex = ResidualFeatureExcess(ra.withheld);
    if (keep) *keep = std::move(ra);
    return ex;
  }
  std::vector<double> PooledFloors() const {
    return std::vector<double>(set.records.size(), std::sqrt(sigma2));
  }
};

/// The output of `model` at `params` on every record, as a fit (no search, no polish), with the
/// uncertainty table there for a model searched through its RecordMap (the bench form): the nested
/// model of a bench fit (RecordDiagnoseOptions::BenchFits). `evaluations`: of the fit it replaces.
records::FitResult FitAt(const io::RecordSet& set, std::shared_ptr<records::RecordModel> model,
                         std::vector<double> params, int64_t evaluations,
                         const records::FitOptions& fo) {
  records::FitResult f;
  f.model = std::move(model);
  f.params = std::move(params);
  std::vector<const io::Record*> train;
  for (const io::Record& r : set.records) {
    std::vector<double> y;
    f.metrics.push_back(Evaluate(*f.model, f.params, {}, r, &y));
    f.yhat.push_back(std::move(y));
    if (Withheld(r)) continue;
    f.train_sse += f.metrics.back().sse;
    train.push_back(&r);
  }
  size_t n = 0;
  for (const io::Record* r : train) n += r->scored();
  f.train_mse = f.train_sse / static_cast<double>(std::max<size_t>(n, 1));
  if (fo.uncertainty && f.model->has_ratio()) {
    const records::RecordFitness fitness(*f.model, train);
    const records::RecordMap map(*f.model);
    f.uncertainty = opt::ComputeUncertainty(
        map,
        [&](std::span<const double> x, std::vector<double>& r) { return fitness.Residuals(x, r); },
        f.params, fo.threads, fo.lm.fd_step, fitness.ResidualWeight());
  }
  f.evaluations = evaluations;
  return f;
}

/// A candidate fit as the bench's (RecordDiagnoseOptions::BenchFits).
records::FitResult BenchFitOnTop(const io::RecordSet& set, const records::FitResult& start,
                                 std::shared_ptr<records::RecordModel> model, model::EffectKind e,
                                 const RecordDiagnoseOptions& o, const records::FitOptions& fo) {
  std::vector<double> x0 = start.params;
  const records::Effect zero = records::Effect::Zero(e);
  for (double v : zero.params) x0.push_back(v);
  if (x0.size() != model->params().size()) {
    throw InputError(model->Describe() + ": " + std::to_string(model->params().size()) +
                     " parameters, the bench's fit extends " + std::to_string(start.params.size()) +
                     " by " + std::to_string(zero.params.size()));
  }
  records::FitOptions ce = fo;
  ce.extra_starts.clear();
  ce.seed_points.clear();
  ce.start_points.clear();
  bool beam = false;
  for (model::EffectKind k : model->effects())
    beam = beam || records::GetFinEffectInfo(k).stage == model::EffectStage::kBeam;
  if (beam) {
    ce.polish_from = x0;  // refined at the start fractions (FitOptions::beam)
  } else {
    std::vector<std::vector<double>> starts;
    if (const int mp = records::GetFinEffectInfo(e).magnitude_param; mp >= 0) {
      const size_t mag = start.params.size() + static_cast<size_t>(mp);
      const records::ParamInfo& s = model->params()[mag];
      const bool both_signs = s.lower < 0 && s.upper > 0;
      const std::vector<double>& fr = fo.beam.start_fractions;
      for (size_t j = 0; j < fr.size(); ++j) {
        const double f = both_signs ? fr[0] : fr[j];
        std::vector<double> x = x0;
        x[mag] = both_signs && j % 2 == 1 ? f * s.lower : f * s.upper;
        starts.push_back(std::move(x));
      }
    }
    ce.polish_from.clear();
    ce.search.algorithm = opt::SearchAlgorithm::kDe;
    ce.search.repetitions = 1;
    ce.search.de = o.bench_fits.de;
    ce.search.de.seed = o.bench_fits.seed +
                        1000 * (static_cast<uint64_t>(records::FinIndex(e)) + 1) +
                        17 * model->effects().size();
    ce.seed_points = {x0};
    ce.seed_points.insert(ce.seed_points.end(), starts.begin(), starts.end());
    ce.start_points = {x0};
  }
  records::FitResult f = FitModel(set, model, ce);
  if (f.train_sse > start.train_sse) {
    records::FitResult nested =
        FitAt(set, model, x0, f.evaluations + f.uncertainty.evaluations, ce);
    nested.polish_message =
        "refinement ended above the starting model (" + f.polish_message + "): effect kept at zero";
    return nested;
  }
  return f;
}

/// Fits `start`'s model plus effect e (extra starts: `start` with e at small magnitudes; or as the
/// bench's, RecordDiagnoseOptions::BenchFits).
records::FitResult FitOnTop(const io::RecordSet& set, const records::FitResult& start,
                            model::EffectKind e, const records::DataScale& scale,
                            const RecordDiagnoseOptions& o, const records::FitOptions& fo) {
  std::vector<model::EffectKind> effects = start.model->effects();
  effects.push_back(e);
  auto model = std::make_shared<records::RecordModel>(start.model->family_ptr(), effects, scale);
  if (o.bench_fits.enabled) return BenchFitOnTop(set, start, model, e, o, fo);
  records::FitOptions ce = fo;
  AddExtraStarts(*model, start.params, e, scale, ce);
  return FitModel(set, model, ce);
}

/// Scores the fitted candidates of a round against the gap of `start`, ranks them and names one.
Naming ScoreAndName(const Shape& shape, const Gap& gap, const records::FitResult& start,
                    std::vector<RecordCandidate>& cands) {
  const io::RecordSet& set = shape.set;
  const auto start_ex = shape.Excess(start);
  const auto start_sq = WithheldSquares(set, start);
  for (RecordCandidate& c : cands) {
    const int k = static_cast<int>(c.fit.model->params().size() - start.model->params().size());
    ScoreCandidate(gap, Sse(set, c.fit, true), Sse(set, c.fit, false), k,
                   PatternExplained(start_ex, shape.Excess(c.fit)), shape.o.rules, c);
    c.z_vs_base = model::PairedBlockZ(start_sq, WithheldSquares(set, c.fit), shape.o.rules.blocks);
  }
  RankByScore(cands);
  const std::vector<CandidateScore*> ranked = Scores(cands);
  AssignWeights(gap, ranked);
  return NameEffect(
      gap, ranked,
      [&](int i) {
        return i < 0 ? start_sq : WithheldSquares(set, cands[static_cast<size_t>(i)].fit);
      },
      shape.o.rules);
}

/// Each record's gap before (the base) and after (the final model).
std::vector<RecordGap> RecordGaps(const io::RecordSet& set, const RecordDiagnosis& d) {
  std::vector<RecordGap> out;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& r = set.records[i];
    RecordGap g;
    g.name = r.name;
    g.role = r.role;
    g.amplitude = pz::diagnose::DriveAmplitude(r);
    g.frequency_hz = r.frequency_hz;
    g.floor_rms = d.record_floor[i];
    const double n = static_cast<double>(r.scored());
    g.pi_before = RecordSse(r, d.base.yhat[i]);
    g.pi_after = RecordSse(r, d.final_fit->yhat[i]);
    g.rms_before = std::sqrt(g.pi_before / n);
    g.rms_after = std::sqrt(g.pi_after / n);
    const double floor_c = n * g.floor_rms * g.floor_rms;
    g.closed = g.pi_before > floor_c
                   ? std::clamp(ClosedShare(g.pi_before, g.pi_after, floor_c), -9.0, 1.0)
                   : 0.0;
    out.push_back(g);
  }
  return out;
}

/// The greedy second round on top of the named candidate (RecordDiagnoseOptions::second_effect).
RecordRound SecondRound(const Shape& shape, const std::vector<model::EffectKind>& cands,
                        const RecordCandidate& first, const Gap& first_gap,
                        const records::FitOptions& fo, RecordDiagnosis& d) {
  const io::RecordSet& set = shape.set;
  const RecordDiagnoseOptions& o = shape.o;
  RecordRound round;
  round.start = first.fit.model->effects();
  round.gap = MeasureGap(first.s_withheld, first.s_train, first_gap.s_floor, first_gap.var_w,
                         first_gap.var_t, first_gap.nw, first_gap.nt, o.rules);
  if (round.gap.significant) {
    for (model::EffectKind e : cands) {
      if (e == first.kind) continue;
      if (o.fit.progress)
        o.fit.progress("second effect: " + ModelLabel(*first.fit.model, o) + " + " + EffectName(e));
      RecordCandidate c;
      c.kind = e;
      c.fit = FitOnTop(set, first.fit, e, shape.scale, o, fo);
      if (!std::isfinite(Sse(set, c.fit, true))) {
        d.diverged.push_back(ModelLabel(*first.fit.model, o) + " + " + EffectName(e));
        continue;
      }
      round.candidates.push_back(std::move(c));
    }
  }
  const Naming naming = ScoreAndName(shape, round.gap, first.fit, round.candidates);
  round.named = naming.named;
  round.runner_up = naming.runner_up;
  round.z_runner_up = naming.z_runner_up;
  round.confidence = naming.confidence;
  VerdictText text;
  text.model = ModelLabel(*first.fit.model, o);
  text.unit = set.response_unit;
  SetFloorText(o, d, text);
  if (round.runner_up >= 0 && o.next_hint) {
    text.next = o.next_hint(round.candidates[static_cast<size_t>(round.named)].kind,
                            round.candidates[static_cast<size_t>(round.runner_up)].kind);
  }
  round.verdict = ComposeVerdict(round.gap, Named(round.candidates), naming, o.rules, text);
  return round;
}

}  // namespace

std::vector<Absorption> AbsorbedParameters(std::span<const opt::ParamEstimate> without,
                                           std::span<const opt::ParamEstimate> with, size_t count) {
  std::vector<Absorption> r;
  for (size_t i = 0; i < count && i < without.size() && i < with.size(); ++i) {
    const opt::ParamEstimate& a = without[i];
    const opt::ParamEstimate& b = with[i];
    const double se = std::sqrt(a.std_error * a.std_error + b.std_error * b.std_error);
    const double z = se > 0 && std::isfinite(se) ? (a.value - b.value) / se : 0.0;
    const double rel =
        std::abs(a.value - b.value) / std::max({std::abs(a.value), std::abs(b.value), 1e-300});
    if (std::abs(z) > 2.0 && rel > 0.05) r.push_back({a.name, a.unit, a.value, b.value, z});
  }
  std::sort(r.begin(), r.end(),
            [](const Absorption& x, const Absorption& y) { return std::abs(x.z) > std::abs(y.z); });
  return r;
}

std::vector<double> ResidualFeatureExcess(const model::GroupResidual& g) {
  const double v = g.floor_rms * g.floor_rms;
  std::vector<double> ex;
  auto bin = [&](const model::BinStat& b) { ex.push_back(b.n * std::max(0.0, b.rms * b.rms - v)); };
  for (const auto& b : g.phase) bin(b);
  for (const auto* b :
       {&g.rising, &g.falling, &g.near_reversal, &g.in_saturation, &g.first_cycle, &g.later_cycles})
    bin(*b);
  const double hn = g.harmonic_noise * g.harmonic_noise;
  for (double a : {g.odd_rms, g.even_rms, g.low_rms})
    ex.push_back(0.5 * g.samples * std::max(0.0, a * a - hn));
  return ex;
}

RecordDiagnosis DiagnoseRecords(const io::RecordSet& set, const RecordDiagnoseOptions& o) {
  if (auto st = o.rules.Validate(); !st.ok()) throw InputError("rules." + st.message());
  RecordDiagnosis d;
  for (const io::Record& r : set.records)
    (Withheld(r) ? d.withheld_samples : d.train_samples) += r.scored();
  if (d.train_samples == 0)
    throw InputError(set.source.string() + ": no training record (role train)");
  if (d.withheld_samples == 0) {
    throw InputError(set.source.string() +
                     ": no withheld record or window (role validate or test): the diagnosis scores "
                     "effects on data the fits did not see");
  }
  if (o.pattern == RecordPattern::kResidualAnalysis) {
    for (const io::Record& r : set.records) {
      if (!(r.frequency_hz > 0)) {
        throw InputError(r.Label() + ": states no frequency (frequency_Hz), which the residual " +
                         "analysis's phase bins and harmonics need (pattern: residual analysis)");
      }
    }
  }
  d.excitation = records::AnalyseExcitation(set);
  const auto progress = o.fit.progress;
  records::FitOptions fo = o.fit;
  fo.family = o.family;
  fo.effects.clear();
  fo.progress = nullptr;
  if (progress) progress("base fit: " + o.family);
  d.base = FitRecords(set, fo);
  d.noise = BaseNoiseFloor(set, d.base);
  const double sigma2 = d.noise.sigma * d.noise.sigma;
  const double nw = static_cast<double>(d.withheld_samples),
               nt = static_cast<double>(d.train_samples);

  // Candidates that apply to the family, each fitted on top of the base model.
  const records::DataScale& scale = d.base.model->scale();
  const std::vector<model::EffectKind> cands = CandidateEffects(set, d, o);
  for (model::EffectKind e : cands) {
    if (progress) progress(std::string("candidate: ") + o.family + " + " + EffectName(e));
    RecordCandidate c;
    c.kind = e;
    c.fit = FitOnTop(set, d.base, e, scale, o, fo);
    if (!std::isfinite(Sse(set, c.fit, true))) {  // diverges on a withheld record: no score
      d.diverged.push_back(EffectName(e));
      continue;
    }
    d.candidates.push_back(std::move(c));
  }

  // The floor: one σ, or per record where the best-fitting model sits on its saturations.
  Shape shape{set, o, scale, sigma2, {}};
  double s_floor = nw * sigma2, var_w = sigma2, var_t = sigma2;
  if (o.floor == RecordFloor::kPerRecord) {
    const records::FitResult* floor_model = &d.base;
    for (const RecordCandidate& c : d.candidates)
      if (c.fit.train_sse < floor_model->train_sse) floor_model = &c.fit;
    d.floor_model = ModelLabel(*floor_model->model, o);
    shape.floors = PerRecordFloors(set, *floor_model);
    double st = 0;
    s_floor = 0;
    for (size_t i = 0; i < set.records.size(); ++i) {
      const double v = shape.floors[i] * shape.floors[i] * set.records[i].scored();
      (Withheld(set.records[i]) ? s_floor : st) += v;
    }
    var_w = s_floor / nw;
    var_t = st / nt;
    d.record_floor = shape.floors;
  } else {
    d.record_floor = shape.PooledFloors();
  }
  const Gap gap = MeasureGap(Sse(set, d.base, true), Sse(set, d.base, false), s_floor, var_w, var_t,
                             nw, nt, o.rules);
  d.s0 = gap.s0;
  d.s_floor = gap.s_floor;
  d.rms_ratio = gap.rms_ratio;
  d.significant = gap.significant;
  if (o.pattern == RecordPattern::kResidualAnalysis) shape.Excess(d.base, &d.base_residuals);
  const Naming naming = ScoreAndName(shape, gap, d.base, d.candidates);

  // The greedy second round, the final model and how far it closed the gap.
  std::shared_ptr<const records::FitResult> final_fit;
  if (naming.named >= 0) {
    const RecordCandidate& first = d.candidates[static_cast<size_t>(naming.named)];
    d.named_effects.push_back(first.kind);
    final_fit = std::make_shared<records::FitResult>(first.fit);
    if (o.second_effect) {
      d.second = SecondRound(shape, cands, first, gap, fo, d);
      if (d.second->named >= 0) {
        const RecordCandidate& c = d.second->candidates[static_cast<size_t>(d.second->named)];
        d.named_effects.push_back(c.kind);
        final_fit = std::make_shared<records::FitResult>(c.fit);
      }
    }
  } else {
    final_fit = std::make_shared<records::FitResult>(d.base);
  }
  d.final_fit = final_fit;
  d.withheld_after = Sse(set, *final_fit, true);
  d.closed_total = ClosedShare(d.s0, d.withheld_after, d.s_floor);
  d.gaps = RecordGaps(set, d);
  if (o.pattern == RecordPattern::kResidualAnalysis) shape.Excess(*final_fit, &d.final_residuals);
  if (!d.candidates.empty()) {
    d.absorbed =
        AbsorbedParameters(d.base.uncertainty.params, d.candidates[0].fit.uncertainty.params,
                           d.base.uncertainty.params.size());
    d.absorbed_by = EffectName(d.candidates[0].kind);
  }
  if (o.trends) {
    if (progress) progress("per-record fits (trends over the V x f grid)");
    d.trends = pz::diagnose::RecordTrends(set, d.base, fo, 25, &d.trend_evaluations);
  }
  ComposeRecordVerdict(set, o, gap, naming, d);
  return d;
}

std::string FinNextMeasurementHint(model::EffectKind a, model::EffectKind b) {
  auto is = [&](model::EffectKind x, model::EffectKind y) {
    return (a == x && b == y) || (a == y && b == x);
  };
  if (is(model::EffectKind::Named("driver-lowpass"), model::EffectKind::Named("delay")))
    return "A delay shifts every frequency by the same time, a low-pass lags by atan(2 pi f tau) "
           "and rounds edges: "
           "a square-wave (step) drive, or sinusoids at several times the bench's highest "
           "frequency, would separate them";
  return "A drive outside the bench's range of amplitudes and frequencies (a square wave, a sweep) "
         "would separate them; "
         "`piezoid diagnose --records` proposes one for record sets";
}

std::string ModelLabel(const records::RecordModel& model, const RecordDiagnoseOptions& o) {
  if (o.base_name.empty()) return model.Describe();
  std::string s = o.base_name;
  for (model::EffectKind e : model.effects()) s += std::string(" + ") + EffectName(e);
  return s;
}

RecordDiagnoseOptions FinBenchOptions() {
  RecordDiagnoseOptions o;
  o.family = "bimorph-fin";
  o.fit.family_options.bench_form = true;
  for (const records::FinEffectInfo& e : records::FinEffects()) o.candidates.push_back(e.kind);
  o.fit.search.algorithm = opt::SearchAlgorithm::kDe;
  o.fit.search.repetitions = 1;
  o.fit.search.de = opt::DeOptions{.population = 40, .generations = 80, .stall_generations = 15};
  o.fit.lm = opt::LmOptions{.max_iterations = 40};
  o.bench_fits.enabled = true;
  o.floor = RecordFloor::kPerRecord;
  o.pattern = RecordPattern::kResidualAnalysis;
  o.second_effect = true;
  o.absorbed_in_verdict = true;
  o.trends = true;
  o.model_label = "the base model";
  o.base_name = "base";
  o.propose = false;
  o.next_hint = FinNextMeasurementHint;
  o.excitation_note = false;
  o.floor_source = "rounding, scatter and saturation plateaus per case";
  return o;
}

TrialVerdict TrialVerdictOf(const RecordDiagnosis& d) {
  TrialVerdict v;
  v.verdict_kind = d.verdict_kind;
  v.significant = d.significant;
  v.rms_ratio = d.rms_ratio;
  if (d.named >= 0) {
    v.named = EffectName(d.candidates[static_cast<size_t>(d.named)].kind);
    v.confidence = d.confidence;
  }
  return v;
}

}  // namespace pz::diagnose
