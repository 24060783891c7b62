#include "service/wire_codec.h"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/util/json_util.h>

#include <cmath>
#include <cstdio>

#include <zlib.h>

#include "job.pb.h"
#include "network.pb.h"
#include "wire.pb.h"

namespace pz::service {

using job::CaseRole;
using job::CompleteModelProblem;
using job::CompleteModelRecord;
using job::DiagnoseParamBox;
using job::DiagnoseProblem;
using job::ExternalSettings;
using job::FieldViolation;
using job::GaSettings;
using job::HgannCaseSpec;
using job::HgannProblem;
using job::JobSpec;
using job::ParameterRange;
using job::SyntheticProblem;
using opt::FitnessResult;
using opt::FitnessStatus;
using opt::GaState;
using opt::Genome;
using opt::RngState;
namespace pw = ::pz::wire;
namespace {

constexpr uint32_t kCheckpointVersion = 1;
constexpr uint32_t kMaxGenomeBits = 1u << 20;

Status Malformed(const std::string& what) { return {StatusCode::kDataLoss, what}; }

std::string Deterministic(const google::protobuf::MessageLite& msg) {
  std::string out;
  {
    google::protobuf::io::StringOutputStream sos(&out);
    google::protobuf::io::CodedOutputStream cos(&sos);
    cos.SetSerializationDeterministic(true);
    msg.SerializeToCodedStream(&cos);
  }
  return out;
}

bool Parse(std::string_view bytes, google::protobuf::MessageLite* msg) {
  if (bytes.size() > static_cast<size_t>(INT32_MAX)) return false;
  return msg->ParseFromArray(bytes.data(), static_cast<int>(bytes.size()));
}

// ---------------------------------------------------------------- genomes and results

void ToProto(const Genome& g, pw::Genome* p) {
  std::string packed((g.bits.size() + 7) / 8, '\0');
  for (size_t i = 0; i < g.bits.size(); ++i)
    if (g.bits[i]) packed[i / 8] = static_cast<char>(packed[i / 8] | (1u << (i % 8)));
  p->set_bits(std::move(packed));
  p->set_bit_count(static_cast<uint32_t>(g.bits.size()));
  p->mutable_reals()->Assign(g.reals.begin(), g.reals.end());
}

Status FromProto(const pw::Genome& p, Genome* g) {
  if (p.bit_count() > kMaxGenomeBits) return Malformed("genome.bit_count too large");
  if (p.bits().size() != (p.bit_count() + 7) / 8)
    return Malformed("genome.bits has " + std::to_string(p.bits().size()) + " bytes for " +
                     std::to_string(p.bit_count()) + " bits");
  g->bits.resize(p.bit_count());
  for (uint32_t i = 0; i < p.bit_count(); ++i)
    g->bits[i] = (static_cast<uint8_t>(p.bits()[i / 8]) >> (i % 8)) & 1u;
  g->reals.assign(p.reals().begin(), p.reals().end());
  return Status::Ok();
}

pw::FitnessCode ToProto(FitnessStatus s) {
  switch (s) {
    case FitnessStatus::kOk: return pw::FITNESS_OK;
    case FitnessStatus::kPenalized: return pw::FITNESS_PENALIZED;
    case FitnessStatus::kError: return pw::FITNESS_ERROR;
  }
  return pw::FITNESS_UNSPECIFIED;
}

Status FromProto(pw::FitnessCode c, double cost, FitnessStatus* s) {
  switch (c) {
    case pw::FITNESS_OK: *s = FitnessStatus::kOk; break;
    case pw::FITNESS_PENALIZED: *s = FitnessStatus::kPenalized; break;
    case pw::FITNESS_ERROR:
    case pw::FITNESS_QUARANTINED: *s = FitnessStatus::kError; break;
    default: return Malformed("fitness code unspecified");
  }
  if (!std::isfinite(cost)) return Malformed("cost is not finite");
  return Status::Ok();
}

void ToProto(const FitnessResult& r, int index, pw::TaskResult* t) {
  t->set_index(index);
  t->set_cost(r.cost);
  t->set_code(ToProto(r.status));
  t->set_reason(r.reason);
  if (!r.residuals.empty()) t->mutable_residuals()->Assign(r.residuals.begin(), r.residuals.end());
}

Status FromProto(const pw::TaskResult& t, FitnessResult* r) {
  r->cost = t.cost();
  r->reason = t.reason();
  r->residuals.assign(t.residuals().begin(), t.residuals().end());
  return FromProto(t.code(), t.cost(), &r->status);
}

void ToProto(const ScoredGenome& s, pw::Individual* p) {
  ToProto(s.genome, p->mutable_genome());
  p->set_cost(s.fitness.cost);
  p->set_code(ToProto(s.fitness.status));
  p->set_reason(s.fitness.reason);
  p->set_index(s.index);
}

Status FromProto(const pw::Individual& p, ScoredGenome* s) {
  s->index = p.index();
  s->fitness.cost = p.cost();
  s->fitness.reason = p.reason();
  if (Status st = FromProto(p.code(), p.cost(), &s->fitness.status); !st.ok()) return st;
  return FromProto(p.genome(), &s->genome);
}

void ToProto(const GenerationRecord& r, pw::GenerationRecord* p) {
  p->set_generation(r.generation);
  p->set_best_cost(r.best_cost);
  p->set_mean_cost(r.mean_cost);
  p->set_evaluations(r.evaluations);
  p->set_errors(r.errors);
  p->set_quarantined(r.quarantined);
  p->set_worst_cost(r.worst_cost);
  p->set_stall(r.stall);
  p->set_evaluated(r.evaluated);
  p->set_penalized(r.penalized);
  for (const auto& [k, n] : r.failure_reasons) (*p->mutable_failure_reasons())[k] = n;
  p->set_best_description(r.best_description);
  p->set_wall_time_s(r.wall_time_s);
  p->set_improved(r.improved);
}

GenerationRecord FromProto(const pw::GenerationRecord& p) {
  GenerationRecord r;
  r.generation = p.generation();
  r.best_cost = p.best_cost();
  r.mean_cost = p.mean_cost();
  r.evaluations = p.evaluations();
  r.errors = p.errors();
  r.quarantined = p.quarantined();
  r.worst_cost = p.worst_cost();
  r.stall = p.stall();
  r.evaluated = p.evaluated();
  r.penalized = p.penalized();
  for (const auto& [k, n] : p.failure_reasons()) r.failure_reasons[k] = n;
  r.best_description = p.best_description();
  r.wall_time_s = p.wall_time_s();
  r.improved = p.improved();
  return r;
}

void ToProto(const QuarantineRecord& q, pw::QuarantineRecord* p) {
  p->set_generation(q.generation);
  p->set_index(q.index);
  p->set_strikes(q.strikes);
}

QuarantineRecord FromProto(const pw::QuarantineRecord& p) {
  return {p.generation(), p.index(), p.strikes()};
}

template <typename Domain, typename ProtoList>
Status IndividualsFromProto(const ProtoList& list, std::vector<Domain>* out) {
  out->resize(list.size());
  for (int i = 0; i < list.size(); ++i)
    if (Status s = FromProto(list[i], &(*out)[i]); !s.ok()) return s;
  return Status::Ok();
}

bool ValidState(int s) { return pw::JobState_IsValid(s); }

// ---------------------------------------------------------------- job specs

int ClampInt(uint64_t v) { return v > 0x7fffffffu ? 0x7fffffff : static_cast<int>(v); }

void CaseToProto(const HgannCaseSpec& c, pw::HgannCase* pc) {
  pc->set_number(static_cast<uint32_t>(std::max(0, c.number)));
  pc->set_amplitude_v(c.amplitude_v);
  pc->set_frequency_hz(c.frequency_hz);
  pc->set_role(static_cast<pw::CaseRole>(c.role));
  pc->set_sample_rate_hz(c.sample_rate_hz);
  pc->mutable_angle_deg()->Assign(c.angle_deg.begin(), c.angle_deg.end());
  pc->mutable_voltage_v()->Assign(c.voltage_v.begin(), c.voltage_v.end());
  if (c.b1) pc->set_b1(*c.b1);
  if (c.b2) pc->set_b2(*c.b2);
}

/// `field` names the case in violations ("hgann.cases[3]").
HgannCaseSpec CaseFromProto(const pw::HgannCase& pc, const std::string& field, std::vector<FieldViolation>* v) {
  HgannCaseSpec c;
  c.number = ClampInt(pc.number());
  c.amplitude_v = pc.amplitude_v();
  c.frequency_hz = pc.frequency_hz();
  if (pw::CaseRole_IsValid(pc.role())) {
    c.role = static_cast<CaseRole>(pc.role());
  } else if (v) {
    const std::string f = field + ".role";
    v->push_back({f, f + " = " + std::to_string(pc.role()) +
                         ": must be CASE_ROLE_TRAIN, CASE_ROLE_VALIDATE or CASE_ROLE_TEST"});
  }
  c.sample_rate_hz = pc.sample_rate_hz();
  c.angle_deg.assign(pc.angle_deg().begin(), pc.angle_deg().end());
  c.voltage_v.assign(pc.voltage_v().begin(), pc.voltage_v().end());
  if (pc.has_b1()) c.b1 = pc.b1();
  if (pc.has_b2()) c.b2 = pc.b2();
  return c;
}

void ToProto(const JobSpec& s, pw::JobSpec* p) {
  p->set_version(s.version);
  p->set_name(s.name);
  p->set_seed(s.seed);
  auto* l = p->mutable_limits();
  l->set_task_timeout_s(s.limits.task_timeout_s);
  l->set_quarantine_after(static_cast<uint32_t>(s.limits.quarantine_after));
  l->set_penalty_cost(s.limits.penalty_cost);
  if (s.limits.target_cost) l->set_target_cost(*s.limits.target_cost);
  if (const auto* h = std::get_if<HgannProblem>(&s.problem)) {
    auto* ph = p->mutable_hgann();
    for (const HgannCaseSpec& c : h->cases) CaseToProto(c, ph->add_cases());
    ph->set_case_set_dir(h->case_set_dir);
    ph->set_source(h->source);
    ph->set_ranges_preset(h->ranges_preset);
    for (const ParameterRange& r : h->ranges) {
      auto* pr = ph->add_ranges();
      pr->set_name(r.name);
      pr->set_min(r.min);
      pr->set_max(r.max);
    }
    ph->set_spread_penalty(h->spread_penalty);
    ph->set_saturation(h->saturation == HgannProblem::Saturation::kGiven
                           ? pw::SATURATION_GIVEN
                           : pw::SATURATION_FROM_EXTREMES);
    if (!h->geometry.empty()) {
      auto* g = ph->mutable_geometry();
      const auto* d = g->GetDescriptor();
      const auto* refl = g->GetReflection();
      for (const auto& [name, value] : h->geometry) {
        const auto* f = d->FindFieldByName(name);
        if (!f) continue;  // unknown names are refused by validation before they are encoded
        if (f->cpp_type() == google::protobuf::FieldDescriptor::CPPTYPE_DOUBLE)
          refl->SetDouble(g, f, value);
        else
          refl->SetUInt32(g, f, value >= 0 && value <= 4294967295.0 ? static_cast<uint32_t>(value) : 0u);
      }
    }
  } else if (const auto* d = std::get_if<DiagnoseProblem>(&s.problem)) {
    auto* pd = p->mutable_diagnose();
    for (const HgannCaseSpec& c : d->cases) CaseToProto(c, pd->add_cases());
    pd->mutable_cycles()->Assign(d->cycles.begin(), d->cycles.end());
    for (const auto& e : d->structure) pd->add_structure(e);
    for (const DiagnoseParamBox& b : d->params) {
      auto* pp = pd->add_params();
      pp->set_name(b.name);
      pp->set_lower(b.lower);
      pp->set_upper(b.upper);
      pp->set_log_scale(b.log_scale);
      pp->set_ratio(b.ratio);
    }
    pd->set_residuals(d->residuals);
    pd->set_oversample(static_cast<uint32_t>(std::max(0, d->oversample)));
    pd->set_rtol(d->rtol);
    pd->set_atol(d->atol);
    pd->set_max_steps(static_cast<uint64_t>(std::max<int64_t>(0, d->max_steps)));
    pd->set_force_cvode(d->force_cvode);
    pd->set_source(d->source);
  } else if (const auto* m = std::get_if<CompleteModelProblem>(&s.problem)) {
    auto* pm = p->mutable_complete_model();
    pm->set_family(static_cast<pw::CompleteModelFamily>(m->family));
    for (const CompleteModelRecord& r : m->records) {
      auto* pr = pm->add_records();
      pr->set_name(r.name);
      pr->set_sample_rate_hz(r.sample_rate_hz);
      pr->mutable_input()->Assign(r.input.begin(), r.input.end());
      pr->mutable_output()->Assign(r.output.begin(), r.output.end());
      pr->set_first_counted(r.first_counted);
    }
    pm->set_criterion(static_cast<pw::CompleteModelCriterion>(m->criterion));
    pm->set_t0_s(m->t0_s);
    pm->set_t1_s(m->t1_s);
    pm->set_substeps(static_cast<uint32_t>(std::max(0, m->substeps)));
    pm->set_interpolation(static_cast<pw::BwInterpolation>(m->interpolation));
    pm->set_period_samples(m->period_samples);
    pm->set_error_cost(m->error_cost);
    pm->set_source(m->source);
  } else if (const auto* y = std::get_if<SyntheticProblem>(&s.problem)) {
    auto* py = p->mutable_synthetic();
    py->set_cost(y->cost == SyntheticProblem::Cost::kNull ? pw::SyntheticProblem::COST_NULL
                                                          : pw::SyntheticProblem::COST_FUNCTION);
    py->set_genome_bits(static_cast<uint32_t>(y->genome_bits));
    py->set_sleep_ms(y->sleep_ms);
    py->set_crash_prefix(y->crash_prefix);
  }
  if (s.ga) {
    auto* g = p->mutable_ga();
    g->set_population(static_cast<uint32_t>(s.ga->population));
    g->set_elite_fraction(s.ga->elite_fraction);
    g->set_tournament(static_cast<uint32_t>(s.ga->tournament));
    g->set_crossover_probability(s.ga->crossover_probability);
    g->set_mutation_probability(s.ga->mutation_probability);
    g->set_generations(static_cast<uint32_t>(s.ga->generations));
    g->set_stall_generations(static_cast<uint32_t>(s.ga->stall_generations));
  }
  if (s.external) {
    auto* e = p->mutable_external();
    e->set_idle_timeout_s(s.external->idle_timeout_s);
    e->set_owner(s.external->owner);
  }
}

template <typename T>
T OrDefault(T v, T def) { return v == T{} ? def : v; }

void FromProto(const pw::JobSpec& p, JobSpec* s, std::vector<FieldViolation>* v) {
  *s = JobSpec{};
  s->version = p.version();
  s->name = p.name();
  s->seed = p.seed();
  s->limits.task_timeout_s = OrDefault(p.limits().task_timeout_s(), 60.0);
  s->limits.quarantine_after = ClampInt(OrDefault<uint32_t>(p.limits().quarantine_after(), 3));
  s->limits.penalty_cost = OrDefault(p.limits().penalty_cost(), 1e9);
  if (p.limits().has_target_cost()) s->limits.target_cost = p.limits().target_cost();
  if (p.has_hgann()) {
    const auto& ph = p.hgann();
    HgannProblem h;
    for (int i = 0; i < ph.cases_size(); ++i)
      h.cases.push_back(CaseFromProto(ph.cases(i), "hgann.cases[" + std::to_string(i) + "]", v));
    h.case_set_dir = ph.case_set_dir();
    h.source = ph.source();
    h.ranges_preset = ph.ranges_preset();
    for (const auto& pr : ph.ranges()) h.ranges.push_back({pr.name(), pr.min(), pr.max()});
    h.spread_penalty = ph.spread_penalty();
    switch (ph.saturation()) {
      case pw::SATURATION_UNSPECIFIED:
      case pw::SATURATION_FROM_EXTREMES: h.saturation = HgannProblem::Saturation::kFromExtremes; break;
      case pw::SATURATION_GIVEN: h.saturation = HgannProblem::Saturation::kGiven; break;
      default:
        if (v) v->push_back({"hgann.saturation", "hgann.saturation = " + std::to_string(ph.saturation()) +
                                                     ": must be SATURATION_FROM_EXTREMES or SATURATION_GIVEN"});
    }
    if (ph.has_geometry()) {
      const auto& g = ph.geometry();
      const auto* d = g.GetDescriptor();
      const auto* refl = g.GetReflection();
      for (int i = 0; i < d->field_count(); ++i) {
        const auto* f = d->field(i);
        if (!refl->HasField(g, f)) continue;
        h.geometry[f->name()] = f->cpp_type() == google::protobuf::FieldDescriptor::CPPTYPE_DOUBLE
                                    ? refl->GetDouble(g, f)
                                    : static_cast<double>(refl->GetUInt32(g, f));
      }
    }
    s->problem = std::move(h);
  } else if (p.has_synthetic()) {
    const auto& py = p.synthetic();
    SyntheticProblem y;
    switch (py.cost()) {
      case pw::SyntheticProblem::COST_NULL: y.cost = SyntheticProblem::Cost::kNull; break;
      case pw::SyntheticProblem::COST_FUNCTION: y.cost = SyntheticProblem::Cost::kFunction; break;
      default:
        if (v) v->push_back({"synthetic.cost", "synthetic.cost = " + std::to_string(py.cost()) +
                                                   ": must be COST_NULL or COST_FUNCTION"});
    }
    y.genome_bits = ClampInt(OrDefault<uint32_t>(py.genome_bits(), 64));
    y.sleep_ms = py.sleep_ms();
    y.crash_prefix = py.crash_prefix();
    s->problem = std::move(y);
  } else if (p.has_diagnose()) {
    const auto& pd = p.diagnose();
    DiagnoseProblem d;
    for (int i = 0; i < pd.cases_size(); ++i)
      d.cases.push_back(CaseFromProto(pd.cases(i), "diagnose.cases[" + std::to_string(i) + "]", v));
    d.cycles.assign(pd.cycles().begin(), pd.cycles().end());
    d.structure.assign(pd.structure().begin(), pd.structure().end());
    for (const auto& pp : pd.params())
      d.params.push_back({pp.name(), pp.lower(), pp.upper(), pp.log_scale(), pp.ratio()});
    d.residuals = pd.residuals();
    d.oversample = ClampInt(OrDefault<uint32_t>(pd.oversample(), 4));
    d.rtol = OrDefault(pd.rtol(), 1e-6);
    d.atol = OrDefault(pd.atol(), 1e-13);
    d.max_steps = static_cast<int64_t>(std::min<uint64_t>(OrDefault<uint64_t>(pd.max_steps(), 5000000), INT64_MAX));
    d.force_cvode = pd.force_cvode();
    d.source = pd.source();
    s->problem = std::move(d);
  } else if (p.has_complete_model()) {
    const auto& pm = p.complete_model();
    CompleteModelProblem m;
    auto bad_enum = [&](const char* field, int value, const char* known) {
      if (v) v->push_back({field, std::string(field) + " = " + std::to_string(value) + ": must be " + known});
    };
    if (pm.family() >= 0 && pm.family() <= 3)
      m.family = static_cast<CompleteModelProblem::Family>(pm.family());
    else
      bad_enum("complete_model.family", pm.family(), "BW_OSCILLATOR, STACK_BOUC_WEN or STACK_BACKLASH_LIKE");
    for (const auto& pr : pm.records()) {
      CompleteModelRecord r;
      r.name = pr.name();
      r.sample_rate_hz = pr.sample_rate_hz();
      r.input.assign(pr.input().begin(), pr.input().end());
      r.output.assign(pr.output().begin(), pr.output().end());
      r.first_counted = pr.first_counted();
      m.records.push_back(std::move(r));
    }
    if (pm.criterion() >= 0 && pm.criterion() <= 4)
      m.criterion = static_cast<CompleteModelProblem::Criterion>(std::max(1, static_cast<int>(pm.criterion())));
    else
      bad_enum("complete_model.criterion", pm.criterion(), "IAE, SSE, RMSE or MAX");
    m.t0_s = pm.t0_s();
    m.t1_s = pm.t1_s();
    m.substeps = ClampInt(pm.substeps());
    if (pm.interpolation() >= 0 && pm.interpolation() <= 4)
      m.interpolation = pm.interpolation() == 0 ? CompleteModelProblem::Interpolation::kSpline
                                                : static_cast<CompleteModelProblem::Interpolation>(pm.interpolation());
    else
      bad_enum("complete_model.interpolation", pm.interpolation(), "ZOH, LINEAR, SPLINE or FOURIER");
    m.period_samples = pm.period_samples();
    m.error_cost = OrDefault(pm.error_cost(), 1e30);
    m.source = pm.source();
    s->problem = std::move(m);
  }
  if (p.has_ga()) {
    const auto& pg = p.ga();
    GaSettings g;
    g.population = ClampInt(OrDefault<uint32_t>(pg.population(), 400));
    if (pg.has_elite_fraction()) g.elite_fraction = pg.elite_fraction();
    g.tournament = ClampInt(OrDefault<uint32_t>(pg.tournament(), 2));
    if (pg.has_crossover_probability()) g.crossover_probability = pg.crossover_probability();
    if (pg.has_mutation_probability()) g.mutation_probability = pg.mutation_probability();
    if (pg.has_generations()) g.generations = ClampInt(pg.generations());
    if (pg.has_stall_generations()) g.stall_generations = ClampInt(pg.stall_generations());
    s->ga = g;
  } else if (p.has_external()) {
    ExternalSettings e;
    e.idle_timeout_s = OrDefault(p.external().idle_timeout_s(), 120.0);
    e.owner = p.external().owner();
    s->external = e;
  }
}

// ---------------------------------------------------------------- worker protocol

void BatchToProto(const TaskBatchMsg& b, pw::TaskBatch* p) {
  p->set_lease_id(b.lease_id);
  p->set_job_id(b.job_id);
  p->set_generation(b.generation);
  p->set_context_hash(b.context_hash);
  p->set_deadline_s(b.deadline_s);
  for (size_t i = 0; i < b.indices.size(); ++i) {
    auto* t = p->add_tasks();
    t->set_index(b.indices[i]);
    ToProto(b.genomes[i], t->mutable_genome());
  }
}

Status BatchFromProto(const pw::TaskBatch& p, TaskBatchMsg* b) {
  b->lease_id = p.lease_id();
  b->job_id = p.job_id();
  b->generation = p.generation();
  b->context_hash = p.context_hash();
  b->deadline_s = p.deadline_s();
  b->indices.resize(p.tasks_size());
  b->genomes.resize(p.tasks_size());
  for (int i = 0; i < p.tasks_size(); ++i) {
    b->indices[i] = p.tasks(i).index();
    if (Status s = FromProto(p.tasks(i).genome(), &b->genomes[i]); !s.ok()) return s;
  }
  return Status::Ok();
}

void ResultToProto(const BatchResultMsg& r, pw::BatchResult* p) {
  p->set_lease_id(r.lease_id);
  p->set_job_id(r.job_id);
  p->set_generation(r.generation);
  p->set_code(static_cast<pw::Code>(r.code));
  p->set_error(r.error);
  p->set_eval_seconds(r.eval_seconds);
  for (size_t i = 0; i < r.indices.size(); ++i) ToProto(r.results[i], r.indices[i], p->add_results());
}

Status CodeFromProto(int c, WireCode* out) {
  if (!pw::Code_IsValid(c) || c == 0) return Malformed("code unspecified or unknown");
  *out = static_cast<WireCode>(c);
  return Status::Ok();
}

Status ResultFromProto(const pw::BatchResult& p, BatchResultMsg* r) {
  r->lease_id = p.lease_id();
  r->job_id = p.job_id();
  r->generation = p.generation();
  r->error = p.error();
  r->eval_seconds = p.eval_seconds();
  if (Status s = CodeFromProto(p.code(), &r->code); !s.ok()) return s;
  r->indices.resize(p.results_size());
  r->results.resize(p.results_size());
  for (int i = 0; i < p.results_size(); ++i) {
    const auto& t = p.results(i);
    r->indices[i] = t.index();
    if (Status s = FromProto(t, &r->results[i]); !s.ok()) return s;
  }
  return Status::Ok();
}

Status VersionCheck(uint32_t got) {
  if (got == kProtocolVersion) return Status::Ok();
  return {StatusCode::kFailedPrecondition, "protocol version " + std::to_string(got) +
                                               " (this side speaks " +
                                               std::to_string(kProtocolVersion) + ")"};
}

// ---------------------------------------------------------------- client protocol

void InfoToProto(const JobInfo& i, pw::JobInfo* p) {
  p->set_job_id(i.job_id);
  p->set_name(i.name);
  p->set_kind(i.kind);
  p->set_state(static_cast<pw::JobState>(i.state));
  p->set_generation(i.generation);
  p->set_max_generations(i.max_generations);
  p->set_best_cost(i.best_cost);
  p->set_evaluations(i.evaluations);
  p->set_message(i.message);
  for (const auto& q : i.quarantined) ToProto(q, p->add_quarantined());
  p->set_elapsed_s(i.elapsed_s);
  p->set_seed(i.seed);
  p->set_algorithm(i.algorithm);
  p->set_notice(i.notice);
  p->set_storage_error(i.storage_error);
  p->set_storage_error_since_unix_s(i.storage_error_since_unix_s);
  p->set_archived(i.archived);
  p->set_ended_unix_s(i.ended_unix_s);
}

Status InfoFromProto(const pw::JobInfo& p, JobInfo* i) {
  if (!ValidState(p.state())) return Malformed("job state unknown");
  i->job_id = p.job_id();
  i->name = p.name();
  i->kind = p.kind();
  i->state = static_cast<JobState>(p.state());
  i->generation = p.generation();
  i->max_generations = p.max_generations();
  i->best_cost = p.best_cost();
  i->evaluations = p.evaluations();
  i->message = p.message();
  i->quarantined.clear();
  for (const auto& q : p.quarantined()) i->quarantined.push_back(FromProto(q));
  i->elapsed_s = p.elapsed_s();
  i->seed = p.seed();
  i->algorithm = p.algorithm();
  i->notice = p.notice();
  i->storage_error = p.storage_error();
  i->storage_error_since_unix_s = p.storage_error_since_unix_s();
  i->archived = p.archived();
  i->ended_unix_s = p.ended_unix_s();
  return Status::Ok();
}

}  // namespace

std::string ContentHash(std::string_view bytes) {
  uint64_t h = 0xcbf29ce484222325ull;
  for (unsigned char c : bytes) {
    h ^= c;
    h *= 0x100000001b3ull;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

WireCode DecodeFailureCode(const Status& s) {
  return s.code() == StatusCode::kFailedPrecondition ? WireCode::kVersionMismatch
                                                     : WireCode::kMalformed;
}

std::string BitString(const Genome& g) {
  std::string s(g.bits.size(), '0');
  for (size_t i = 0; i < g.bits.size(); ++i) s[i] = g.bits[i] ? '1' : '0';
  return s;
}

const char* WireCodeName(WireCode c) {
  return pw::Code_Name(static_cast<pw::Code>(c)).c_str();
}

const char* JobStateName(JobState s) {
  switch (s) {
    case JobState::kRunning: return "running";
    case JobState::kSucceeded: return "succeeded";
    case JobState::kFailed: return "failed";
    case JobState::kCancelled: return "cancelled";
    default: return "unspecified";
  }
}

std::string EncodeJobSpec(const JobSpec& spec) {
  pw::JobSpec p;
  ToProto(spec, &p);
  return Deterministic(p);
}

Status DecodeJobSpec(std::string_view bytes, JobSpec* spec, std::vector<FieldViolation>* v) {
  pw::JobSpec p;
  if (!Parse(bytes, &p)) return Malformed("job spec does not decode");
  FromProto(p, spec, v);
  return Status::Ok();
}

Status JobSpecFromJson(const std::string& json, JobSpec* spec, std::vector<FieldViolation>* v) {
  pw::JobSpec p;
  google::protobuf::util::JsonParseOptions opts;
  opts.ignore_unknown_fields = false;
  auto st = google::protobuf::util::JsonStringToMessage(json, &p, opts);
  if (!st.ok()) return InvalidArgument("job spec JSON: " + std::string(st.message()));
  FromProto(p, spec, v);
  return Status::Ok();
}

std::string JobSpecToJson(const JobSpec& spec) {
  pw::JobSpec p;
  ToProto(spec, &p);
  std::string out;
  google::protobuf::util::JsonPrintOptions opts;
  opts.add_whitespace = true;
  opts.preserve_proto_field_names = true;
  (void)google::protobuf::util::MessageToJsonString(p, &out, opts);
  return out;
}

std::string EncodeWorkerToMaster(const WorkerMsg& m) {
  pw::WorkerToMaster p;
  p.set_version(kProtocolVersion);
  switch (m.type) {
    case WorkerMsg::Type::kReady: {
      auto* r = p.mutable_ready();
      r->set_threads(static_cast<uint32_t>(m.threads));
      r->set_host(m.host);
      r->set_pid(m.pid);
      break;
    }
    case WorkerMsg::Type::kDisconnect: p.mutable_disconnect()->set_reason(m.reason); break;
    case WorkerMsg::Type::kContextRequest:
      p.mutable_context_request()->set_context_hash(m.context_hash);
      break;
    case WorkerMsg::Type::kResult: ResultToProto(m.result, p.mutable_result()); break;
    default: p.mutable_heartbeat(); break;
  }
  return p.SerializeAsString();
}

Status DecodeWorkerToMaster(std::string_view bytes, WorkerMsg* m) {
  pw::WorkerToMaster p;
  if (!Parse(bytes, &p)) return Malformed("worker message does not decode");
  if (Status s = VersionCheck(p.version()); !s.ok()) return s;
  *m = WorkerMsg{};
  switch (p.body_case()) {
    case pw::WorkerToMaster::kReady:
      m->type = WorkerMsg::Type::kReady;
      if (p.ready().threads() < 1 || p.ready().threads() > 4096)
        return Malformed("ready.threads must be in [1, 4096]");
      m->threads = static_cast<int>(p.ready().threads());
      m->host = p.ready().host();
      m->pid = p.ready().pid();
      return Status::Ok();
    case pw::WorkerToMaster::kHeartbeat: m->type = WorkerMsg::Type::kHeartbeat; return Status::Ok();
    case pw::WorkerToMaster::kDisconnect:
      m->type = WorkerMsg::Type::kDisconnect;
      m->reason = p.disconnect().reason();
      return Status::Ok();
    case pw::WorkerToMaster::kContextRequest:
      m->type = WorkerMsg::Type::kContextRequest;
      m->context_hash = p.context_request().context_hash();
      return Status::Ok();
    case pw::WorkerToMaster::kResult:
      m->type = WorkerMsg::Type::kResult;
      return ResultFromProto(p.result(), &m->result);
    default: return Malformed("worker message has no body");
  }
}

std::string EncodeMasterToWorker(const WorkerMsg& m) {
  pw::MasterToWorker p;
  p.set_version(kProtocolVersion);
  p.set_code(static_cast<pw::Code>(m.code));
  switch (m.type) {
    case WorkerMsg::Type::kBatch: BatchToProto(m.batch, p.mutable_batch()); break;
    case WorkerMsg::Type::kContext: {
      auto* c = p.mutable_context();
      c->set_context_hash(m.context_hash);
      c->set_spec(m.context_spec);
      c->set_code(static_cast<pw::Code>(m.code));
      break;
    }
    case WorkerMsg::Type::kDisconnect:
      p.mutable_disconnect()->set_reason(m.reason);
      p.set_error(m.reason);
      break;
    default: p.mutable_heartbeat(); break;
  }
  return p.SerializeAsString();
}

Status DecodeMasterToWorker(std::string_view bytes, WorkerMsg* m) {
  pw::MasterToWorker p;
  if (!Parse(bytes, &p)) return Malformed("master message does not decode");
  if (Status s = VersionCheck(p.version()); !s.ok()) return s;
  *m = WorkerMsg{};
  m->code = pw::Code_IsValid(p.code()) ? static_cast<WireCode>(p.code()) : WireCode::kUnspecified;
  switch (p.body_case()) {
    case pw::MasterToWorker::kBatch:
      m->type = WorkerMsg::Type::kBatch;
      return BatchFromProto(p.batch(), &m->batch);
    case pw::MasterToWorker::kContext:
      m->type = WorkerMsg::Type::kContext;
      m->context_hash = p.context().context_hash();
      m->context_spec = p.context().spec();
      m->code = pw::Code_IsValid(p.context().code()) ? static_cast<WireCode>(p.context().code())
                                                     : WireCode::kUnspecified;
      return Status::Ok();
    case pw::MasterToWorker::kHeartbeat: m->type = WorkerMsg::Type::kHeartbeat; return Status::Ok();
    case pw::MasterToWorker::kDisconnect:
      m->type = WorkerMsg::Type::kDisconnect;
      m->reason = p.disconnect().reason();
      return Status::Ok();
    default: return Malformed("master message has no body");
  }
}

std::string EncodeClientRequest(const ClientRequestMsg& m) {
  pw::ClientRequest p;
  p.set_version(kProtocolVersion);
  p.set_request_id(m.request_id);
  using T = ClientRequestMsg::Type;
  switch (m.type) {
    case T::kSubmit:
      ToProto(m.spec, p.mutable_submit()->mutable_spec());
      p.mutable_submit()->set_client_token(m.client_token);
      break;
    case T::kStatus: p.mutable_status()->set_job_id(m.job_id); break;
    case T::kWatch: p.mutable_watch()->set_job_id(m.job_id); break;
    case T::kCancel: p.mutable_cancel()->set_job_id(m.job_id); break;
    case T::kList: p.mutable_list(); break;
    case T::kFetch:
      p.mutable_fetch()->set_job_id(m.job_id);
      p.mutable_fetch()->set_count(static_cast<uint32_t>(std::max(0, m.count)));
      break;
    case T::kPing: p.mutable_ping(); break;
    case T::kEvaluate: {
      auto* e = p.mutable_evaluate();
      e->set_job_id(m.job_id);
      e->set_batch_seq(m.batch_seq);
      for (const Genome& g : m.genomes) ToProto(g, e->add_genomes());
      break;
    }
    case T::kClose: p.mutable_close()->set_job_id(m.job_id); break;
    case T::kPrune: {
      auto* q = p.mutable_prune();
      for (const auto& id : m.job_ids) q->add_job_ids(id);
      q->set_older_than_s(m.older_than_s);
      q->set_keep(m.keep);
      q->set_dry_run(m.dry_run);
      break;
    }
  }
  return p.SerializeAsString();
}

Status DecodeClientRequest(std::string_view bytes, ClientRequestMsg* m) {
  pw::ClientRequest p;
  if (!Parse(bytes, &p)) return Malformed("client request does not decode");
  *m = ClientRequestMsg{};
  m->request_id = p.request_id();
  if (Status s = VersionCheck(p.version()); !s.ok()) return s;
  using T = ClientRequestMsg::Type;
  switch (p.body_case()) {
    case pw::ClientRequest::kSubmit:
      m->type = T::kSubmit;
      FromProto(p.submit().spec(), &m->spec, &m->decode_violations);
      m->spec_bytes = EncodeJobSpec(m->spec);
      m->client_token = p.submit().client_token();
      break;
    case pw::ClientRequest::kStatus: m->type = T::kStatus; m->job_id = p.status().job_id(); break;
    case pw::ClientRequest::kWatch: m->type = T::kWatch; m->job_id = p.watch().job_id(); break;
    case pw::ClientRequest::kCancel: m->type = T::kCancel; m->job_id = p.cancel().job_id(); break;
    case pw::ClientRequest::kList: m->type = T::kList; break;
    case pw::ClientRequest::kFetch:
      m->type = T::kFetch;
      m->job_id = p.fetch().job_id();
      m->count = ClampInt(std::max<uint32_t>(1, p.fetch().count()));
      break;
    case pw::ClientRequest::kPing: m->type = T::kPing; break;
    case pw::ClientRequest::kEvaluate: {
      const auto& e = p.evaluate();
      m->type = T::kEvaluate;
      m->job_id = e.job_id();
      m->batch_seq = e.batch_seq();
      m->genomes.resize(e.genomes_size());
      for (int i = 0; i < e.genomes_size(); ++i)
        if (Status s = FromProto(e.genomes(i), &m->genomes[i]); !s.ok())
          return Malformed("evaluate.genomes[" + std::to_string(i) + "]: " + s.message());
      break;
    }
    case pw::ClientRequest::kClose: m->type = T::kClose; m->job_id = p.close().job_id(); break;
    case pw::ClientRequest::kPrune: {
      const auto& q = p.prune();
      m->type = T::kPrune;
      if (q.job_ids_size() > 100000) return Malformed("prune.job_ids: more than 100000");
      m->job_ids.assign(q.job_ids().begin(), q.job_ids().end());
      if (!std::isfinite(q.older_than_s()) || q.older_than_s() < 0)
        return Malformed("prune.older_than_s = " + std::to_string(q.older_than_s()) + ": must be finite and >= 0");
      if (q.keep() < 0) return Malformed("prune.keep = " + std::to_string(q.keep()) + ": must be >= 0");
      m->older_than_s = q.older_than_s();
      m->keep = q.keep();
      m->dry_run = q.dry_run();
      break;
    }
    default: return Malformed("client request has no body");
  }
  return Status::Ok();
}

std::string EncodeClientReply(const ClientReplyMsg& m) {
  pw::ClientReply p;
  p.set_version(kProtocolVersion);
  p.set_request_id(m.request_id);
  p.set_code(static_cast<pw::Code>(m.code));
  p.set_error(m.error);
  for (const auto& v : m.violations) {
    auto* pv = p.add_violations();
    pv->set_field(v.field);
    pv->set_description(v.description);
  }
  using T = ClientReplyMsg::Type;
  switch (m.type) {
    case T::kSubmit:
      p.mutable_submit()->set_job_id(m.job_id);
      p.mutable_submit()->set_existed(m.existed);
      break;
    case T::kStatus: InfoToProto(m.info, p.mutable_status()); break;
    case T::kList:
      for (const auto& j : m.jobs) InfoToProto(j, p.mutable_list()->add_jobs());
      p.mutable_list()->set_workers(static_cast<uint32_t>(m.workers));
      p.mutable_list()->set_worker_threads(static_cast<uint32_t>(m.worker_threads));
      break;
    case T::kFetch: {
      auto* f = p.mutable_fetch();
      InfoToProto(m.info, f->mutable_info());
      for (const auto& b : m.best) ToProto(b, f->add_best());
      for (const auto& r : m.log) ToProto(r, f->add_log());
      if (m.spec) ToProto(*m.spec, f->mutable_spec());
      for (const auto& n : m.networks) io::ToProto(n, f->add_networks());
      break;
    }
    case T::kEvent: {
      auto* e = p.mutable_event();
      e->set_job_id(m.event.job_id);
      e->set_state(static_cast<pw::JobState>(m.event.state));
      if (m.event.record) ToProto(*m.event.record, e->mutable_record());
      e->set_message(m.event.message);
      e->set_workers(static_cast<uint32_t>(std::max(0, m.event.workers)));
      e->set_worker_threads(static_cast<uint32_t>(std::max(0, m.event.worker_threads)));
      e->set_storage_error(m.event.storage_error);
      break;
    }
    case T::kEvaluate: {
      auto* e = p.mutable_evaluate();
      e->set_job_id(m.job_id);
      e->set_batch_seq(m.batch_seq);
      e->set_done(m.done);
      for (size_t i = 0; i < m.results.size(); ++i)
        ToProto(m.results[i], static_cast<int>(i), e->add_results());
      e->set_worker_threads(static_cast<uint32_t>(std::max(0, m.worker_threads)));
      break;
    }
    case T::kPrune: {
      auto* q = p.mutable_prune();
      for (const auto& id : m.pruned) q->add_pruned(id);
      for (const auto& v : m.refused) {
        auto* r = q->add_refused();
        r->set_field(v.field);
        r->set_description(v.description);
      }
      break;
    }
    case T::kNone: break;
  }
  return p.SerializeAsString();
}

Status DecodeClientReply(std::string_view bytes, ClientReplyMsg* m) {
  pw::ClientReply p;
  if (!Parse(bytes, &p)) return Malformed("client reply does not decode");
  if (Status s = VersionCheck(p.version()); !s.ok()) return s;
  *m = ClientReplyMsg{};
  m->request_id = p.request_id();
  if (Status s = CodeFromProto(p.code(), &m->code); !s.ok()) return s;
  m->error = p.error();
  for (const auto& v : p.violations()) m->violations.push_back({v.field(), v.description()});
  using T = ClientReplyMsg::Type;
  switch (p.body_case()) {
    case pw::ClientReply::kSubmit:
      m->type = T::kSubmit;
      m->job_id = p.submit().job_id();
      m->existed = p.submit().existed();
      break;
    case pw::ClientReply::kStatus:
      m->type = T::kStatus;
      return InfoFromProto(p.status(), &m->info);
    case pw::ClientReply::kList:
      m->type = T::kList;
      m->workers = ClampInt(p.list().workers());
      m->worker_threads = ClampInt(p.list().worker_threads());
      for (const auto& j : p.list().jobs()) {
        m->jobs.emplace_back();
        if (Status s = InfoFromProto(j, &m->jobs.back()); !s.ok()) return s;
      }
      break;
    case pw::ClientReply::kFetch:
      m->type = T::kFetch;
      for (const auto& r : p.fetch().log()) m->log.push_back(FromProto(r));
      if (p.fetch().has_spec()) {
        m->spec.emplace();
        FromProto(p.fetch().spec(), &*m->spec, nullptr);
      }
      if (Status s = IndividualsFromProto(p.fetch().best(), &m->best); !s.ok()) return s;
      for (int i = 0; i < p.fetch().networks_size(); ++i) {
        io::SavedNetwork n;
        if (Status s = io::FromProto(p.fetch().networks(i), &n); !s.ok())
          return Malformed("fetch.networks[" + std::to_string(i) + "]: " + s.message());
        m->networks.push_back(std::move(n));
      }
      return InfoFromProto(p.fetch().info(), &m->info);
    case pw::ClientReply::kEvent:
      m->type = T::kEvent;
      if (!ValidState(p.event().state())) return Malformed("event state unknown");
      m->event.job_id = p.event().job_id();
      m->event.state = static_cast<JobState>(p.event().state());
      if (p.event().has_record()) m->event.record = FromProto(p.event().record());
      m->event.message = p.event().message();
      m->event.workers = ClampInt(p.event().workers());
      m->event.worker_threads = ClampInt(p.event().worker_threads());
      m->event.storage_error = p.event().storage_error();
      break;
    case pw::ClientReply::kEvaluate: {
      const auto& e = p.evaluate();
      m->type = T::kEvaluate;
      m->job_id = e.job_id();
      m->batch_seq = e.batch_seq();
      m->done = e.done();
      m->worker_threads = ClampInt(e.worker_threads());
      m->results.resize(e.results_size());
      for (int i = 0; i < e.results_size(); ++i) {
        if (e.results(i).index() != i) return Malformed("evaluate.results[" + std::to_string(i) + "].index");
        if (Status s = FromProto(e.results(i), &m->results[i]); !s.ok()) return s;
      }
      break;
    }
    case pw::ClientReply::kPrune:
      m->type = T::kPrune;
      m->pruned.assign(p.prune().pruned().begin(), p.prune().pruned().end());
      for (const auto& r : p.prune().refused()) m->refused.push_back({r.field(), r.description()});
      break;
    default: m->type = T::kNone; break;
  }
  return Status::Ok();
}

std::string EncodeCheckpoint(const JobCheckpoint& c) {
  pw::JobCheckpoint p;
  p.set_version(kCheckpointVersion);
  p.set_job_id(c.job_id);
  p.set_state(static_cast<pw::JobState>(c.state));
  auto* o = p.mutable_optimizer();
  const GaState& g = c.optimizer;
  o->set_initialized(g.initialized);
  o->set_generation(g.generation);
  o->set_stall(g.stall);
  for (size_t i = 0; i < g.population.size(); ++i)
    ToProto(ScoredGenome{static_cast<int>(i), g.population[i],
                         i < g.fitness.size() ? g.fitness[i] : FitnessResult{}},
            o->add_population());
  o->mutable_rng_words()->Assign(g.rng.words.begin(), g.rng.words.end());
  o->set_rng_position(g.rng.position);
  ToProto(ScoredGenome{0, g.best, g.best_fitness}, o->mutable_best());
  o->set_best_generation(g.best_generation);
  o->set_evaluations(g.evaluations);
  o->set_failures(g.failures);
  for (const auto& r : c.log) ToProto(r, p.add_log());
  for (const auto& b : c.best) ToProto(b, p.add_best());
  p.set_message(c.message);
  for (const auto& q : c.quarantined) ToProto(q, p.add_quarantined());
  p.set_elapsed_s(c.elapsed_s);
  return Deterministic(p);
}

Status DecodeCheckpoint(std::string_view bytes, JobCheckpoint* c) {
  pw::JobCheckpoint p;
  if (!Parse(bytes, &p)) return Malformed("checkpoint does not decode");
  if (p.version() != kCheckpointVersion)
    return {StatusCode::kFailedPrecondition,
            "checkpoint version " + std::to_string(p.version()) + " unsupported"};
  if (!ValidState(p.state())) return Malformed("checkpoint state unknown");
  *c = JobCheckpoint{};
  c->job_id = p.job_id();
  c->state = static_cast<JobState>(p.state());
  const auto& o = p.optimizer();
  GaState& g = c->optimizer;
  g.initialized = o.initialized();
  g.generation = o.generation();
  g.stall = o.stall();
  std::vector<ScoredGenome> pop;
  if (Status s = IndividualsFromProto(o.population(), &pop); !s.ok()) return s;
  for (auto& sg : pop) {
    g.population.push_back(std::move(sg.genome));
    g.fitness.push_back(std::move(sg.fitness));
  }
  if (o.initialized() || o.rng_words_size() > 0) {
    if (o.rng_words_size() != RngState::kWords) return Malformed("checkpoint rng_words size");
    std::copy(o.rng_words().begin(), o.rng_words().end(), g.rng.words.begin());
    g.rng.position = o.rng_position();
  }
  if (o.has_best()) {
    ScoredGenome best;
    if (Status s = FromProto(o.best(), &best); !s.ok()) return s;
    g.best = std::move(best.genome);
    g.best_fitness = std::move(best.fitness);
  }
  g.best_generation = o.best_generation();
  g.evaluations = o.evaluations();
  g.failures = o.failures();
  for (const auto& r : p.log()) c->log.push_back(FromProto(r));
  if (Status s = IndividualsFromProto(p.best(), &c->best); !s.ok()) return s;
  c->message = p.message();
  for (const auto& q : p.quarantined()) c->quarantined.push_back(FromProto(q));
  c->elapsed_s = p.elapsed_s();
  return Status::Ok();
}

std::string EncodeStoredFile(std::string_view type, std::string_view payload) {
  pw::StoredFile f;
  f.set_type(std::string(type));
  f.set_payload(std::string(payload));
  f.set_length(payload.size());
  f.set_crc32(static_cast<uint32_t>(
      crc32(0L, reinterpret_cast<const Bytef*>(payload.data()), static_cast<uInt>(payload.size()))));
  return Deterministic(f);
}

Status DecodeStoredFile(std::string_view bytes, std::string_view type, std::string* payload) {
  pw::StoredFile f;
  if (!Parse(bytes, &f) || f.type().empty())
    return {StatusCode::kNotFound, "not a stored file (" + std::to_string(bytes.size()) + " bytes)"};
  if (f.type() != type)
    return {StatusCode::kDataLoss, "holds a " + f.type() + ", not a " + std::string(type)};
  if (f.payload().size() != f.length())
    return {StatusCode::kDataLoss, "truncated: " + std::to_string(f.payload().size()) + " of " +
                                       std::to_string(f.length()) + " payload bytes"};
  const auto crc = static_cast<uint32_t>(crc32(
      0L, reinterpret_cast<const Bytef*>(f.payload().data()), static_cast<uInt>(f.payload().size())));
  if (crc != f.crc32()) return {StatusCode::kDataLoss, "checksum mismatch (the file was altered)"};
  *payload = std::move(*f.mutable_payload());
  return Status::Ok();
}

}  // namespace pz::service
