#include "reports/bench_grid.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>

#include "diagnose/verdict.h"
#include "diagnosis.pb.h"
#include "io/csv.h"
#include "model/model_comparison.h"
#include "reports/diagnose_report.h"
#include "reports/plots.h"

namespace pz::reports {
namespace {

using diagnose::BenchDiagnosis;
using diagnose::RecordCandidate;
using diagnose::RecordDiagnosis;

std::string F(const char* fmt, double a) {
  if (!std::isfinite(a)) return "n/a";
  char buf[64];
  std::snprintf(buf, sizeof buf, fmt, a);
  return buf;
}
std::string Pct(double share) { return std::isfinite(share) ? F("%.0f %%", 100 * share) : "n/a"; }
// A table cell of Markdown: '|' escaped, a line break as a space.
std::string Md(const std::string& s) {
  std::string r;
  for (char c : s) {
    if (c == '|')
      r += "\\|";
    else
      r += c == '\n' ? ' ' : c;
  }
  return r;
}

double Rms(double pi, int n) { return n > 0 ? std::sqrt(pi / n) : NAN; }

std::string Pad(std::string s, size_t w) {
  // Pads by code points (the names hold UTF-8 Greek letters in some places).
  size_t len = 0;
  for (unsigned char c : s) len += (c & 0xC0) != 0x80;
  while (len++ < w) s += ' ';
  return s;
}

// A records fit as the bench reads it: its structure ("base + delay") and its Σe² [deg²] and
// samples over the training and the withheld cases.
struct FitView {
  const records::FitResult* fit = nullptr;
  std::string description;
  double train_pi = 0, withheld_pi = 0;
  int train_samples = 0, withheld_samples = 0;
  const std::vector<opt::ParamEstimate>& params() const { return fit->uncertainty.params; }
};

FitView ViewOf(const io::RecordSet& set, const records::FitResult& f) {
  static const diagnose::RecordDiagnoseOptions kBench = diagnose::FinBenchOptions();
  FitView v;
  v.fit = &f;
  v.description = diagnose::ModelLabel(*f.model, kBench);
  for (size_t i = 0; i < set.records.size() && i < f.metrics.size(); ++i) {
    const bool training = set.records[i].role == model::CaseRole::kTrain;
    (training ? v.train_pi : v.withheld_pi) += f.metrics[i].sse;
    (training ? v.train_samples : v.withheld_samples) += static_cast<int>(set.records[i].scored());
  }
  return v;
}

// A greedy round of the records result: the model it starts from, its gap, its ranked candidates
// and what it named.
struct RoundView {
  const records::FitResult* start = nullptr;
  double s0 = 0, s_floor = 0, rms_ratio = 0;
  bool significant = false;
  const std::vector<RecordCandidate>* candidates = nullptr;
  int named = -1, runner_up = -1;
  double z_runner_up = 0;
  const std::string* verdict = nullptr;
};

std::vector<RoundView> Rounds(const RecordDiagnosis& d) {
  std::vector<RoundView> r = {{&d.base, d.s0, d.s_floor, d.rms_ratio, d.significant, &d.candidates,
                               d.named, d.runner_up, d.z_runner_up, &d.round_verdict}};
  if (d.second) {
    const diagnose::RecordRound& s = *d.second;
    r.push_back({&d.candidates[static_cast<size_t>(d.named)].fit, s.gap.s0, s.gap.s_floor,
                 s.gap.rms_ratio, s.gap.significant, &s.candidates, s.named, s.runner_up,
                 s.z_runner_up, &s.verdict});
  }
  return r;
}

int AddedParams(const RecordCandidate& c, const RoundView& r) {
  return static_cast<int>(c.fit.params.size() - r.start->params.size());
}

void PrintParams(std::ostream& o, const FitView& f, const std::string& indent) {
  o << indent << Pad("parameter", 30) << Pad("value", 14) << Pad("± σ", 12)
    << Pad("sensitivity", 13) << "identifiability\n";
  for (const auto& p : f.params()) {
    o << indent << Pad(p.name + " [" + p.unit + "]", 30) << Pad(F("%.5g", p.value), 14)
      << Pad(std::isfinite(p.std_error) ? F("%.3g", p.std_error) : "—", 12)
      << Pad(F("%.4f deg", p.sensitivity), 13) << opt::IdentifiabilityName(p.identifiability)
      << (p.note.empty() ? "" : "; " + p.note) << "\n";
  }
  if (!f.fit->uncertainty.weakest_direction.empty())
    o << indent << "weakest direction: " << f.fit->uncertainty.weakest_direction << "\n";
}

// The effects' parameters (those after the family's own) with σ.
std::string EffectParams(const records::FitResult& f) {
  std::string s;
  const auto& params = f.uncertainty.params;
  for (size_t i = f.model->family().params().size(); i < params.size(); ++i) {
    const auto& p = params[i];
    s += (s.empty() ? "" : ", ") + p.name + " = " + F("%.4g", p.value) +
         (std::isfinite(p.std_error) ? " ± " + F("%.2g", p.std_error) : "") + " " + p.unit;
  }
  return s;
}

std::vector<double> Sorted(std::set<double> s) { return {s.begin(), s.end()}; }

// ---- terminal
// ------------------------------------------------------------------------------------

// The noise floor and the base model's fit.
void PrintHead(std::ostream& o, const BenchDiagnosis& d, const FitView& b) {
  int nt = 0, nw = 0;
  for (const auto& c : d.cases) (c.training ? nt : nw) += 1;
  o << "piezoid diagnose: " << d.bench << " (" << d.cases.size() << " cases: " << nt
    << " training, " << nw << " withheld)\n";
  o << "noise floor: encoder quantum " << F("%.5g", d.quantum_deg) << " deg; floor "
    << F("%.4f", d.floor_train) << " (training) / " << F("%.4f", d.floor_withheld)
    << " (withheld) deg RMS (plateaus of " << d.records.floor_model << ")\n";
  o << "base model (one parameter set for every case, b1/b2 from the measured extremes): training "
       "RMS "
    << F("%.4f", Rms(b.train_pi, b.train_samples)) << ", withheld RMS "
    << F("%.4f", Rms(b.withheld_pi, b.withheld_samples)) << " deg\n\n";
}

// Where the base model's residual lies, and the trends of the per-case fits.
void PrintWhere(std::ostream& o, const RecordDiagnosis& d) {
  o << "WHERE the gap lies (base model, each against the floor)\n";
  o << "  case   V [V]  f [Hz]  role      floor   RMS      x floor  share of PI\n";
  for (size_t i = 0; i < d.base_residuals.cases.size(); ++i) {
    const auto& c = d.base_residuals.cases[i];
    char buf[200];
    std::snprintf(buf, sizeof buf, "  %-5d %6.0f %7.3g  %-8s %7.4f  %7.4f  %6.2f   %5.1f %%\n",
                  c.number, c.amplitude_v, c.frequency_hz, c.training ? "training" : "withheld",
                  c.floor_rms, c.rms, c.rms_over_floor, 100 * c.share);
    o << buf;
  }
  for (const auto& f : d.base_residuals.findings) o << "  - " << f << "\n";
  bool any_trend = false;
  for (const auto& t : d.trends) {
    if (!t.significant) continue;
    if (!any_trend)
      o << "  parameter trends over the V x f grid (per-case fits; a global model cannot follow "
           "them):\n";
    any_trend = true;
    o << "    " << Pad(t.name, 7) << " slope " << F("%.3g", t.slope_v)
      << " /V (p = " << F("%.2g", t.p_v) << "), " << F("%.3g", t.slope_f)
      << " /Hz (p = " << F("%.2g", t.p_f) << "), range " << Pct(t.relative_range)
      << " of its mean\n";
  }
  if (!d.trends.empty() && !any_trend)
    o << "  no significant parameter trend over the V x f grid (per-case fits)\n";
}

// Each round's candidates, the verdict and what the base parameters absorbed.
void PrintWhich(std::ostream& o, const BenchDiagnosis& d, const FitView& b) {
  const RecordDiagnosis& rd = d.records;
  o << "\nWHICH effect (re-identified on the training cases, scored on the withheld ones)\n";
  const std::vector<RoundView> rounds = Rounds(rd);
  for (size_t r = 0; r < rounds.size(); ++r) {
    const RoundView& rr = rounds[r];
    o << "  round " << r + 1 << " from " << ViewOf(d.set, *rr.start).description
      << ": withheld RMS " << F("%.4f", std::sqrt(rr.s0 / std::max(1, b.withheld_samples)))
      << " deg = " << F("%.2f", rr.rms_ratio) << " x floor ("
      << (rr.significant ? "significant" : "not significant") << ", threshold "
      << F("%.2f", d.rules.significance_ratio) << ")\n";
    o << "    " << Pad("candidate", 18) << Pad("+k", 4) << Pad("withheld RMS", 14)
      << Pad("score", 10) << Pad("closed", 8) << Pad("pattern", 9) << Pad("weight", 8) << "notes\n";
    for (const RecordCandidate& c : *rr.candidates) {
      const FitView f = ViewOf(d.set, c.fit);
      o << "    " << Pad(model::EffectName(c.kind), 18)
        << Pad(std::to_string(AddedParams(c, rr)), 4)
        << Pad(F("%.4f", Rms(f.withheld_pi, f.withheld_samples)), 14) << Pad(F("%.1f", c.score), 10)
        << Pad(Pct(c.closed), 8) << Pad(Pct(c.pattern), 9) << Pad(F("%.3f", c.weight), 8)
        << (c.qualifies ? "qualifies" : c.note) << "\n";
    }
    o << "    => " << *rr.verdict << "\n";
  }
  o << "\nVERDICT: " << rd.verdict << "\n";
  if (!rd.absorbed.empty()) {
    o << "  base parameters that move when " << rd.absorbed_by << " is added (|shift| > 2 σ):";
    for (const auto& a : rd.absorbed)
      o << " " << a.name << " " << F("%.4g", a.without) << " -> " << F("%.4g", a.with) << " "
        << a.unit << " (z " << F("%.1f", a.z) << ");";
    o << "\n";
  }
}

}  // namespace

void PrintBenchSummary(std::ostream& o, const BenchDiagnosis& d) {
  const RecordDiagnosis& rd = d.records;
  const FitView b = ViewOf(d.set, rd.base), fin = ViewOf(d.set, *rd.final_fit);
  PrintHead(o, d, b);
  PrintWhere(o, rd);
  PrintWhich(o, d, b);

  o << "\nHOW FAR the gap shrinks (" << fin.description << ")\n";
  o << "  case  role      floor   RMS before  RMS after  x floor after  closed\n";
  for (size_t i = 0; i < rd.gaps.size(); ++i) {
    const diagnose::RecordGap& g = rd.gaps[i];
    char buf[200];
    std::snprintf(buf, sizeof buf, "  %-5d %-8s %7.4f  %9.4f  %9.4f  %12.2f  %s\n",
                  d.cases[i].number, d.cases[i].training ? "training" : "withheld", g.floor_rms,
                  g.rms_before, g.rms_after, g.floor_rms > 0 ? g.rms_after / g.floor_rms : NAN,
                  Pct(g.closed).c_str());
    o << buf;
  }
  o << "  withheld total: PI " << F("%.4f", rd.s0) << " -> " << F("%.4f", rd.withheld_after)
    << " deg^2 (floor " << F("%.4f", rd.s_floor) << "), share of the gap closed "
    << Pct(rd.closed_total) << ", remaining "
    << F("%.2f", std::sqrt(rd.withheld_after / rd.s_floor)) << " x floor\n";
  if (!rd.named_effects.empty())
    o << "  effect parameters: " << EffectParams(*rd.final_fit) << "\n";

  o << "\nIDENTIFIABILITY (" << fin.description << ", σ from s² (JᵀJ)⁺ at the solution)\n";
  PrintParams(o, fin, "  ");
  if (fin.description != b.description) {
    o << "  base model:\n";
    PrintParams(o, b, "  ");
  }
  o << "\n"
    << F("%.1f", d.wall_time_s) << " s, " << diagnose::BenchEvaluations(rd)
    << " model evaluations\n";
}

// ---- JSON ---------------------------------------------------------------------------------------
// diagnosis.json: the diagnosis as its stored message (proto/diagnosis.proto), written by
// io/diagnosis_json.h (keys sorted, a non-finite number as null).

namespace {

void FitOf(const FitView& v, proto::DiagnosisFit* o) {
  const records::FitResult& f = *v.fit;
  o->set_structure(v.description);
  o->set_ok(true);
  o->set_train_pi_deg2(v.train_pi);
  o->set_withheld_pi_deg2(v.withheld_pi);
  o->set_train_rms_deg(Rms(v.train_pi, v.train_samples));
  o->set_withheld_rms_deg(Rms(v.withheld_pi, v.withheld_samples));
  o->set_residual_sigma_deg(f.uncertainty.residual_sigma);
  for (const records::RecordMetrics& m : f.metrics) o->add_case_pi_deg2(m.sse);
  for (const auto& p : v.params()) {
    proto::DiagnosisParameter& g = *o->add_parameters();
    g.set_name(p.name);
    g.set_unit(p.unit);
    g.set_value(p.value);
    g.set_std_error(p.std_error);
    g.set_sensitivity_deg(p.sensitivity);
    g.set_identifiability(opt::IdentifiabilityName(p.identifiability));
    g.set_note(p.note);
  }
  o->mutable_singular_values()->Assign(f.uncertainty.singular_values.begin(),
                                       f.uncertainty.singular_values.end());
  o->set_weakest_direction(f.uncertainty.weakest_direction);
  o->set_evaluations(diagnose::FitEvaluations(f));
  o->set_wall_time_s(f.wall_time_s);
  o->set_message(f.polish_message);
}

void BinOf(const model::BinStat& b, proto::ResidualBin* o) {
  o->set_rms_deg(b.rms);
  o->set_mean_deg(b.mean);
  o->set_n(b.n);
}

void LoopOf(const model::LoopFeatures& l, proto::LoopFeatures* o) {
  o->set_width_deg(l.width_deg);
  o->set_area_deg_v(l.area_deg_v);
  o->set_offset_deg(l.offset_deg);
  o->set_peak_to_peak_deg(l.peak_to_peak_deg);
  o->set_top_phase_deg(l.top_phase_deg);
  o->set_phase_lag_deg(l.phase_lag_deg);
  o->set_fundamental_deg(l.fundamental_deg);
}

void CaseResidualOf(const model::CaseResidual& c, proto::CaseResidual* o) {
  o->set_case_(c.number);
  o->set_training(c.training);
  o->set_amplitude_v(c.amplitude_v);
  o->set_frequency_hz(c.frequency_hz);
  o->set_pi_deg2(c.pi);
  o->set_rms_deg(c.rms);
  o->set_max_abs_deg(c.max_abs);
  o->set_share(c.share);
  o->set_floor_rms_deg(c.floor_rms);
  o->set_rms_over_floor(c.rms_over_floor);
  for (int b = 0; b < model::kPhaseBins; ++b) {
    o->add_phase_bins_rms_deg(c.phase[b].rms);
    o->add_phase_bins_mean_deg(c.phase[b].mean);
  }
  BinOf(c.rising, o->mutable_rising());
  BinOf(c.falling, o->mutable_falling());
  BinOf(c.near_reversal, o->mutable_near_reversal());
  BinOf(c.in_saturation, o->mutable_in_saturation());
  BinOf(c.first_cycle, o->mutable_first_cycle());
  BinOf(c.later_cycles, o->mutable_later_cycles());
  o->mutable_cycle_mean_deg()->Assign(c.cycle_mean.begin(), c.cycle_mean.end());
  o->set_trend_deg_per_s(c.trend_deg_per_s);
  o->set_trend_se(c.trend_se);
  o->mutable_harmonics_deg()->Assign(c.harmonic.begin(), c.harmonic.end());
  o->set_harmonic_noise_deg(c.harmonic_noise);
  o->set_odd_rms_deg(c.odd_rms);
  o->set_even_rms_deg(c.even_rms);
  o->set_low_frequency_rms_deg(c.low_rms);
  LoopOf(c.measured_loop, o->mutable_measured_loop());
  LoopOf(c.model_loop, o->mutable_model_loop());
}

void AnalysisOf(const model::ResidualAnalysis& a, proto::ResidualAnalysis* o) {
  for (const auto& c : a.cases) CaseResidualOf(c, o->add_cases());
  for (const auto& f : a.findings) o->add_findings(f);
}

// The noise floor: the encoder's quantum, the pooled floors and each case's.
void NoiseOf(const BenchDiagnosis& d, proto::BenchNoise* o) {
  o->set_quantum_deg(d.quantum_deg);
  o->set_floor_train_deg(d.floor_train);
  o->set_floor_withheld_deg(d.floor_withheld);
  o->set_floor_model(d.records.floor_model);
  for (size_t i = 0; i < d.cases.size(); ++i) {
    const auto& c = d.cases[i];
    proto::BenchCaseNoise& g = *o->add_cases();
    g.set_case_(c.number);
    g.set_quantum_deg(c.noise.quantum_deg);
    g.set_quantisation_rms_deg(c.noise.quantisation_rms_deg);
    g.set_scatter_rms_deg(c.noise.scatter_rms_deg);
    g.set_floor_rms_deg(c.noise.floor_rms_deg);
    g.set_saturation_aware_floor_deg(i < d.records.gaps.size() ? d.records.gaps[i].floor_rms : NAN);
    g.set_b1_deg(c.b1);
    g.set_b2_deg(c.b2);
  }
}

void TrendOf(const diagnose::ParamTrend& t, proto::ParamTrend* o) {
  o->set_name(t.name);
  o->mutable_per_case()->Assign(t.per_case.begin(), t.per_case.end());
  o->set_slope_per_v(t.slope_v);
  o->set_slope_per_hz(t.slope_f);
  o->set_p_v(t.p_v);
  o->set_p_f(t.p_f);
  o->set_r2(t.r2);
  o->set_relative_range(t.relative_range);
  o->set_significant(t.significant);
}

void RoundOf(const io::RecordSet& set, const RoundView& r, proto::DiagnosisRound* o) {
  for (const auto& k : r.start->model->effects()) o->add_from(model::EffectName(k));
  o->set_withheld_pi_deg2(r.s0);
  o->set_floor_pi_deg2(r.s_floor);
  o->set_rms_over_floor(r.rms_ratio);
  o->set_significant(r.significant);
  if (r.named >= 0)
    o->set_named(model::EffectName((*r.candidates)[static_cast<size_t>(r.named)].kind));
  if (r.runner_up >= 0) {
    o->mutable_runner_up()->set_effect(
        model::EffectName((*r.candidates)[static_cast<size_t>(r.runner_up)].kind));
    o->mutable_runner_up()->set_z(r.z_runner_up);
  }
  o->set_verdict(*r.verdict);
  for (const auto& c : *r.candidates) {
    proto::DiagnosisCandidate& g = *o->add_candidates();
    CandidateOf(c, *r.start, &g);
    FitOf(ViewOf(set, c.fit), g.mutable_fit());
  }
}

// The withheld gap before / after the named effects, in total and per case.
void GapOf(const BenchDiagnosis& d, proto::DiagnosisGap* o) {
  const RecordDiagnosis& rd = d.records;
  o->set_withheld_pi_before_deg2(rd.s0);
  o->set_withheld_pi_after_deg2(rd.withheld_after);
  o->set_withheld_floor_pi_deg2(rd.s_floor);
  o->set_closed(rd.closed_total);
  o->set_remaining_over_floor(std::sqrt(rd.withheld_after / rd.s_floor));
  for (size_t i = 0; i < rd.gaps.size(); ++i) {
    const diagnose::RecordGap& g = rd.gaps[i];
    proto::CaseGap& c = *o->add_cases();
    c.set_case_(d.cases[i].number);
    c.set_training(d.cases[i].training);
    c.set_floor_rms_deg(g.floor_rms);
    c.set_rms_before_deg(g.rms_before);
    c.set_rms_after_deg(g.rms_after);
    c.set_pi_before_deg2(g.pi_before);
    c.set_pi_after_deg2(g.pi_after);
    c.set_closed(g.closed);
  }
}

}  // namespace

void BenchGridOf(const BenchDiagnosis& d, proto::BenchGrid* out) {
  const RecordDiagnosis& rd = d.records;
  proto::BenchGrid m;
  proto::DiagnosisThresholds& t = *m.mutable_thresholds();
  t.set_significance_ratio(d.rules.significance_ratio);
  t.set_min_closed(d.rules.min_closed);
  t.set_min_pattern(d.rules.min_pattern);
  NoiseOf(d, m.mutable_noise());
  FitOf(ViewOf(d.set, rd.base), m.mutable_base());
  AnalysisOf(rd.base_residuals, m.mutable_base_residuals());
  for (const auto& x : rd.trends) TrendOf(x, m.add_trends());
  for (const RoundView& r : Rounds(rd)) RoundOf(d.set, r, m.add_rounds());
  m.set_absorbed_by(rd.absorbed_by);
  for (const auto& a : rd.absorbed) {
    proto::Absorption& g = *m.add_absorbed();
    g.set_name(a.name);
    g.set_unit(a.unit);
    g.set_without(a.without);
    g.set_with(a.with);
    g.set_z(a.z);
  }
  FitOf(ViewOf(d.set, *rd.final_fit), m.mutable_final());
  AnalysisOf(rd.final_residuals, m.mutable_final_residuals());
  GapOf(d, m.mutable_gap());
  m.set_wall_time_s(d.wall_time_s);
  m.set_evaluations(diagnose::BenchEvaluations(rd));
  *out = std::move(m);
}

// ---- report.md and figures ----------------------------------------------------------------------

namespace {

namespace fs = std::filesystem;

// Case c's trace (time, phase, drive, measured, both models, residuals, cycle) and residual spectra
// as CSV, and the scripts of its three figures (residual vs phase, spectrum, loop). The models'
// outputs are the records fits' (base and final) on the case's record.
void WriteCaseFigures(const fs::path& fig, const BenchDiagnosis& d, size_t c,
                      std::vector<fs::path>& scripts) {
  const RecordDiagnosis& rd = d.records;
  const std::string base_name = ViewOf(d.set, rd.base).description;
  const std::string final_name = ViewOf(d.set, *rd.final_fit).description;
  const bool has_final = final_name != base_name;
  const diagnose::BenchCase& dc = d.cases[c];
  const io::Record& r = d.set.records[c];
  const std::vector<double>& yb = rd.base.yhat[c];
  const std::vector<double>& yf = rd.final_fit->yhat[c];
  if (yb.size() < r.y.size() || yf.size() < r.y.size())
    throw InputError(r.Label() + ": the fits' outputs do not cover the record (a bug)");
  const std::string stem = "case" + std::to_string(dc.number);
  const fs::path trace = fig / (stem + "_trace.csv");
  {
    std::ofstream t(trace);
    t << "t_s,phase_deg,u_V,measured_deg,base_deg,final_deg,residual_base_deg,residual_final_deg,"
         "cycle\n";
    const double fs_hz = r.sinusoid.sample_rate_hz, f = dc.frequency_hz;
    const size_t p = r.y.size() / std::max(1L, std::lround(r.sinusoid.cycles));
    for (size_t k = 0; k < r.y.size(); ++k) {
      const double tk = k / fs_hz;
      const double ph = std::fmod(360.0 * f * tk, 360.0);
      t << io::FormatNumber(tk) << "," << io::FormatNumber(ph) << "," << io::FormatNumber(r.u[k])
        << "," << io::FormatNumber(r.y[k]) << "," << io::FormatNumber(yb[k]) << ","
        << io::FormatNumber(yf[k]) << "," << io::FormatNumber(r.y[k] - yb[k]) << ","
        << io::FormatNumber(r.y[k] - yf[k]) << "," << (p ? k / p + 1 : 1) << "\n";
    }
  }
  const fs::path spec = fig / (stem + "_spectrum.csv");
  {
    std::ofstream s(spec);
    s << "harmonic,base_deg,final_deg,noise_deg\n";
    const auto& rb = rd.base_residuals.cases[c];
    const auto& rf = rd.final_residuals.cases[c];
    for (int k = 0; k <= model::kHarmonics; ++k)
      s << k << "," << io::FormatNumber(rb.harmonic[k]) << "," << io::FormatNumber(rf.harmonic[k])
        << "," << io::FormatNumber(rb.harmonic_noise) << "\n";
  }
  const std::string label = " (case " + std::to_string(dc.number) + ", " +
                            F("%.0f V", dc.amplitude_v) + ", " + F("%.3g Hz", dc.frequency_hz) +
                            (dc.training ? ", training)" : ", withheld)");
  Plot ph{stem + "_phase",
          "Residual vs drive phase" + label,
          "drive phase [deg]",
          "measured - model [deg]",
          false,
          {}};
  ph.series.push_back({trace.filename().string(), 2, 7, "base model", "points pt 7 ps 0.4"});
  if (has_final)
    ph.series.push_back({trace.filename().string(), 2, 8, final_name, "points pt 7 ps 0.4"});
  Plot sp{stem + "_spectrum",
          "Residual spectrum, later cycles" + label,
          "harmonic of the drive frequency",
          "amplitude [deg]",
          false,
          {}};
  sp.series.push_back({spec.filename().string(), 1, 2, "base model", "linespoints pt 7"});
  if (has_final)
    sp.series.push_back({spec.filename().string(), 1, 3, final_name, "linespoints pt 7"});
  sp.series.push_back({spec.filename().string(), 1, 4, "noise level (one bin)", "lines dt 2"});
  Plot lp{stem + "_loop", "Loop" + label, "drive u [V]", "fin angle [deg]", false, {}};
  lp.series.push_back({trace.filename().string(), 3, 4, "measured", "points pt 7 ps 0.3"});
  lp.series.push_back({trace.filename().string(), 3, 5, "base model", "lines"});
  if (has_final) lp.series.push_back({trace.filename().string(), 3, 6, final_name, "lines"});
  for (const Plot& pl : {ph, sp, lp}) scripts.push_back(WritePlotScript(fig, pl));
}

// The noise floor per case and the V × f grid of each case's PI before / after.
void MdGrid(std::ostream& h, const BenchDiagnosis& d) {
  h << "\n## The V × f grid\n\nNoise floor: encoder quantum " << F("%.5g", d.quantum_deg)
    << " deg; floor " << F("%.4f", d.floor_train) << " deg (training), "
    << F("%.4f", d.floor_withheld)
    << " deg (withheld) RMS, from the quantisation, the scatter between the last two cycles and "
       "the rounding of the saturation plateaus of "
    << d.records.floor_model << ". A gap is significant when the withheld RMS exceeds "
    << F("%.2f", d.rules.significance_ratio) << " × the floor.\n\n";
  std::set<double> vs, fs_set;
  for (const auto& c : d.cases) {
    vs.insert(c.amplitude_v);
    fs_set.insert(c.frequency_hz);
  }
  const std::vector<double> V = Sorted(vs), Fr = Sorted(fs_set);
  h << "PI = Σ e² [deg²] per case, base model → "
    << Md(ViewOf(d.set, *d.records.final_fit).description)
    << "; RMS / floor in brackets; withheld cases in italics.\n\n| V \\ f |";
  for (double f : Fr) h << " " << F("%.3g Hz", f) << " |";
  h << "\n|---|";
  for (size_t i = 0; i < Fr.size(); ++i) h << "---|";
  h << "\n";
  for (double v : V) {
    h << "| " << F("%.0f V", v) << " |";
    for (double f : Fr) {
      int at = -1;  // the case at (v, f): the last one there
      for (size_t i = 0; i < d.cases.size() && i < d.records.gaps.size(); ++i)
        if (d.cases[i].amplitude_v == v && d.cases[i].frequency_hz == f) at = static_cast<int>(i);
      if (at < 0) {
        h << " |";
        continue;
      }
      const diagnose::BenchCase& c = d.cases[static_cast<size_t>(at)];
      const diagnose::RecordGap& g = d.records.gaps[static_cast<size_t>(at)];
      const double floor = std::max(g.floor_rms, 1e-12);
      const std::string i = c.training ? "" : "*";
      h << " " << i << "case " << c.number << ": " << F("%.3g", g.pi_before) << " → "
        << F("%.3g", g.pi_after) << " (" << F("%.1f", g.rms_before / floor) << " → "
        << F("%.1f", g.rms_after / floor) << ")" << i << " |";
    }
    h << "\n";
  }
  h << "\n| case | quantum [deg] | quantisation | scatter | floor | saturation-aware floor | b1 | "
       "b2 |\n|---|---|---|---|---|---|---|---|\n";
  for (size_t i = 0; i < d.cases.size(); ++i) {
    const auto& c = d.cases[i];
    h << "| " << c.number << " | " << F("%.5g", c.noise.quantum_deg) << " | "
      << F("%.4f", c.noise.quantisation_rms_deg) << " | " << F("%.4f", c.noise.scatter_rms_deg)
      << " | " << F("%.4f", c.noise.floor_rms_deg) << " | "
      << F("%.4f", i < d.records.gaps.size() ? d.records.gaps[i].floor_rms : NAN) << " | "
      << F("%.4f", c.b1) << " | " << F("%.4f", c.b2) << " |\n";
  }
}

// Where the base model's residual lies (the findings and the table per case) and the parameter
// trends of the per-case fits.
void MdLocalisation(std::ostream& h, const BenchDiagnosis& bd) {
  const RecordDiagnosis& d = bd.records;
  h << "\n### Localisation of the base model's residual\n\n";
  for (const auto& f : d.base_residuals.findings) h << "- " << f << "\n";
  h << "\n| case | role | floor | RMS | rising | falling | near reversals | in saturation | first "
       "cycle | later cycles | trend [deg/s] | odd harm. | even harm. | low freq. | lag "
       "meas./model [deg] | width meas./model [deg] |\n"
       "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& c : d.base_residuals.cases) {
    h << "| " << c.number << " | " << (c.training ? "training" : "withheld") << " | "
      << F("%.4f", c.floor_rms) << " | " << F("%.4f", c.rms) << " | " << F("%.4f", c.rising.rms)
      << " | " << F("%.4f", c.falling.rms) << " | " << F("%.4f", c.near_reversal.rms) << " | "
      << F("%.4f", c.in_saturation.rms) << " | " << F("%.4f", c.first_cycle.rms) << " | "
      << F("%.4f", c.later_cycles.rms) << " | " << F("%.2g", c.trend_deg_per_s) << " | "
      << F("%.4f", c.odd_rms) << " | " << F("%.4f", c.even_rms) << " | " << F("%.4f", c.low_rms)
      << " | " << F("%.2f", c.measured_loop.phase_lag_deg) << " / "
      << F("%.2f", c.model_loop.phase_lag_deg) << " | " << F("%.3f", c.measured_loop.width_deg)
      << " / " << F("%.3f", c.model_loop.width_deg) << " |\n";
  }
  if (d.trends.empty()) return;
  h << "\n### Parameter trends of per-case fits over the V × f grid\n\n| parameter |";
  for (const auto& c : bd.cases) h << " case " << c.number << " |";
  h << " p (V) | p (f) | trend |\n|---|";
  for (size_t i = 0; i < bd.cases.size() + 3; ++i) h << "---|";
  h << "\n";
  for (const auto& t : d.trends) {
    h << "| " << Md(t.name) << " |";
    for (double v : t.per_case) h << " " << F("%.4g", v) << " |";
    h << " " << F("%.2g", t.p_v) << " | " << F("%.2g", t.p_f) << " | "
      << (t.significant ? "**significant**" : "") << " |\n";
  }
}

// Each round's candidates, and what the base parameters absorbed.
void MdRounds(std::ostream& h, const BenchDiagnosis& bd) {
  const RecordDiagnosis& d = bd.records;
  const std::vector<RoundView> rounds = Rounds(d);
  for (size_t r = 0; r < rounds.size(); ++r) {
    const RoundView& rr = rounds[r];
    h << "\n### Round " << r + 1 << "\n\n"
      << *rr.verdict
      << "\n\n| candidate | added parameters | withheld RMS [deg] | score | closed | pattern | "
         "weight | parameters | notes |\n|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& c : *rr.candidates) {
      const FitView f = ViewOf(bd.set, c.fit);
      h << "| " << model::EffectName(c.kind) << " | " << AddedParams(c, rr) << " | "
        << F("%.4f", Rms(f.withheld_pi, f.withheld_samples)) << " | " << F("%.1f", c.score) << " | "
        << Pct(c.closed) << " | " << Pct(c.pattern) << " | " << F("%.3f", c.weight) << " | "
        << Md(EffectParams(c.fit)) << " | " << Md(c.qualifies ? "qualifies" : c.note) << " |\n";
    }
  }
  if (!d.absorbed.empty()) {
    h << "\nBase parameters that move when **" << d.absorbed_by << "** is added (|shift| > 2 σ): ";
    for (const auto& a : d.absorbed)
      h << a.name << " " << F("%.4g", a.without) << " → " << F("%.4g", a.with) << " " << a.unit
        << "; ";
    h << "\n";
  }
}

// The gap per case before / after and in total.
void MdHowFar(std::ostream& h, const BenchDiagnosis& bd) {
  const RecordDiagnosis& d = bd.records;
  h << "\n### How far\n\n| case | role | floor | RMS before | RMS after | closed |\n"
       "|---|---|---|---|---|---|\n";
  for (size_t i = 0; i < d.gaps.size(); ++i) {
    const diagnose::RecordGap& g = d.gaps[i];
    h << "| " << bd.cases[i].number << " | " << (bd.cases[i].training ? "training" : "withheld")
      << " | " << F("%.4f", g.floor_rms) << " | " << F("%.4f", g.rms_before) << " | "
      << F("%.4f", g.rms_after) << " | " << Pct(g.closed) << " |\n";
  }
  h << "\nWithheld total PI " << F("%.4f", d.s0) << " → " << F("%.4f", d.withheld_after)
    << " deg² (floor " << F("%.4f", d.s_floor) << "): " << Pct(d.closed_total)
    << " of the gap closed, " << F("%.2f", std::sqrt(d.withheld_after / d.s_floor))
    << " × floor remains.\n";
}

// A fit's parameters with σ, sensitivity and identifiability, and its weakest direction.
void MdParams(std::ostream& h, const FitView& f) {
  h << "\n| parameter | value | ± σ | sensitivity [deg] | identifiability |\n"
       "|---|---|---|---|---|\n";
  for (const auto& p : f.params())
    h << "| " << Md(p.name) << " [" << Md(p.unit) << "] | " << F("%.5g", p.value) << " | "
      << (std::isfinite(p.std_error) ? F("%.3g", p.std_error) : "—") << " | "
      << F("%.4f", p.sensitivity) << " | " << opt::IdentifiabilityName(p.identifiability)
      << (p.note.empty() ? "" : "; " + Md(p.note)) << " |\n";
  h << "\nWeakest direction: " << f.fit->uncertainty.weakest_direction << "\n";
}

// The identifiability tables, the figures of every case and the run's cost.
void MdTail(std::ostream& h, const BenchDiagnosis& d) {
  const FitView fin = ViewOf(d.set, *d.records.final_fit), base = ViewOf(d.set, d.records.base);
  h << "\n### Identifiability\n\n"
    << fin.description
    << ": σ from s²(JᵀJ)⁺ at the solution; sensitivity = RMS output change per typical step of the "
       "parameter.\n";
  MdParams(h, fin);
  if (fin.description != base.description) {
    h << "\nBase model:\n";
    MdParams(h, base);
  }
  h << "\n### Figures of the cases\n\n";
  for (const auto& c : d.cases) {
    const std::string stem = "figures/case" + std::to_string(c.number);
    h << "Case " << c.number << ": ![residual vs phase](" << stem
      << "_phase.png) ![residual spectrum](" << stem << "_spectrum.png) ![loop](" << stem
      << "_loop.png)\n\n";
  }
  h << F("%.1f", d.wall_time_s) << " s, " << diagnose::BenchEvaluations(d.records)
    << " model evaluations.\n";
}

}  // namespace

void WriteBenchGridMarkdown(std::ostream& out, const BenchDiagnosis& d) {
  MdGrid(out, d);
  MdLocalisation(out, d);
  out << "\n## The greedy rounds\n";
  MdRounds(out, d);
  MdHowFar(out, d);
  MdTail(out, d);
}

void WriteBenchGridFigures(const std::filesystem::path& figures, const BenchDiagnosis& d,
                           std::vector<std::filesystem::path>& scripts) {
  for (size_t c = 0; c < d.cases.size(); ++c) WriteCaseFigures(figures, d, c, scripts);
}

}  // namespace pz::reports
