// The checkpoint codec: JobCheckpoint ↔ proto, and the StoredFile frame (length + CRC-32) of the
// state directory's files.
#include "service/codec_detail.h"

#include <zlib.h>

#include <cmath>

namespace pz::service {
using namespace detail;

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
  p.set_arithmetic(c.arithmetic);
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
  c->arithmetic = p.arithmetic();
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
