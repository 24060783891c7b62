#include "diagnose/fin_diagnose.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "model/saturation.h"

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

BenchCase GridCaseOf(const io::Record& r) {
  const io::Record::StatedSinusoid& s = r.sinusoid;
  if (!s.stated())
    throw InputError(r.Label() + ": states no sinusoid (a fin bench's case number, V, f, cycles " +
                     "and fs: io/fin_records.h), which the bench's V × f grid needs");
  const model::SaturationPair sat = [&] {
    try {
      return model::SaturationFromExtremes(r.y);
    } catch (const InputError& e) {
      throw InputError(r.Label() + ": " + e.what());
    }
  }();
  return {s.case_number,
          r.role == model::CaseRole::kTrain,
          s.amplitude_v,
          s.frequency_hz,
          records::EstimateCaseNoise(r.y, std::max(1, static_cast<int>(std::lround(s.cycles)))),
          sat.b1,
          sat.b2};
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

BenchDiagnosis DiagnoseBench(const io::RecordSet& set, const DiagnoseOptions& o) {
  ThrowIfError(o.Validate());
  const auto start = std::chrono::steady_clock::now();
  BenchDiagnosis d;
  d.bench = set.source.string();
  d.set = set;
  d.rules = o.rules;
  for (const io::Record& r : set.records) d.cases.push_back(GridCaseOf(r));
  d.records = DiagnoseRecords(d.set, RecordOptionsOf(o));
  // The floors pooled by role, and the largest encoder quantum of the cases.
  double st = 0, sw = 0;
  int nt = 0, nw = 0;
  for (size_t c = 0; c < d.cases.size(); ++c) {
    const BenchCase& bc = d.cases[c];
    const int n = static_cast<int>(set.records[c].y.size());
    (bc.training ? nt : nw) += n;
    d.quantum_deg = std::max(d.quantum_deg, bc.noise.quantum_deg);
    const double f = d.records.record_floor[c];
    (bc.training ? st : sw) += f * f * n;
  }
  d.floor_train = std::sqrt(st / std::max(1, nt));
  d.floor_withheld = std::sqrt(sw / std::max(1, nw));
  d.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return d;
}

}  // namespace pz::diagnose
