#include "records/diagnose.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

#include "io/csv.h"
#include "model/model_comparison.h"
#include "model/noise_floor.h"

namespace pz::records {
namespace {

using model::CaseRole;

bool Withheld(const io::Record& r) { return r.role != CaseRole::kTrain; }

std::string Fmt(double x, int prec = 3) {
  std::ostringstream s;
  s.precision(prec);
  s << x;
  return s.str();
}

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
std::vector<double> BinExcess(const io::RecordSet& set, const FitResult& f, double sigma2, const DataScale& s) {
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

double DetrendedStd(std::span<const double> y) {
  const double n = static_cast<double>(y.size());
  double st = 0, sy = 0, stt = 0, sty = 0;
  for (size_t k = 0; k < y.size(); ++k) {
    const double t = static_cast<double>(k);
    st += t;
    sy += y[k];
    stt += t * t;
    sty += t * y[k];
  }
  const double b = (sty - st * sy / n) / (stt - st * st / n), a = (sy - b * st) / n;
  double ss = 0;
  for (size_t k = 0; k < y.size(); ++k) {
    const double e = y[k] - a - b * static_cast<double>(k);
    ss += e * e;
  }
  return std::sqrt(ss / (n - 2));
}

}  // namespace

NoiseFloor EstimateNoiseFloor(const io::RecordSet& set, const std::vector<std::vector<double>>* residuals) {
  NoiseFloor nf;
  // Rest segments (one per file: records that share a file share its rest).
  {
    double ss = 0;
    size_t n = 0;
    std::vector<std::string> seen;
    for (const io::Record& r : set.records) {
      if (r.rest_samples < 50 || std::find(seen.begin(), seen.end(), r.file.string()) != seen.end()) continue;
      seen.push_back(r.file.string());
      const double s = DetrendedStd(std::span<const double>(r.y).first(r.rest_samples));
      ss += s * s * static_cast<double>(r.rest_samples);
      n += r.rest_samples;
    }
    if (n > 0) nf.estimates.push_back({"rest", std::sqrt(ss / static_cast<double>(n)), n, std::to_string(seen.size()) + " rest segment(s)"});
  }
  // Periods: the drive repeats after P samples over the excited part.
  {
    double ss = 0;
    size_t n = 0;
    int found = 0;
    std::vector<std::string> seen;
    for (const io::Record& r : set.records) {
      if (std::find(seen.begin(), seen.end(), r.file.string()) != seen.end()) continue;
      seen.push_back(r.file.string());
      const size_t start = r.rest_samples, len = r.size() - start;
      if (len < 60) continue;
      double lo = *std::min_element(r.u.begin() + static_cast<std::ptrdiff_t>(start), r.u.end());
      double hi = *std::max_element(r.u.begin() + static_cast<std::ptrdiff_t>(start), r.u.end());
      const double tol = 1e-4 * (hi - lo) + 1e-12;
      size_t period = 0;
      for (size_t P = 10; P <= len / 2 && !period; ++P) {  // two periods at least
        bool ok = true;
        for (size_t k = start; k + P < r.size() && ok; k += std::max<size_t>(1, P / 50)) ok = std::abs(r.u[k + P] - r.u[k]) <= tol;
        if (ok) period = P;
      }
      if (!period) continue;
      // The last two periods (model/noise_floor.h, as the scatter of a bench case).
      const double s = model::PeriodDifferenceSquares(r.y, r.size() - 2 * period, period);
      ss += s / 4;
      n += period - 1;
      ++found;
    }
    if (n > 0) nf.estimates.push_back({"periods", std::sqrt(ss / static_cast<double>(n)), n, std::to_string(found) + " periodic record(s)"});
  }
  // Repeats: records with the same drive.
  {
    double ss = 0;
    size_t n = 0;
    for (size_t i = 0; i < set.records.size(); ++i) {
      for (size_t j = i + 1; j < set.records.size(); ++j) {
        const io::Record &a = set.records[i], &b = set.records[j];
        if (a.file == b.file || a.size() != b.size()) continue;
        bool same = true;
        for (size_t k = 0; k < a.size() && same; ++k) same = std::abs(a.u[k] - b.u[k]) <= 1e-9 * (1 + std::abs(a.u[k]));
        if (!same) continue;
        double mean = 0;
        for (size_t k = 0; k < a.size(); ++k) mean += a.y[k] - b.y[k];
        mean /= static_cast<double>(a.size());
        for (size_t k = 0; k < a.size(); ++k) {
          const double d = a.y[k] - b.y[k] - mean;
          ss += d * d / 2;
        }
        n += a.size();
      }
    }
    if (n > 0) nf.estimates.push_back({"repeats", std::sqrt(ss / static_cast<double>(n)), n, "records with the same drive"});
  }
  if (residuals) {
    double ss = 0;
    size_t n = 0;
    for (const auto& e : *residuals) {
      for (size_t k = 1; k < e.size(); ++k) ss += (e[k] - e[k - 1]) * (e[k] - e[k - 1]) / 2;
      n += e.size() > 1 ? e.size() - 1 : 0;
    }
    if (n > 0) nf.estimates.push_back({"residual", std::sqrt(ss / static_cast<double>(n)), n, "high-frequency part of the base model's residual"});
  }
  if (nf.estimates.empty()) {
    throw InputError("no noise estimate is possible: no rest segment of 50 samples, no periodic drive, no repeated record, no residual");
  }
  // A reading rounded to a quantum q is at least q/√12 RMS from a continuous model on a varying
  // signal, while a rest or two identical periods can cancel the rounding (σ ≪ q): no estimate
  // goes below that floor.
  double q = 0;
  for (const io::Record& r : set.records) q = std::max(q, r.quantum);
  const double q_floor = q / std::sqrt(12.0);
  for (NoiseEstimate& e : nf.estimates) {
    if (e.sigma < q_floor) {
      e.sigma = q_floor;
      e.detail += "; raised to the quantisation floor q/√12 (q = " + Fmt(q) + ")";
    }
  }
  nf.sigma = nf.estimates.front().sigma;
  nf.used = nf.estimates.front().method;
  return nf;
}

std::vector<double> PredictOnShape(const FitResult& fit, const DriveShape& shape, io::Record* out) {
  io::Record r;
  r.u = MakeDrive(shape);
  const size_t n = r.u.size();
  r.dt = 1 / shape.fs_hz;
  r.t.resize(n);
  for (size_t k = 0; k < n; ++k) r.t[k] = static_cast<double>(k) * r.dt;
  r.rest_samples = 1;
  while (r.rest_samples < n && r.u[r.rest_samples] == r.u[0]) ++r.rest_samples;
  r.first_scored = std::min(n - 1, r.rest_samples + static_cast<size_t>(shape.fs_hz / shape.frequency_hz));
  r.end_scored = n;
  std::vector<double> y(n);
  fit.model->Simulate(r, fit.params, fit.weights, n, y);
  for (double& v : y) v *= fit.model->scale().polarity;
  if (out) *out = std::move(r);
  return y;
}

ProposedExperiment ProposeExperiment(const io::RecordSet& set, const FitResult& a, const FitResult& b, double sigma) {
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
        for (size_t k = r.first_scored; k < r.end_scored; ++k) ss += (ya[k] - yb[k] - mean) * (ya[k] - yb[k] - mean);
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
  best.description = std::string("a ") + WaveformName(d.waveform) + " of ±" + Fmt(d.amplitude, 4) + " " +
                     set.drive_unit + " around " + Fmt(d.bias, 4) + " " + set.drive_unit + " at " +
                     Fmt(d.frequency_hz, 4) + " Hz for " + Fmt(d.duration_s, 3) + " s (sampled at " + Fmt(d.fs_hz, 5) +
                     " Hz), where " + a.model->Describe() + " and " + b.model->Describe() + " differ by " +
                     Fmt(best.rms_difference, 3) + " " + set.response_unit + " RMS = " + Fmt(best.ratio_to_noise, 3) +
                     " × the noise floor";
  return best;
}

RecordDiagnosis DiagnoseRecords(const io::RecordSet& set, const RecordDiagnoseOptions& o) {
  if (auto st = o.rules.Validate(); !st.ok()) throw InputError("rules." + st.message());
  RecordDiagnosis d;
  for (const io::Record& r : set.records) (Withheld(r) ? d.withheld_samples : d.train_samples) += r.scored();
  if (d.train_samples == 0) throw InputError(set.source.string() + ": no training record (role train)");
  if (d.withheld_samples == 0) {
    throw InputError(set.source.string() + ": no withheld record or window (role validate or test): the diagnosis scores effects on data the fits did not see");
  }
  d.excitation = AnalyseExcitation(set);
  const auto progress = o.fit.progress;
  FitOptions fo = o.fit;
  fo.family = o.family;
  fo.effects.clear();
  fo.progress = nullptr;
  if (progress) progress("base fit: " + o.family);
  d.base = FitRecords(set, fo);
  std::vector<std::vector<double>> base_res;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const io::Record& r = set.records[i];
    std::vector<double> e;
    for (size_t k = r.first_scored; k < r.end_scored; ++k) e.push_back(r.y[k] - d.base.yhat[i][k]);
    base_res.push_back(std::move(e));
  }
  d.noise = EstimateNoiseFloor(set, &base_res);
  const double sigma2 = d.noise.sigma * d.noise.sigma;
  const double nw = static_cast<double>(d.withheld_samples), nt = static_cast<double>(d.train_samples);
  const records::Gap gap =
      MeasureGap(Sse(set, d.base, true), Sse(set, d.base, false), nw * sigma2, sigma2, sigma2, nw, nt, o.rules);
  d.s0 = gap.s0;
  d.s_floor = gap.s_floor;
  d.rms_ratio = gap.rms_ratio;
  d.significant = gap.significant;

  // Candidates that apply to the family.
  const DataScale& scale = d.base.model->scale();
  const auto lib = EffectLibrary(scale);
  std::vector<EffectKind> cands = o.candidates;
  if (cands.empty()) {
    // By default, the effects the family does not hold and the records can support (creep-spectrum
    // needs a window of a decade above its fastest relaxation); asked for by name, such an effect
    // is an error (its model throws).
    const auto excluded = d.base.model->family().excluded_effects();
    for (const EffectInfo& e : lib)
      if (std::find(excluded.begin(), excluded.end(), e.name) == excluded.end() && e.unsupported.empty())
        cands.push_back(e.kind);
  }
  const auto base_ex = BinExcess(set, d.base, sigma2, scale);
  const auto base_sq = WithheldSquares(set, d.base);
  for (EffectKind e : cands) {
    if (progress) progress(std::string("candidate: ") + o.family + " + " + EffectName(e));
    RecordCandidate c;
    c.kind = e;
    FitOptions ce = fo;
    auto model = std::make_shared<RecordModel>(d.base.model->family_ptr(), std::vector<EffectKind>{e}, scale);
    // Extra starts: the base fit with the effect at small magnitudes (unit coordinates).
    const auto& params = model->params();
    opt::ParamBox box;
    for (const ParamInfo& p : params) {
      box.names.push_back(p.name);
      box.lower.push_back(p.lower);
      box.upper.push_back(p.upper);
      box.log_scale.push_back(p.log_scale);
    }
    for (double frac : {0.02, 0.1, 0.3}) {
      std::vector<double> phys = d.base.params;
      for (const ParamInfo& p : lib[static_cast<size_t>(e)].params) {
        const double mid = p.lower <= 0 && p.upper >= 0 ? frac * (p.upper > 0 ? p.upper : p.lower)
                                                         : p.lower * std::pow(p.upper / p.lower, frac);
        phys.push_back(mid);
      }
      std::vector<double> unit(box.size());
      box.ToUnit(phys.data(), unit.data());
      ce.extra_starts.push_back(unit);
    }
    c.fit = FitModel(set, model, ce);
    const int k = static_cast<int>(lib[static_cast<size_t>(e)].params.size());
    ScoreCandidate(gap, Sse(set, c.fit, true), Sse(set, c.fit, false), k,
                   PatternExplained(base_ex, BinExcess(set, c.fit, sigma2, scale)), o.rules, c);
    c.z_vs_base = model::PairedBlockZ(base_sq, WithheldSquares(set, c.fit), o.rules.blocks);
    d.candidates.push_back(std::move(c));
  }
  RankByScore(d.candidates);
  const std::vector<CandidateScore*> ranked = Scores(d.candidates);
  AssignWeights(gap, ranked);
  const Naming naming = NameEffect(
      gap, ranked,
      [&](int i) { return i < 0 ? base_sq : WithheldSquares(set, d.candidates[static_cast<size_t>(i)].fit); },
      o.rules);
  d.named = naming.named;
  d.runner_up = naming.runner_up;
  d.z_runner_up = naming.z_runner_up;
  d.confidence = naming.confidence;
  d.verdict_kind = VerdictKind(d.significant, naming);
  const std::string unit = set.response_unit;
  std::ostringstream v;
  if (!d.significant) {
    v << "No significant gap: the withheld RMS error of " << o.family << " is " << Fmt(d.rms_ratio) << " × the noise floor ("
      << Fmt(d.noise.sigma) << " " << unit << ", from " << d.noise.used << "), at most " << o.rules.significance_ratio << ".";
  } else if (d.named < 0) {
    v << "A significant gap (" << Fmt(d.rms_ratio) << " × the noise floor) that no candidate explains by the rules.";
  } else {
    const RecordCandidate& best = d.candidates[static_cast<size_t>(d.named)];
    if (d.runner_up >= 0) {
      const RecordCandidate& ru = d.candidates[static_cast<size_t>(d.runner_up)];
      v << "The data cannot separate " << EffectName(best.kind) << " from " << EffectName(ru.kind)
        << ": both bring the withheld gap to the noise floor (" << Fmt(std::sqrt(best.s_withheld / d.s_floor)) << " × and "
        << Fmt(std::sqrt(ru.s_withheld / d.s_floor)) << " ×, at most " << o.rules.significance_ratio
        << "; they close " << Fmt(100 * best.closed) << " % and " << Fmt(100 * ru.closed)
        << " %) and the paired block test does not separate them (z = " << Fmt(d.z_runner_up, 2) << " < "
        << o.rules.separation_z << "); confidence in " << EffectName(best.kind) << " " << Fmt(100 * d.confidence, 3) << " %.";
      if (o.propose) {
        d.next = ProposeExperiment(set, best.fit, ru.fit, d.noise.sigma);
        v << " Next measurement: " << d.next->description << ".";
      }
    } else {
      v << "The gap is " << EffectName(best.kind) << " (confidence " << Fmt(100 * d.confidence, 3) << " %): adding it closes "
        << Fmt(100 * best.closed) << " % of the excess withheld gap; withheld RMS " << Fmt(std::sqrt(d.s0 / nw)) << " → "
        << Fmt(std::sqrt(best.s_withheld / nw)) << " " << unit << " against a noise floor of " << Fmt(d.noise.sigma) << " "
        << unit << " (" << d.noise.used << ").";
    }
  }
  std::vector<double> ratios;
  for (const RecordMetrics& m : d.base.metrics) ratios.push_back(m.rmse / d.noise.sigma);
  if (d.significant && d.noise.sigma > 0) d.excitation_note = ExcitationGapNote(set, d.excitation, ratios, o.rules.significance_ratio);
  if (!d.excitation_note.empty()) v << " " << d.excitation_note;
  d.verdict = v.str();
  return d;
}

}  // namespace pz::records
