// The codecs' shared pieces (service/codec_detail.h).
#include "service/codec_detail.h"

#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/stubs/logging.h>

#include <array>
#include <bit>
#include <cmath>
#include <cstring>
#include <cstdio>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace pz::service::detail {

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
  // The callers say what is wrong with bytes that do not decode; protobuf's own log lines ("String
  // field … contains invalid UTF-8 data", when a damaged checkpoint is tried as a bare one or a
  // peer sends garbage) would only repeat it on stderr, once per frame a peer chooses to send.
  google::protobuf::LogSilencer quiet;
  return msg->ParseFromArray(bytes.data(), static_cast<int>(bytes.size()));
}

// ---------------------------------------------------------------- genomes and results

namespace {

static_assert(std::endian::native == std::endian::little,
              "the genome packing reads eight bytes as one word");

/// Eight genome bits (one byte each, nonzero = set) as one byte, bit k = genome bit k.
inline uint8_t PackEight(const uint8_t* bits) {
  uint64_t x;
  std::memcpy(&x, bits, 8);
  constexpr uint64_t kLow7 = 0x7F7F7F7F7F7F7F7FULL, kHigh = 0x8080808080808080ULL;
  const uint64_t set = ((((x & kLow7) + kLow7) | x) & kHigh) >> 7;   // 1 in each nonzero byte
  return static_cast<uint8_t>((set * 0x0102040810204080ULL) >> 56);  // byte k's 1 → bit k
}

/// A packed byte as eight genome bits (bytes 0/1, bit k → byte k).
constexpr std::array<uint64_t, 256> kUnpacked = [] {
  std::array<uint64_t, 256> t{};
  for (int v = 0; v < 256; ++v)
    for (int k = 0; k < 8; ++k) t[v] |= static_cast<uint64_t>((v >> k) & 1) << (8 * k);
  return t;
}();

}  // namespace

void ToProto(const Genome& g, pw::Genome* p) {
  // Sixteen or eight bits at a time: the master packs every genome it leases (the paper's has 1415
  // bits). Written into the message's own string, whose capacity a reused message keeps
  // (PackedTasks).
  const size_t n = g.bits.size(), whole = n / 8;
  std::string& packed = *p->mutable_bits();
  packed.assign((n + 7) / 8, '\0');
  size_t b = 0;
#if defined(__SSE2__)
  // Sixteen bits at a time: the mask of the zero bytes, inverted, is the packed pair of bytes.
  for (; b + 2 <= whole; b += 2) {
    const __m128i sixteen =
        _mm_loadu_si128(reinterpret_cast<const __m128i*>(g.bits.data() + 8 * b));
    const auto set =
        static_cast<uint16_t>(~_mm_movemask_epi8(_mm_cmpeq_epi8(sixteen, _mm_setzero_si128())));
    packed[b] = static_cast<char>(set & 0xFF);
    packed[b + 1] = static_cast<char>(set >> 8);
  }
#endif
  for (; b < whole; ++b) packed[b] = static_cast<char>(PackEight(g.bits.data() + 8 * b));
  for (size_t i = 8 * whole; i < n; ++i)
    if (g.bits[i]) packed[i / 8] = static_cast<char>(packed[i / 8] | (1u << (i % 8)));
  p->set_bit_count(static_cast<uint32_t>(g.bits.size()));
  p->mutable_reals()->Assign(g.reals.begin(), g.reals.end());
}

Status FromProto(const pw::Genome& p, Genome* g) {
  if (p.bit_count() > kMaxGenomeBits) return Malformed("genome.bit_count too large");
  if (p.bits().size() != (p.bit_count() + 7) / 8)
    return Malformed("genome.bits has " + std::to_string(p.bits().size()) + " bytes for " +
                     std::to_string(p.bit_count()) + " bits");
  const size_t n = p.bit_count(), whole = n / 8;
  g->bits.resize(n);
  for (size_t b = 0; b < whole; ++b) {
    const uint64_t eight = kUnpacked[static_cast<uint8_t>(p.bits()[b])];
    std::memcpy(g->bits.data() + 8 * b, &eight, 8);
  }
  for (size_t i = 8 * whole; i < n; ++i)
    g->bits[i] = (static_cast<uint8_t>(p.bits()[i / 8]) >> (i % 8)) & 1u;
  g->reals.assign(p.reals().begin(), p.reals().end());
  return Status::Ok();
}

pw::FitnessCode ToProto(FitnessStatus s) {
  switch (s) {
    case FitnessStatus::kOk:
      return pw::FITNESS_OK;
    case FitnessStatus::kPenalized:
      return pw::FITNESS_PENALIZED;
    case FitnessStatus::kError:
      return pw::FITNESS_ERROR;
  }
  return pw::FITNESS_UNSPECIFIED;
}

Status FromProto(pw::FitnessCode c, double cost, FitnessStatus* s) {
  switch (c) {
    case pw::FITNESS_OK:
      *s = FitnessStatus::kOk;
      break;
    case pw::FITNESS_PENALIZED:
      *s = FitnessStatus::kPenalized;
      break;
    case pw::FITNESS_ERROR:
    case pw::FITNESS_QUARANTINED:
      *s = FitnessStatus::kError;
      break;
    default:
      return Malformed("fitness code unspecified");
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
  p->set_evaluations(static_cast<uint64_t>(std::max<int64_t>(0, r.evaluations_total)));
  p->set_errors(static_cast<uint32_t>(std::max(0, r.failures)));
  p->set_quarantined(static_cast<uint32_t>(std::max(0, r.quarantined)));
  p->set_worst_cost(r.worst_cost);
  p->set_stall(static_cast<uint32_t>(std::max(0, r.stall)));
  p->set_evaluated(static_cast<uint32_t>(std::max(0, r.evaluations)));
  p->set_penalized(static_cast<uint32_t>(std::max(0, r.penalized)));
  for (const auto& [k, n] : r.failure_reasons)
    (*p->mutable_failure_reasons())[k] = static_cast<uint32_t>(std::max(0, n));
  p->set_best_description(r.best_description);
  p->set_wall_time_s(r.wall_time_s);
  p->set_improved(r.improved);
  p->set_median_cost(r.median_cost);
  p->set_best_island(static_cast<uint32_t>(std::max(0, r.best_island)));
  p->set_migrated(r.migrated);
  for (const opt::IslandSummary& i : r.islands) {
    auto* q = p->add_islands();
    q->set_best_cost(i.best_cost);
    q->set_stall(static_cast<uint32_t>(std::max(0, i.stall)));
    q->set_immigrants(static_cast<uint32_t>(std::max(0, i.immigrants)));
    q->set_restarted(i.restarted);
  }
}

GenerationRecord FromProto(const pw::GenerationRecord& p) {
  GenerationRecord r;
  r.generation = p.generation();
  r.best_cost = p.best_cost();
  r.mean_cost = p.mean_cost();
  r.median_cost = p.median_cost();
  r.evaluations_total = static_cast<int64_t>(std::min<uint64_t>(p.evaluations(), INT64_MAX));
  r.failures = ClampInt(p.errors());
  r.quarantined = ClampInt(p.quarantined());
  r.worst_cost = p.worst_cost();
  r.stall = ClampInt(p.stall());
  r.evaluations = ClampInt(p.evaluated());
  r.penalized = ClampInt(p.penalized());
  r.errors = std::max(0, r.failures - r.penalized);  // the non-ok results that are not penalties
  for (const auto& [k, n] : p.failure_reasons()) r.failure_reasons[k] = ClampInt(n);
  r.best_description = p.best_description();
  r.wall_time_s = p.wall_time_s();
  r.improved = p.improved();
  r.best_island = ClampInt(p.best_island());
  r.migrated = p.migrated();
  for (const auto& q : p.islands())
    r.islands.push_back(
        {q.best_cost(), ClampInt(q.stall()), ClampInt(q.immigrants()), q.restarted()});
  return r;
}

pw::GaTermination ToProto(std::optional<opt::GaTermination> t) {
  return t ? static_cast<pw::GaTermination>(*t) : pw::GA_TERMINATION_UNSPECIFIED;
}

std::optional<opt::GaTermination> FromProto(pw::GaTermination t) {
  if (t == pw::GA_TERMINATION_UNSPECIFIED || !pw::GaTermination_IsValid(t)) return std::nullopt;
  return static_cast<opt::GaTermination>(t);
}

void ToProto(const QuarantineRecord& q, pw::QuarantineRecord* p) {
  p->set_generation(q.generation);
  p->set_index(q.index);
  p->set_strikes(q.strikes);
}

QuarantineRecord FromProto(const pw::QuarantineRecord& p) {
  return {p.generation(), p.index(), p.strikes()};
}

bool ValidState(int s) { return pw::JobState_IsValid(s); }

// ---------------------------------------------------------------- job specs

int ClampInt(uint64_t v) { return v > 0x7fffffffu ? 0x7fffffff : static_cast<int>(v); }
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
  p->set_termination(ToProto(i.termination));
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
  i->termination = FromProto(p.termination());
  return Status::Ok();
}

void ToProto(const WorkersSnapshot& w, pw::WorkersReply* q) {
  for (const WorkerView& v : w.workers) {
    auto* o = q->add_workers();
    o->set_id(v.id);
    o->set_host(v.host);
    o->set_pid(v.pid);
    o->set_threads(static_cast<uint32_t>(std::max(0, v.threads)));
    o->set_item_seconds(v.item_seconds);
    o->set_leases(static_cast<uint32_t>(std::max(0, v.leases)));
    o->set_tasks_in_flight(static_cast<uint32_t>(std::max(0, v.tasks_in_flight)));
    o->set_tasks_done(v.tasks_done);
    o->set_connected_unix_s(v.connected_unix_s);
    o->set_solo(v.solo);
    o->set_key(v.key);
    o->set_arithmetic(v.arithmetic);
  }
  for (const WorkerDepartureView& d : w.departed) {
    auto* o = q->add_departed();
    o->set_id(d.id);
    o->set_host(d.host);
    o->set_pid(d.pid);
    o->set_reason(d.reason);
    o->set_at_unix_s(d.at_unix_s);
    o->set_tasks_done(d.tasks_done);
  }
  q->set_leases_sent(w.leases_sent);
  q->set_tasks_done(w.tasks_done);
  q->set_results_ignored(w.results_ignored);
  q->set_bad_frames(w.bad_frames);
  q->set_uptime_s(w.uptime_s);
  q->set_speculative_leases(w.speculative_leases);
  q->set_speculative_wins(w.speculative_wins);
}

WorkersSnapshot FromProto(const pw::WorkersReply& q) {
  WorkersSnapshot w;
  for (const auto& o : q.workers()) {
    WorkerView v;
    v.id = o.id();
    v.host = o.host();
    v.key = o.key();
    v.arithmetic = o.arithmetic();
    v.pid = o.pid();
    v.threads = ClampInt(o.threads());
    v.item_seconds = std::isfinite(o.item_seconds()) ? o.item_seconds() : -1;
    v.leases = ClampInt(o.leases());
    v.tasks_in_flight = ClampInt(o.tasks_in_flight());
    v.tasks_done = o.tasks_done();
    v.connected_unix_s = o.connected_unix_s();
    v.solo = o.solo();
    w.workers.push_back(std::move(v));
  }
  for (const auto& o : q.departed())
    w.departed.push_back({o.id(), o.host(), o.reason(), o.pid(), o.at_unix_s(), o.tasks_done()});
  w.leases_sent = q.leases_sent();
  w.tasks_done = q.tasks_done();
  w.results_ignored = q.results_ignored();
  w.bad_frames = q.bad_frames();
  w.speculative_leases = q.speculative_leases();
  w.speculative_wins = q.speculative_wins();
  w.uptime_s = q.uptime_s();
  return w;
}

void ToProto(const job::LawCommittee& c, pw::LawCommittee* p) {
  p->set_members(static_cast<uint32_t>(c.members));
  for (size_t i = 0; i < c.floor.size(); ++i) {
    auto* k = p->add_cases();
    k->set_floor(c.floor[i]);
    k->set_disagreement(i < c.disagreement.size() ? c.disagreement[i] : 0.0);
    k->set_kept_disagreement(i < c.kept_disagreement.size() ? c.kept_disagreement[i] : 0.0);
    k->set_open(i < c.open.size() && c.open[i]);
    if (i < c.lo.size())
      for (double v : c.lo[i]) k->add_lo(v);
    if (i < c.hi.size())
      for (double v : c.hi[i]) k->add_hi(v);
  }
  for (const auto& cand : c.candidates) {
    auto* k = p->add_candidates();
    k->set_amplitude_v(cand.amplitude_v);
    k->set_frequency_hz(cand.frequency_hz);
    k->set_case_index(cand.case_index);
  }
  for (const auto& [index, left_open] : c.next) {
    auto* r = p->add_next();
    r->set_candidate(static_cast<uint32_t>(index));
    r->set_left_open(left_open);
  }
  p->set_simulations(c.simulations);
}

Status FromProto(const pw::LawCommittee& p, job::LawCommittee* c) {
  *c = job::LawCommittee{};
  c->members = ClampInt(p.members());
  for (int i = 0; i < p.cases_size(); ++i) {
    const auto& k = p.cases(i);
    const std::string at = "committee.cases[" + std::to_string(i) + "]";
    if (k.lo_size() != model::kNetworkOutputs || k.hi_size() != model::kNetworkOutputs)
      return Malformed(at + ": lo and hi must hold the " +
                       std::to_string(model::kNetworkOutputs) + " parameters");
    c->floor.push_back(k.floor());
    c->disagreement.push_back(k.disagreement());
    c->kept_disagreement.push_back(k.kept_disagreement());
    c->open.push_back(k.open());
    std::array<double, model::kNetworkOutputs> lo{}, hi{};
    for (int j = 0; j < model::kNetworkOutputs; ++j) lo[j] = k.lo(j), hi[j] = k.hi(j);
    c->lo.push_back(lo);
    c->hi.push_back(hi);
  }
  for (int i = 0; i < p.candidates_size(); ++i) {
    const auto& k = p.candidates(i);
    if (k.case_index() < -1 || k.case_index() >= p.cases_size())
      return Malformed("committee.candidates[" + std::to_string(i) + "].case_index = " +
                       std::to_string(k.case_index()) + ": must be -1 or a case's index");
    c->candidates.push_back({k.amplitude_v(), k.frequency_hz(), k.case_index()});
  }
  for (int i = 0; i < p.next_size(); ++i) {
    if (p.next(i).candidate() >= static_cast<uint32_t>(p.candidates_size()))
      return Malformed("committee.next[" + std::to_string(i) + "].candidate = " +
                       std::to_string(p.next(i).candidate()) + ": must index candidates");
    c->next.emplace_back(static_cast<int>(p.next(i).candidate()), p.next(i).left_open());
  }
  c->simulations = p.simulations();
  return Status::Ok();
}

}  // namespace pz::service::detail
