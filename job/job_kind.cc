#include "job/job_kind.h"

namespace pz::job {

using opt::FitnessFunction;

opt::GaOptions ToGaOptions(const JobSpec& spec, const GenomeLayout& layout) {
  opt::GaOptions o;
  const GaSettings g = spec.ga.value_or(GaSettings{});
  o.population_size = g.population;
  o.genome_bits = layout.bits;
  o.elite_fraction = g.elite_fraction;
  o.tournament_size = g.tournament;
  o.crossover_probability = g.crossover_probability;
  o.mutation_probability = g.mutation_probability;
  o.max_generations = g.generations;
  o.stall_generations = g.stall_generations;
  if (const auto* h = std::get_if<HgannProblem>(&spec.problem))  // the preset's relative step
    o.stall_relative =
        HgannSearchPreset(h->preset).value_or(*HgannSearchPreset("")).stall_relative;
  o.islands = g.islands;
  o.migration_interval = g.migration_interval;
  o.migrants = g.migrants;
  o.topology = g.topology;
  o.migration_margin = g.migration_margin;
  o.island_stall_generations = g.island_stall_generations;
  o.broadcast_interval = g.broadcast_interval;
  o.broadcast_margin = g.broadcast_margin;
  o.island_mutation = g.island_mutation;
  o.output_moves = g.output_moves;
  if (spec.limits.target_cost) o.target_cost = *spec.limits.target_cost;
  o.error_cost = spec.limits.penalty_cost;
  o.seed = spec.seed;
  return o;
}

void JobKindRegistry::Register(JobKind kind) {
  std::lock_guard lock(mu_);
  std::string name = kind.name;
  kinds_[name] = std::make_shared<const JobKind>(std::move(kind));
}

const JobKind* JobKindRegistry::Find(const std::string& name) const {
  std::lock_guard lock(mu_);
  auto it = kinds_.find(name);
  return it == kinds_.end() ? nullptr : it->second.get();
}

std::vector<FieldViolation> JobKindRegistry::Validate(const JobSpec& spec) const {
  std::vector<FieldViolation> out = spec.Validate();
  if (spec.kind().empty()) return out;
  const JobKind* k = Find(spec.kind());
  if (!k) {
    out.push_back({spec.kind(), spec.kind() + ": job kind not available on this master"});
    return out;
  }
  if (!k->move && spec.ga && spec.ga->output_moves > 0) {
    out.push_back({"ga.output_moves", "ga.output_moves = " + std::to_string(spec.ga->output_moves) +
                                          ": the " + spec.kind() +
                                          " kind has no output move; must be 0 or unset"});
  }
  if (k->validate) {
    auto more = k->validate(spec);
    out.insert(out.end(), more.begin(), more.end());
  }
  return out;
}

Status JobKindRegistry::Layout(const JobSpec& spec, GenomeLayout* layout) const {
  const JobKind* k = Find(spec.kind());
  if (!k || !k->layout) return NotFound("job kind '" + spec.kind() + "' has no genome layout");
  return k->layout(spec, layout);
}

Status JobKindRegistry::MakeFitness(const JobSpec& spec,
                                    std::unique_ptr<FitnessFunction>* out) const {
  const JobKind* k = Find(spec.kind());
  if (!k || !k->make_fitness) return NotFound("job kind '" + spec.kind() + "' has no fitness");
  return k->make_fitness(spec, out);
}

Status JobKindRegistry::Networks(const JobSpec& spec, std::span<const opt::Genome> genomes,
                                 std::vector<model::Network>* out) const {
  const JobKind* k = Find(spec.kind());
  if (!k || !k->networks) return NotFound("job kind '" + spec.kind() + "' has no networks");
  return k->networks(spec, genomes, out);
}

Status JobKindRegistry::Move(const JobSpec& spec, opt::GeneticAlgorithm::Move* out) const {
  *out = nullptr;
  const JobKind* k = Find(spec.kind());
  if (!k || !k->move) return Status::Ok();
  return k->move(spec, out);
}

Status JobKindRegistry::Repair(const JobSpec& spec, opt::GeneticAlgorithm::Repair* out) const {
  *out = nullptr;
  const JobKind* k = Find(spec.kind());
  if (!k || !k->repair) return Status::Ok();
  return k->repair(spec, out);
}

Status JobKindRegistry::Seeds(const JobSpec& spec, std::vector<opt::Genome>* out) const {
  out->clear();
  const JobKind* k = Find(spec.kind());
  if (!k || !k->seeds) return Status::Ok();
  return k->seeds(spec, out);
}

Status JobKindRegistry::Committee(const JobSpec& spec, const opt::Genome& best,
                                  LawCommittee* out) const {
  const JobKind* k = Find(spec.kind());
  if (!k || !k->committee) return {StatusCode::kNotFound, "no committee for this kind"};
  return k->committee(spec, best, out);
}

}  // namespace pz::job
