#include "diagnose/fin_diagnose.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "io/fin_records.h"

namespace pz::diagnose {

using model::EffectKind;

Status DiagnoseOptions::Validate() const {
  if (threads < 1) return InvalidArgument(FieldError("threads", threads, "must be >= 1"));
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

// A records fit as the bench's: "base + effect", per-case PI, the uncertainty table.
FitResult FinFitOf(const io::RecordSet& set, const records::FitResult& f) {
  FitResult o;
  o.structure = f.model->effects();
  o.description = ParameterLayout(o.structure).Describe();
  o.x = f.params;
  o.params = f.uncertainty.params;
  for (size_t i = 0; i < set.records.size(); ++i) {
    const double pi = f.metrics[i].sse;
    o.case_pi.push_back(pi);
    const bool training = set.records[i].role == model::CaseRole::kTrain;
    (training ? o.train_pi : o.withheld_pi) += pi;
    (training ? o.train_samples : o.withheld_samples) += static_cast<int>(set.records[i].scored());
  }
  o.residual_sigma = f.uncertainty.residual_sigma;
  o.singular_values = f.uncertainty.singular_values;
  o.weakest_direction = f.uncertainty.weakest_direction;
  o.evaluations = f.evaluations + f.uncertainty.evaluations;
  o.wall_time_s = f.wall_time_s;
  o.message = f.polish_message;
  o.ok = true;
  return o;
}

CandidateResult FinCandidateOf(const io::RecordSet& set, const records::RecordCandidate& c,
                               const records::FitResult& start) {
  CandidateResult o;
  static_cast<records::CandidateScore&>(o) = c;
  o.kind = c.kind;
  o.fit = FinFitOf(set, c.fit);
  o.added_params = static_cast<int>(c.fit.params.size() - start.params.size());
  return o;
}

RoundResult FinRoundOf(const io::RecordSet& set, const records::FitResult& start,
                       const records::Gap& gap, const std::vector<records::RecordCandidate>& cands,
                       int named, int runner_up, double z_runner_up, const std::string& verdict) {
  RoundResult r;
  r.base_structure = start.model->effects();
  r.s0 = gap.s0;
  r.s_floor = gap.s_floor;
  r.rms_ratio = gap.rms_ratio;
  r.significant = gap.significant;
  for (const records::RecordCandidate& c : cands)
    r.candidates.push_back(FinCandidateOf(set, c, start));
  r.named = named;
  r.runner_up = runner_up;
  r.z_runner_up = z_runner_up;
  r.gap = gap;
  r.verdict = verdict;
  return r;
}

}  // namespace

Diagnosis DiagnosisOfRecords(const DiagnosisModel& m, const io::RecordSet& set,
                             const records::RecordDiagnosis& rd) {
  if (set.records.size() != m.cases().size())
    throw InputError("the bench's records: " + std::to_string(set.records.size()) +
                     " records for " + std::to_string(m.cases().size()) + " cases");
  Diagnosis d;
  d.cases = m.cases();
  for (const DiagCase& c : m.cases()) d.quantum_deg = std::max(d.quantum_deg, c.noise.quantum_deg);
  SetFloorTotals(m, rd.record_floor, d);
  d.floor_model = rd.floor_model;
  d.base = FinFitOf(set, rd.base);
  d.base_residuals = rd.base_residuals;
  d.trends = rd.trends;
  records::Gap gap;
  gap.s0 = rd.s0;
  gap.s_floor = rd.s_floor;
  gap.rms_ratio = rd.rms_ratio;
  gap.significant = rd.significant;
  gap.nw = static_cast<double>(rd.withheld_samples);
  gap.nt = static_cast<double>(rd.train_samples);
  d.rounds.push_back(FinRoundOf(set, rd.base, gap, rd.candidates, rd.named, rd.runner_up,
                                rd.z_runner_up, rd.round_verdict));
  if (rd.second) {
    const records::FitResult& start = rd.candidates[static_cast<size_t>(rd.named)].fit;
    d.rounds.push_back(FinRoundOf(set, start, rd.second->gap, rd.second->candidates,
                                  rd.second->named, rd.second->runner_up, rd.second->z_runner_up,
                                  rd.second->verdict));
  }
  d.named = rd.named_effects;
  d.confidence = rd.confidence;
  d.final_fit = FinFitOf(set, *rd.final_fit);
  d.final_residuals = rd.final_residuals;
  d.withheld_before = d.base.withheld_pi;
  d.withheld_after = d.final_fit.withheld_pi;
  d.closed_total = records::ClosedShare(d.withheld_before, d.withheld_after, d.withheld_floor);
  d.remaining_ratio = std::sqrt(d.withheld_after / d.withheld_floor);
  MeasureCaseGaps(m, rd.record_floor, d);
  d.absorbed = rd.absorbed;
  d.absorbed_by = rd.absorbed_by;
  d.verdict_kind = rd.verdict_kind;
  d.verdict = rd.verdict;
  d.evaluations = d.base.evaluations + rd.trend_evaluations;
  for (const RoundResult& r : d.rounds)
    for (const CandidateResult& c : r.candidates) d.evaluations += c.fit.evaluations;
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

Diagnosis DiagnoseBench(const DiagnosisModel& m, const DiagnoseOptions& o) {
  ThrowIfError(o.Validate());
  const auto start = std::chrono::steady_clock::now();
  const io::RecordSet set = RecordsOfCases(m.cases());
  Diagnosis d = DiagnosisOfRecords(m, set, records::DiagnoseRecords(set, RecordOptionsOf(o)));
  d.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return d;
}

}  // namespace pz::diagnose
