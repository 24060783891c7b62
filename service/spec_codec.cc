// The job-spec codec: JobSpec ↔ proto (binary and protobuf JSON), with every field that does not
// decode named; content hashes; names of codes and states.
#include "service/codec_detail.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/unknown_field_set.h>
#include <google/protobuf/util/json_util.h>

#include <cmath>
#include <cstdio>

namespace pz::service {
namespace detail {
namespace {
template <typename T>
T OrDefault(T v, T def) {
  return v == T{} ? def : v;
}
}  // namespace

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
HgannCaseSpec CaseFromProto(const pw::HgannCase& pc, const std::string& field,
                            std::vector<FieldViolation>* v) {
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

// One encoder and one decoder per problem: a new job kind adds its pair here and its case in
// FromProto's switch.
void ProblemToProto(const std::monostate&, pw::JobSpec*) {}

void ProblemToProto(const HgannProblem& h, pw::JobSpec* p) {
  auto* ph = p->mutable_hgann();
  for (const HgannCaseSpec& c : h.cases) CaseToProto(c, ph->add_cases());
  ph->set_case_set_dir(h.case_set_dir);
  ph->set_source(h.source);
  ph->set_ranges_preset(h.ranges_preset);
  for (const ParameterRange& r : h.ranges) {
    auto* pr = ph->add_ranges();
    pr->set_name(r.name);
    pr->set_min(r.min);
    pr->set_max(r.max);
  }
  // What the preset gives is left unset (a paper-preset spec encodes as before presets, but
  // for the name); an unknown preset's name is refused by validation, its fields written.
  const auto preset = job::HgannSearchPreset(h.preset);
  ph->set_preset(h.preset);
  if (!preset || h.spread_penalty != preset->spread_penalty)
    ph->set_spread_penalty(h.spread_penalty);
  if (!preset || h.trend_seeds != preset->trend_seeds) ph->set_trend_seeds(h.trend_seeds);
  for (const auto& [v, f] : h.next_candidates) {
    auto* point = ph->add_next_candidates();
    point->set_amplitude_v(v);
    point->set_frequency_hz(f);
  }
  ph->set_saturation(h.saturation == HgannProblem::Saturation::kGiven
                         ? pw::SATURATION_GIVEN
                         : pw::SATURATION_FROM_EXTREMES);
  if (!h.geometry.empty()) {
    auto* g = ph->mutable_geometry();
    const auto* d = g->GetDescriptor();
    const auto* refl = g->GetReflection();
    for (const auto& [name, value] : h.geometry) {
      const auto* f = d->FindFieldByName(name);
      if (!f) continue;  // unknown names are refused by validation before they are encoded
      if (f->cpp_type() == google::protobuf::FieldDescriptor::CPPTYPE_DOUBLE)
        refl->SetDouble(g, f, value);
      else
        refl->SetUInt32(g, f,
                        value >= 0 && value <= 4294967295.0 ? static_cast<uint32_t>(value) : 0u);
    }
  }
}

HgannProblem HgannFromProto(const pw::HgannProblem& ph, std::vector<FieldViolation>* v) {
  HgannProblem h;
  for (int i = 0; i < ph.cases_size(); ++i)
    h.cases.push_back(CaseFromProto(ph.cases(i), "hgann.cases[" + std::to_string(i) + "]", v));
  h.case_set_dir = ph.case_set_dir();
  h.source = ph.source();
  h.ranges_preset = ph.ranges_preset();
  for (const auto& pr : ph.ranges()) h.ranges.push_back({pr.name(), pr.min(), pr.max()});
  h.preset = ph.preset();
  // Unset: the preset's (an unknown preset: the default's, and validation names the preset).
  const job::HgannSearchSettings preset =
      job::HgannSearchPreset(h.preset).value_or(*job::HgannSearchPreset(""));
  h.spread_penalty = ph.has_spread_penalty() ? ph.spread_penalty() : preset.spread_penalty;
  h.trend_seeds = ph.has_trend_seeds() ? ph.trend_seeds() : preset.trend_seeds;
  for (const auto& point : ph.next_candidates())
    h.next_candidates.emplace_back(point.amplitude_v(), point.frequency_hz());
  switch (ph.saturation()) {
    case pw::SATURATION_UNSPECIFIED:
    case pw::SATURATION_FROM_EXTREMES:
      h.saturation = HgannProblem::Saturation::kFromExtremes;
      break;
    case pw::SATURATION_GIVEN:
      h.saturation = HgannProblem::Saturation::kGiven;
      break;
    default:
      if (v)
        v->push_back(
            {"hgann.saturation", "hgann.saturation = " + std::to_string(ph.saturation()) +
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
  return h;
}

void ProblemToProto(const SyntheticProblem& y, pw::JobSpec* p) {
  auto* py = p->mutable_synthetic();
  py->set_cost(y.cost == SyntheticProblem::Cost::kNull ? pw::SyntheticProblem::COST_NULL
                                                       : pw::SyntheticProblem::COST_FUNCTION);
  py->set_genome_bits(static_cast<uint32_t>(y.genome_bits));
  py->set_sleep_ms(y.sleep_ms);
  py->set_crash_prefix(y.crash_prefix);
}

SyntheticProblem SyntheticFromProto(const pw::SyntheticProblem& py,
                                    std::vector<FieldViolation>* v) {
  SyntheticProblem y;
  switch (py.cost()) {
    case pw::SyntheticProblem::COST_NULL:
      y.cost = SyntheticProblem::Cost::kNull;
      break;
    case pw::SyntheticProblem::COST_FUNCTION:
      y.cost = SyntheticProblem::Cost::kFunction;
      break;
    default:
      if (v)
        v->push_back({"synthetic.cost", "synthetic.cost = " + std::to_string(py.cost()) +
                                            ": must be COST_NULL or COST_FUNCTION"});
  }
  y.genome_bits = ClampInt(OrDefault<uint32_t>(py.genome_bits(), 64));
  y.sleep_ms = py.sleep_ms();
  y.crash_prefix = py.crash_prefix();
  return y;
}

void ProblemToProto(const CompleteModelProblem& m, pw::JobSpec* p) {
  auto* pm = p->mutable_complete_model();
  pm->set_family(static_cast<pw::CompleteModelFamily>(m.family));
  for (const CompleteModelRecord& r : m.records) {
    auto* pr = pm->add_records();
    pr->set_name(r.name);
    pr->set_sample_rate_hz(r.sample_rate_hz);
    pr->mutable_input()->Assign(r.input.begin(), r.input.end());
    pr->mutable_output()->Assign(r.output.begin(), r.output.end());
    pr->set_first_counted(r.first_counted);
    pr->set_dt_s(r.dt_s);
    pr->set_end_counted(r.end_counted);
    pr->set_rest_samples(r.rest_samples);
    pr->set_offset_mode(static_cast<uint32_t>(std::max(0, r.offset_mode)));
    pr->set_offset(r.offset);
    if (r.sinusoid) {
      auto* ps = pr->mutable_sinusoid();
      ps->set_case_number(
          static_cast<uint32_t>(std::clamp<int64_t>(r.sinusoid->case_number, 0, UINT32_MAX)));
      ps->set_amplitude_v(r.sinusoid->amplitude_v);
      ps->set_frequency_hz(r.sinusoid->frequency_hz);
      ps->set_cycles(r.sinusoid->cycles);
      ps->set_sample_rate_hz(r.sinusoid->sample_rate_hz);
    }
  }
  pm->set_criterion(static_cast<pw::CompleteModelCriterion>(m.criterion));
  pm->set_t0_s(m.t0_s);
  pm->set_t1_s(m.t1_s);
  pm->set_substeps(static_cast<uint32_t>(std::max(0, m.substeps)));
  pm->set_interpolation(static_cast<pw::BwInterpolation>(m.interpolation));
  pm->set_period_samples(m.period_samples);
  pm->set_error_cost(m.error_cost);
  pm->set_source(m.source);
  pm->set_record_family(m.record_family);
  for (const std::string& e : m.effects) pm->add_effects(e);
  pm->set_pi_operators(static_cast<uint32_t>(std::max(0, m.pi_operators)));
  pm->set_initial_state(m.initial_state);
  pm->mutable_scale()->Assign(m.scale.begin(), m.scale.end());
  pm->set_bench_form(m.bench_form);
  pm->set_residuals(m.residuals);
  if (m.fin_sim) {
    auto* pf = pm->mutable_fin_sim();
    pf->set_oversample(static_cast<uint32_t>(std::max(0, m.fin_sim->oversample)));
    pf->set_rtol(m.fin_sim->rtol);
    pf->set_atol(m.fin_sim->atol);
    pf->set_max_steps(static_cast<uint64_t>(std::max<int64_t>(0, m.fin_sim->max_steps)));
    pf->set_force_cvode(m.fin_sim->force_cvode);
  }
}

CompleteModelProblem CompleteModelFromProto(const pw::CompleteModelProblem& pm,
                                            std::vector<FieldViolation>* v) {
  CompleteModelProblem m;
  auto bad_enum = [&](const char* field, int value, const char* known) {
    if (v)
      v->push_back(
          {field, std::string(field) + " = " + std::to_string(value) + ": must be " + known});
  };
  if (pm.family() >= 0 && pm.family() <= 4)
    m.family = static_cast<CompleteModelProblem::Family>(pm.family());
  else
    bad_enum("complete_model.family", pm.family(),
             "BW_OSCILLATOR, STACK_BOUC_WEN, STACK_BACKLASH_LIKE or RECORDS");
  for (const auto& pr : pm.records()) {
    CompleteModelRecord r;
    r.name = pr.name();
    r.sample_rate_hz = pr.sample_rate_hz();
    r.input.assign(pr.input().begin(), pr.input().end());
    r.output.assign(pr.output().begin(), pr.output().end());
    r.first_counted = pr.first_counted();
    r.dt_s = pr.dt_s();
    r.end_counted = pr.end_counted();
    r.rest_samples = std::max<uint64_t>(1, pr.rest_samples());
    r.offset_mode = static_cast<int>(std::min<uint32_t>(pr.offset_mode(), 1000));
    r.offset = pr.offset();
    if (pr.has_sinusoid()) {
      const auto& ps = pr.sinusoid();
      r.sinusoid = CompleteModelRecord::Sinusoid{
          ps.case_number(), ps.amplitude_v(), ps.frequency_hz(), ps.cycles(), ps.sample_rate_hz()};
    }
    m.records.push_back(std::move(r));
  }
  if (pm.criterion() >= 0 && pm.criterion() <= 4)
    m.criterion =
        static_cast<CompleteModelProblem::Criterion>(std::max(1, static_cast<int>(pm.criterion())));
  else
    bad_enum("complete_model.criterion", pm.criterion(), "IAE, SSE, RMSE or MAX");
  m.t0_s = pm.t0_s();
  m.t1_s = pm.t1_s();
  m.substeps = ClampInt(pm.substeps());
  if (pm.interpolation() >= 0 && pm.interpolation() <= 4)
    m.interpolation = pm.interpolation() == 0
                          ? CompleteModelProblem::Interpolation::kSpline
                          : static_cast<CompleteModelProblem::Interpolation>(pm.interpolation());
  else
    bad_enum("complete_model.interpolation", pm.interpolation(), "ZOH, LINEAR, SPLINE or FOURIER");
  m.period_samples = pm.period_samples();
  m.error_cost = OrDefault(pm.error_cost(), 1e30);
  m.source = pm.source();
  m.record_family = pm.record_family();
  m.effects.assign(pm.effects().begin(), pm.effects().end());
  m.pi_operators = pm.pi_operators() == 0 ? 12 : ClampInt(pm.pi_operators());
  m.initial_state = pm.initial_state();
  m.scale.assign(pm.scale().begin(), pm.scale().end());
  m.bench_form = pm.bench_form();
  m.residuals = pm.residuals();
  if (pm.has_fin_sim()) {
    const auto& pf = pm.fin_sim();
    m.fin_sim =
        CompleteModelProblem::FinSim{ClampInt(OrDefault<uint32_t>(pf.oversample(), 4)),
                                     OrDefault(pf.rtol(), 1e-6), OrDefault(pf.atol(), 1e-13),
                                     static_cast<int64_t>(std::min<uint64_t>(
                                         OrDefault<uint64_t>(pf.max_steps(), 5000000), INT64_MAX)),
                                     pf.force_cvode()};
  }
  return m;
}

/// The islands of a spec whose ga leaves them unset: an hgann problem's preset's, else 1.
int DefaultIslands(const JobSpec& s) {
  if (const auto* h = std::get_if<HgannProblem>(&s.problem))  // as decoded: unknown = default
    return job::HgannSearchPreset(h->preset).value_or(*job::HgannSearchPreset("")).islands;
  return 1;
}

namespace {

// The tag of the removed "diagnose" problem (proto/job.proto JobSpec: reserved 13, "diagnose").
constexpr int kRemovedDiagnoseTag = 13;

// An old spec's "diagnose" problem stays in the message's unknown fields.
bool HoldsRemovedKind(const pw::JobSpec& p) {
  const google::protobuf::UnknownFieldSet& u = p.GetReflection()->GetUnknownFields(p);
  for (int i = 0; i < u.field_count(); ++i)
    if (u.field(i).number() == kRemovedDiagnoseTag) return true;
  return false;
}

std::string RemovedKindMessage() {
  std::string kinds;
  for (const std::string& k : job::JobKindNames()) kinds += (kinds.empty() ? "" : ", ") + k;
  return "problem: the job kind \"diagnose\" (the fin engine's fits) was removed; this version "
         "runs " +
         kinds + " (piezoid diagnose --cases --master opens complete_model sessions)";
}

}  // namespace

void ToProto(const JobSpec& s, pw::JobSpec* p) {
  p->set_version(s.version);
  p->set_name(s.name);
  p->set_seed(s.seed);
  auto* l = p->mutable_limits();
  l->set_task_timeout_s(s.limits.task_timeout_s);
  l->set_quarantine_after(static_cast<uint32_t>(s.limits.quarantine_after));
  l->set_penalty_cost(s.limits.penalty_cost);
  if (s.limits.target_cost) l->set_target_cost(*s.limits.target_cost);
  std::visit([p](const auto& problem) { ProblemToProto(problem, p); }, s.problem);
  if (s.ga) {
    auto* g = p->mutable_ga();
    g->set_population(static_cast<uint32_t>(s.ga->population));
    g->set_elite_fraction(s.ga->elite_fraction);
    g->set_tournament(static_cast<uint32_t>(s.ga->tournament));
    g->set_crossover_probability(s.ga->crossover_probability);
    g->set_mutation_probability(s.ga->mutation_probability);
    g->set_generations(static_cast<uint32_t>(s.ga->generations));
    g->set_stall_generations(static_cast<uint32_t>(s.ga->stall_generations));
    // The islands that differ from the problem's default (one island, or an hgann preset's).
    if (s.ga->islands != DefaultIslands(s)) g->set_islands(static_cast<uint32_t>(s.ga->islands));
    if (s.ga->islands !=
        1) {  // a one-island spec serialises as before islands existed (the same job id)
      g->set_migration_interval(static_cast<uint32_t>(s.ga->migration_interval));
      g->set_migrants(static_cast<uint32_t>(s.ga->migrants));
      g->set_topology(static_cast<pw::MigrationTopology>(s.ga->topology));
      g->set_migration_margin(s.ga->migration_margin);
      if (s.ga->broadcast_interval !=
          0) {  // a spec without a broadcast serialises as before it existed
        g->set_broadcast_interval(static_cast<uint32_t>(s.ga->broadcast_interval));
        g->set_broadcast_margin(s.ga->broadcast_margin);
      }
    }
    if (s.ga->island_stall_generations != 0)
      g->set_island_stall_generations(static_cast<uint32_t>(s.ga->island_stall_generations));
    for (double p : s.ga->island_mutation) g->add_island_mutation(p);
    if (s.ga->output_moves >= 0)
      g->set_output_moves(static_cast<uint32_t>(s.ga->output_moves));  // unset = auto
  }
  if (s.external) {
    auto* e = p->mutable_external();
    e->set_idle_timeout_s(s.external->idle_timeout_s);
    e->set_owner(s.external->owner);
  }
}

void FromProto(const pw::JobSpec& p, JobSpec* s, std::vector<FieldViolation>* v) {
  *s = JobSpec{};
  s->version = p.version();
  s->name = p.name();
  s->seed = p.seed();
  s->limits.task_timeout_s = OrDefault(p.limits().task_timeout_s(), 60.0);
  s->limits.quarantine_after = ClampInt(OrDefault<uint32_t>(p.limits().quarantine_after(), 3));
  s->limits.penalty_cost = OrDefault(p.limits().penalty_cost(), 1e9);
  if (p.limits().has_target_cost()) s->limits.target_cost = p.limits().target_cost();
  switch (p.problem_case()) {
    case pw::JobSpec::kHgann:
      s->problem = HgannFromProto(p.hgann(), v);
      break;
    case pw::JobSpec::kSynthetic:
      s->problem = SyntheticFromProto(p.synthetic(), v);
      break;
    case pw::JobSpec::kCompleteModel:
      s->problem = CompleteModelFromProto(p.complete_model(), v);
      break;
    case pw::JobSpec::PROBLEM_NOT_SET:
      if (v && HoldsRemovedKind(p)) v->push_back({"problem", RemovedKindMessage()});
      break;
  }
  if (p.has_ga()) {
    const auto& pg = p.ga();
    GaSettings g;
    g.population = ClampInt(OrDefault<uint32_t>(pg.population(), 400));
    if (pg.has_elite_fraction()) g.elite_fraction = pg.elite_fraction();
    g.tournament = ClampInt(OrDefault<uint32_t>(pg.tournament(), 2));
    if (pg.has_crossover_probability()) g.crossover_probability = pg.crossover_probability();
    if (pg.has_mutation_probability()) g.mutation_probability = pg.mutation_probability();
    if (const auto* h = std::get_if<HgannProblem>(&s->problem)) {  // its preset's search
      const auto preset = job::HgannSearchPreset(h->preset).value_or(*job::HgannSearchPreset(""));
      g.generations = preset.generations;
      g.islands = preset.islands;
      g.stall_generations = preset.stall_generations;
    }
    if (pg.has_generations()) g.generations = ClampInt(pg.generations());
    if (pg.has_stall_generations()) g.stall_generations = ClampInt(pg.stall_generations());
    if (pg.has_islands()) g.islands = ClampInt(pg.islands());
    if (pg.has_migration_interval()) g.migration_interval = ClampInt(pg.migration_interval());
    if (pg.has_migrants()) g.migrants = ClampInt(pg.migrants());
    if (pg.topology() != pw::MIGRATION_TOPOLOGY_UNSPECIFIED)
      g.topology =
          static_cast<opt::MigrationTopology>(pg.topology());  // unknown values: JobSpec::Validate
    if (pg.has_migration_margin()) g.migration_margin = pg.migration_margin();
    if (pg.has_island_stall_generations())
      g.island_stall_generations = ClampInt(pg.island_stall_generations());
    if (pg.has_broadcast_interval()) g.broadcast_interval = ClampInt(pg.broadcast_interval());
    if (pg.has_broadcast_margin()) g.broadcast_margin = pg.broadcast_margin();
    g.island_mutation.assign(pg.island_mutation().begin(), pg.island_mutation().end());
    if (pg.has_output_moves()) g.output_moves = ClampInt(pg.output_moves());
    s->ga = g;
  } else if (p.has_external()) {
    ExternalSettings e;
    e.idle_timeout_s = OrDefault(p.external().idle_timeout_s(), 120.0);
    e.owner = p.external().owner();
    s->external = e;
  }
}

}  // namespace detail

using namespace detail;

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

std::string JobIdOf(const std::string& spec_bytes, const std::string& client_token) {
  std::string key = spec_bytes;
  key += '\0';
  key += client_token;
  return "j" + ContentHash(key).substr(0, 15);
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

const char* WireCodeName(WireCode c) { return pw::Code_Name(static_cast<pw::Code>(c)).c_str(); }

const char* JobStateName(JobState s) {
  switch (s) {
    case JobState::kRunning:
      return "running";
    case JobState::kSucceeded:
      return "succeeded";
    case JobState::kFailed:
      return "failed";
    case JobState::kCancelled:
      return "cancelled";
    default:
      return "unspecified";
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

namespace {

/// protobuf's refusal of an enum name it does not know names the field and the enum type, e.g.
/// "(ga.topology): invalid value "STAR" for type type.googleapis.com/pz.wire.MigrationTopology":
/// the names allowed are added from the type's descriptor ("" for any other message).
std::string AllowedEnumNames(std::string_view message) {
  static constexpr std::string_view kType = "for type type.googleapis.com/";
  const size_t at = message.find(kType);
  if (at == std::string_view::npos) return "";
  std::string_view name = message.substr(at + kType.size());
  name = name.substr(0, name.find_first_of(" \t\n"));
  const auto* e =
      google::protobuf::DescriptorPool::generated_pool()->FindEnumTypeByName(std::string(name));
  if (e == nullptr) return "";
  std::string names;
  for (int i = 0; i < e->value_count(); ++i)
    names += (i ? ", " : "") + std::string(e->value(i)->name());
  return " (allowed: " + names + ")";
}

}  // namespace

Status JobSpecFromJson(const std::string& json, JobSpec* spec, std::vector<FieldViolation>* v) {
  pw::JobSpec p;
  google::protobuf::util::JsonParseOptions opts;
  opts.ignore_unknown_fields = false;
  auto st = google::protobuf::util::JsonStringToMessage(json, &p, opts);
  if (!st.ok()) {
    google::protobuf::Struct object;  // any JSON object: does the spec hold the removed kind?
    if (google::protobuf::util::JsonStringToMessage(json, &object).ok() &&
        object.fields().contains("diagnose"))
      return InvalidArgument("job spec JSON: " + RemovedKindMessage());
    const std::string message(st.message());
    return InvalidArgument("job spec JSON: " + message + AllowedEnumNames(message));
  }
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
}  // namespace pz::service
