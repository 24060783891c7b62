#include "diagnose/diagnose.h"

#include <algorithm>
#include <cmath>
#include <numeric>

#include "io/csv.h"
#include "model/format.h"
#include "model/model_comparison.h"

namespace pz::records {
namespace {

using model::CaseRole;

bool Withheld(const io::Record& r) { return r.role != CaseRole::kTrain; }

std::string Fmt(double x, int prec = 3) { return FormatG(x, prec); }

/// Σe² over the withheld (or training) scored samples of a fit.
double Sse(const io::RecordSet& set, const FitResult& f, bool withheld) {
  double s = 0;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& r = set.records[i];
    if (Withheld(r) != withheld) continue;
    for (size_t k = r.first_scored; k < r.end_scored; ++k) {
      const double e = r.y[k] - f.yhat[i][k];
      s += e * e;
    }
  }
  return s;
}

/// Per-sample squared errors over the withheld samples, in set order.
std::vector<double> WithheldSquares(const io::RecordSet& set, const FitResult& f) {
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

/// Localised excess over drive-level × direction bins of the withheld samples.
std::vector<double> BinExcess(const io::RecordSet& set, const FitResult& f, double sigma2,
                              const DataScale& s) {
  constexpr int kLevels = 10;
  std::vector<double> sse(2 * kLevels, 0.0), n(2 * kLevels, 0.0);
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& r = set.records[i];
    if (!Withheld(r)) continue;
    for (size_t k = std::max<size_t>(r.first_scored, 1); k < r.end_scored; ++k) {
      const double x = (r.u[k] - s.u_min) / (2 * s.u_half);
      const int level = std::clamp(static_cast<int>(x * kLevels), 0, kLevels - 1);
      const int dir = r.u[k] >= r.u[k - 1] ? 0 : 1;
      const double e = r.y[k] - f.yhat[i][k];
      sse[static_cast<size_t>(dir * kLevels + level)] += e * e;
      n[static_cast<size_t>(dir * kLevels + level)] += 1;
    }
  }
  std::vector<double> ex(sse.size());
  for (size_t b = 0; b < sse.size(); ++b) ex[b] = std::max(0.0, sse[b] - n[b] * sigma2);
  return ex;
}

}  // namespace

std::vector<double> PredictOnShape(const FitResult& fit, const DriveShape& shape, io::Record* out) {
  io::Record r;
  r.u = MakeDrive(shape);
  const size_t n = r.u.size();
  r.dt = 1 / shape.fs_hz;
  r.t.resize(n);
  for (size_t k = 0; k < n; ++k) r.t[k] = static_cast<double>(k) * r.dt;
  r.rest_samples = 1;
  while (r.rest_samples < n && r.u[r.rest_samples] == r.u[0]) ++r.rest_samples;
  r.first_scored =
      std::min(n - 1, r.rest_samples + static_cast<size_t>(shape.fs_hz / shape.frequency_hz));
  r.end_scored = n;
  std::vector<double> y(n);
  fit.model->Simulate(r, fit.params, fit.weights, n, y);
  for (double& v : y) v *= fit.model->scale().polarity;
  if (out) *out = std::move(r);
  return y;
}

ProposedExperiment ProposeExperiment(const io::RecordSet& set, const FitResult& a,
                                     const FitResult& b, double sigma) {
  const DataScale& s = a.model->scale();
  const double fs = s.fs;
  ProposedExperiment best;
  best.ratio_to_noise = -1;
  for (Waveform w : {Waveform::kSine, Waveform::kTriangle, Waveform::kSquare}) {
    for (double fm : {0.25, 0.5, 1.0, 2.0, 4.0, 8.0}) {
      const double f = s.f_dom * fm;
      if (f > fs / 20) continue;
      for (double am : {0.5, 1.0}) {
        DriveShape d;
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
  const DriveShape& d = best.shape;
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
NoiseFloor BaseNoiseFloor(const io::RecordSet& set, const FitResult& base) {
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
  return EstimateNoiseFloor(set, &base_res);
}

/// The candidates that apply to the family: those asked for, or by default the effects the family
/// does not hold and the records can support (creep-spectrum needs a window of a decade above its
/// fastest relaxation); asked for by name, such an effect is an error (its model throws); so does
/// rate dependence on training records at one rate (records/excitation.h, the rate span).
std::vector<EffectKind> CandidateEffects(const RecordDiagnosis& d, const RecordDiagnoseOptions& o) {
  std::vector<EffectKind> cands = o.candidates;
  if (!cands.empty()) return cands;
  const auto lib = EffectLibrary(d.base.model->scale());
  const auto excluded = d.base.model->family().excluded_effects();
  const bool rates = d.excitation.training.rate_span() >= kMinRateSpan;
  for (const EffectInfo& e : lib)
    if (std::find(excluded.begin(), excluded.end(), e.name) == excluded.end() &&
        e.unsupported.empty() && (rates || !NeedsRateCoverage(e.kind)))
      cands.push_back(e.kind);
  return cands;
}

/// Extra starts of a candidate's fit: the base fit with the effect at small magnitudes (unit
/// coordinates).
void AddExtraStarts(const RecordModel& model, const std::vector<double>& base_params, EffectKind e,
                    const DataScale& scale, FitOptions& ce) {
  const auto& params = model.params();
  opt::ParamBox box;
  for (const ParamInfo& p : params) {
    box.names.push_back(p.name);
    box.lower.push_back(p.lower);
    box.upper.push_back(p.upper);
    box.log_scale.push_back(p.log_scale);
  }
  for (double frac : {0.02, 0.1, 0.3}) {
    std::vector<double> phys = base_params;
    for (const ParamInfo& p : e->Params(scale)) {
      const double mid = p.lower <= 0 && p.upper >= 0 ? frac * (p.upper > 0 ? p.upper : p.lower)
                                                      : p.lower * std::pow(p.upper / p.lower, frac);
      phys.push_back(mid);
    }
    std::vector<double> unit(box.size());
    box.ToUnit(phys.data(), unit.data());
    ce.extra_starts.push_back(unit);
  }
}

/// The named effect, the proposed experiment, the excitation note and the verdict's text.
void ComposeRecordVerdict(const io::RecordSet& set, const RecordDiagnoseOptions& o,
                          const records::Gap& gap, const Naming& naming, RecordDiagnosis& d) {
  d.named = naming.named;
  d.runner_up = naming.runner_up;
  d.z_runner_up = naming.z_runner_up;
  d.confidence = naming.confidence;
  d.verdict_kind = VerdictKind(d.significant, naming);
  VerdictText text;
  text.model = o.family;
  text.unit = set.response_unit;
  text.floor_source = d.noise.used;
  text.floor = d.noise.sigma;
  if (d.runner_up >= 0 && o.propose) {
    d.next = ProposeExperiment(set, d.candidates[static_cast<size_t>(d.named)].fit,
                               d.candidates[static_cast<size_t>(d.runner_up)].fit, d.noise.sigma);
    text.next = d.next->description;
  }
  std::vector<double> ratios;
  for (const RecordMetrics& m : d.base.metrics) ratios.push_back(m.rmse / d.noise.sigma);
  if (d.significant && d.noise.sigma > 0)
    d.excitation_note = ExcitationGapNote(set, d.excitation, ratios, o.rules.significance_ratio);
  text.closing = d.excitation_note;
  std::vector<VerdictCandidate> ranked_names;
  for (const RecordCandidate& c : d.candidates) ranked_names.push_back({EffectName(c.kind), &c});
  d.verdict = ComposeVerdict(gap, ranked_names, naming, o.rules, text);
  if (!d.diverged.empty()) {
    std::string names;
    for (const auto& n : d.diverged) names += (names.empty() ? "" : ", ") + n;
    d.verdict += " Left out: " + names +
                 " (the fitted model's prediction is not finite on the withheld records: it " +
                 "diverges there).";
  }
}

}  // namespace

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
  d.excitation = AnalyseExcitation(set);
  const auto progress = o.fit.progress;
  FitOptions fo = o.fit;
  fo.family = o.family;
  fo.effects.clear();
  fo.progress = nullptr;
  if (progress) progress("base fit: " + o.family);
  d.base = FitRecords(set, fo);
  d.noise = BaseNoiseFloor(set, d.base);
  const double sigma2 = d.noise.sigma * d.noise.sigma;
  const double nw = static_cast<double>(d.withheld_samples),
               nt = static_cast<double>(d.train_samples);
  const records::Gap gap = MeasureGap(Sse(set, d.base, true), Sse(set, d.base, false), nw * sigma2,
                                      sigma2, sigma2, nw, nt, o.rules);
  d.s0 = gap.s0;
  d.s_floor = gap.s_floor;
  d.rms_ratio = gap.rms_ratio;
  d.significant = gap.significant;

  // Candidates that apply to the family.
  const DataScale& scale = d.base.model->scale();
  const std::vector<EffectKind> cands = CandidateEffects(d, o);
  const auto base_ex = BinExcess(set, d.base, sigma2, scale);
  const auto base_sq = WithheldSquares(set, d.base);
  for (EffectKind e : cands) {
    if (progress) progress(std::string("candidate: ") + o.family + " + " + EffectName(e));
    RecordCandidate c;
    c.kind = e;
    FitOptions ce = fo;
    auto model = std::make_shared<RecordModel>(d.base.model->family_ptr(),
                                               std::vector<EffectKind>{e}, scale);
    AddExtraStarts(*model, d.base.params, e, scale, ce);
    c.fit = FitModel(set, model, ce);
    const int k = static_cast<int>(e->Params(scale).size());
    const double s_withheld = Sse(set, c.fit, true);
    if (!std::isfinite(s_withheld)) {  // diverges on a withheld record: nothing to score
      d.diverged.push_back(EffectName(e));
      continue;
    }
    ScoreCandidate(gap, s_withheld, Sse(set, c.fit, false), k,
                   PatternExplained(base_ex, BinExcess(set, c.fit, sigma2, scale)), o.rules, c);
    c.z_vs_base = model::PairedBlockZ(base_sq, WithheldSquares(set, c.fit), o.rules.blocks);
    d.candidates.push_back(std::move(c));
  }
  RankByScore(d.candidates);
  const std::vector<CandidateScore*> ranked = Scores(d.candidates);
  AssignWeights(gap, ranked);
  const Naming naming = NameEffect(
      gap, ranked,
      [&](int i) {
        return i < 0 ? base_sq : WithheldSquares(set, d.candidates[static_cast<size_t>(i)].fit);
      },
      o.rules);
  ComposeRecordVerdict(set, o, gap, naming, d);
  return d;
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

}  // namespace pz::records
