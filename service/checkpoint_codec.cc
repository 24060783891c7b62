// The checkpoint codec: JobCheckpoint ↔ proto, and the StoredFile frame (length + CRC-32) of the
// state directory's files.
#include "service/codec_detail.h"

#include <zlib.h>

#include <cmath>

namespace pz::service {
using namespace detail;
namespace {

template <typename Proto>
void PopulationToProto(const opt::IslandState& is, Proto* o) {
  for (size_t i = 0; i < is.population.size(); ++i)
    ToProto(ScoredGenome{static_cast<int>(i), is.population[i],
                         i < is.fitness.size() ? is.fitness[i] : FitnessResult{}},
            o->add_population());
  o->mutable_rng_words()->Assign(is.rng.words.begin(), is.rng.words.end());
  o->set_rng_position(is.rng.position);
}

template <typename Proto>
Status PopulationFromProto(const Proto& o, bool need_rng, opt::IslandState* is) {
  std::vector<ScoredGenome> pop;
  if (Status s = IndividualsFromProto(o.population(), &pop); !s.ok()) return s;
  for (auto& sg : pop) {
    is->population.push_back(std::move(sg.genome));
    is->fitness.push_back(std::move(sg.fitness));
  }
  if (need_rng || o.rng_words_size() > 0) {
    if (o.rng_words_size() != RngState::kWords) return Malformed("checkpoint rng_words size");
    std::copy(o.rng_words().begin(), o.rng_words().end(), is->rng.words.begin());
    is->rng.position = o.rng_position();
  }
  return Status::Ok();
}

}  // namespace

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
  // One island that is the job (its stall and best are the job's, never restarted): the layout
  // from before islands, byte for byte; otherwise every island in `islands`.
  const bool single = g.islands.size() == 1 && g.islands[0].stall == g.stall &&
                      g.islands[0].restarts == 0 &&
                      (!g.initialized || g.islands[0].best_cost == g.best_fitness.cost);
  if (single) {
    PopulationToProto(g.islands[0], o);
  } else {
    for (const opt::IslandState& is : g.islands) {
      auto* pi = o->add_islands();
      PopulationToProto(is, pi);
      pi->set_stall(is.stall);
      pi->set_best_cost(is.best_cost);
      pi->set_restarts(static_cast<uint32_t>(is.restarts));
    }
  }
  o->set_best_island(static_cast<uint32_t>(g.best_island));
  ToProto(ScoredGenome{0, g.best, g.best_fitness}, o->mutable_best());
  o->set_best_generation(g.best_generation);
  o->set_evaluations(g.evaluations);
  o->set_failures(g.failures);
  for (const auto& r : c.log) ToProto(r, p.add_log());
  for (const auto& b : c.best) ToProto(b, p.add_best());
  p.set_message(c.message);
  p.set_termination(ToProto(c.termination));
  for (const auto& q : c.quarantined) ToProto(q, p.add_quarantined());
  p.set_elapsed_s(c.elapsed_s);
  p.set_arithmetic(c.arithmetic);
  if (c.committee) ToProto(*c.committee, p.mutable_committee());
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
  if (o.islands_size() == 0) {
    opt::IslandState& is = g.islands.emplace_back();
    if (Status s = PopulationFromProto(o, o.initialized(), &is); !s.ok()) return s;
    is.stall = g.stall;
    is.best_cost = o.best().cost();
  } else {
    for (int k = 0; k < o.islands_size(); ++k) {
      const auto& pi = o.islands(k);
      opt::IslandState& is = g.islands.emplace_back();
      if (Status s = PopulationFromProto(pi, o.initialized(), &is); !s.ok())
        return Malformed("checkpoint islands[" + std::to_string(k) + "]: " + s.message());
      is.stall = pi.stall();
      is.best_cost = pi.best_cost();
      is.restarts = ClampInt(pi.restarts());
    }
  }
  g.best_island = ClampInt(o.best_island());
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
  c->termination = FromProto(p.termination());
  for (const auto& q : p.quarantined()) c->quarantined.push_back(FromProto(q));
  c->elapsed_s = p.elapsed_s();
  c->arithmetic = p.arithmetic();
  if (p.has_committee()) {
    c->committee.emplace();
    if (Status s = FromProto(p.committee(), &*c->committee); !s.ok()) return s;
  }
  return Status::Ok();
}

std::string EncodeStoredFile(std::string_view type, std::string_view payload) {
  pw::StoredFile f;
  f.set_type(std::string(type));
  f.set_payload(std::string(payload));
  f.set_length(payload.size());
  f.set_crc32(static_cast<uint32_t>(crc32(0L, reinterpret_cast<const Bytef*>(payload.data()),
                                          static_cast<uInt>(payload.size()))));
  return Deterministic(f);
}

Status DecodeStoredFile(std::string_view bytes, std::string_view type, std::string* payload) {
  pw::StoredFile f;
  if (!Parse(bytes, &f) || f.type().empty())
    return {StatusCode::kNotFound,
            "not a stored file (" + std::to_string(bytes.size()) + " bytes)"};
  if (f.type() != type)
    return {StatusCode::kDataLoss, "holds a " + f.type() + ", not a " + std::string(type)};
  if (f.payload().size() != f.length())
    return {StatusCode::kDataLoss, "truncated: " + std::to_string(f.payload().size()) + " of " +
                                       std::to_string(f.length()) + " payload bytes"};
  const auto crc =
      static_cast<uint32_t>(crc32(0L, reinterpret_cast<const Bytef*>(f.payload().data()),
                                  static_cast<uInt>(f.payload().size())));
  if (crc != f.crc32()) return {StatusCode::kDataLoss, "checksum mismatch (the file was altered)"};
  *payload = std::move(*f.mutable_payload());
  return Status::Ok();
}

}  // namespace pz::service
