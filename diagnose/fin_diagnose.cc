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
  for (model::EffectKind k : candidates)
    if (!records::IsFinEffect(k))
      return InvalidArgument(
          FieldError("candidates[]", std::string(k.name()), "not an effect of the fin bench"));
  return Status::Ok();
}

RecordDiagnoseOptions RecordOptionsOf(const DiagnoseOptions& o) {
  RecordDiagnoseOptions r = FinBenchOptions();
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

int64_t FitEvaluations(const records::FitResult& f) {
  return f.evaluations + f.uncertainty.evaluations;
}

int64_t BenchEvaluations(const RecordDiagnosis& d) {
  int64_t n = FitEvaluations(d.base) + d.trend_evaluations;
  for (const RecordCandidate& c : d.candidates) n += FitEvaluations(c.fit);
  if (d.second)
    for (const RecordCandidate& c : d.second->candidates) n += FitEvaluations(c.fit);
  return n;
}

BenchDiagnosis DiagnoseBench(const std::vector<DiagCase>& cases, const DiagnoseOptions& o) {
  ThrowIfError(o.Validate());
  const auto start = std::chrono::steady_clock::now();
  BenchDiagnosis d;
  d.set = RecordsOfCases(cases);
  d.records = DiagnoseRecords(d.set, RecordOptionsOf(o));
  // The grid's facts: each case's place, noise and saturations, and the floors pooled by role.
  double st = 0, sw = 0;
  int nt = 0, nw = 0;
  for (size_t c = 0; c < cases.size(); ++c) {
    const DiagCase& dc = cases[c];
    (dc.training ? nt : nw) += static_cast<int>(dc.measured_deg.size());
    d.cases.push_back({dc.number, dc.training, dc.drive.amplitude_v, dc.drive.frequency_hz,
                       dc.noise, dc.b1, dc.b2});
    d.quantum_deg = std::max(d.quantum_deg, dc.noise.quantum_deg);
    const double f = d.records.record_floor[c];
    (dc.training ? st : sw) += f * f * dc.measured_deg.size();
  }
  d.floor_train = std::sqrt(st / std::max(1, nt));
  d.floor_withheld = std::sqrt(sw / std::max(1, nw));
  d.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return d;
}

}  // namespace pz::diagnose
