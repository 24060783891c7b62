#include "opt/ga.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>
#include <sstream>
#include <utility>

namespace pz::opt {
namespace {

double NowSeconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

Status CheckProbability(const std::string& field, double p) {
  if (!(p >= 0 && p <= 1)) return InvalidArgument(FieldError(field, p, "must be in [0, 1]"));
  return Status::Ok();
}

Status CheckGenome(const Genome& g, int bits, const std::string& field) {
  if (g.bits.size() != static_cast<size_t>(bits)) {
    return InvalidArgument(FieldError(field + ".bits.size()", g.bits.size(),
                                      "must equal genome_bits = " + std::to_string(bits)));
  }
  for (size_t i = 0; i < g.bits.size(); ++i) {
    if (g.bits[i] > 1) {
      return InvalidArgument(
          FieldError(field + ".bits[" + std::to_string(i) + "]", int(g.bits[i]), "must be 0 or 1"));
    }
  }
  if (!g.reals.empty()) {
    return InvalidArgument(
        FieldError(field + ".reals.size()", g.reals.size(), "the binary GA carries no real genes"));
  }
  return Status::Ok();
}

bool Better(const FitnessResult& a, int ia, const FitnessResult& b, int ib) {
  return a.cost < b.cost || (a.cost == b.cost && ia < ib);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Options, records

int GaOptions::elite_count() const {
  return static_cast<int>(std::lround(population_size * elite_fraction));
}

Status GaOptions::Validate(const FieldNamer& namer) const {
  // The name of a field in the messages: the member's own, or what the caller's user wrote.
  const auto name = [&namer](const char* field) {
    return namer ? namer(field) : std::string(field);
  };
  if (population_size < 2) {
    return InvalidArgument(FieldError(name("population_size"), population_size, "must be >= 2"));
  }
  if (genome_bits < 3)
    return InvalidArgument(FieldError(name("genome_bits"), genome_bits, "must be >= 3"));
  if (!(elite_fraction > 0 && elite_fraction < 1)) {
    return InvalidArgument(FieldError(name("elite_fraction"), elite_fraction, "must be in (0, 1)"));
  }
  const int e = elite_count();
  if (e < 1 || e > population_size - 1) {
    return InvalidArgument(FieldError(name("elite_fraction"), elite_fraction,
                                      "round(" + name("population_size") + " * " +
                                          name("elite_fraction") + ") = " + std::to_string(e) +
                                          " must be 1 … " + name("population_size") + " − 1"));
  }
  if (tournament_size < 1) {
    return InvalidArgument(FieldError(name("tournament_size"), tournament_size, "must be >= 1"));
  }
  for (Status s : {CheckProbability(name("crossover_probability"), crossover_probability),
                   CheckProbability(name("mutation_probability"), mutation_probability)}) {
    if (!s.ok()) return s;
  }
  if (max_generations < 0) {
    return InvalidArgument(FieldError(name("max_generations"), max_generations, "must be >= 0"));
  }
  if (stall_generations < 0) {
    return InvalidArgument(
        FieldError(name("stall_generations"), stall_generations, "must be >= 0 (0 = never)"));
  }
  if (!(stall_relative >= 0 && stall_relative < 1))
    return InvalidArgument(FieldError(name("stall_relative"), stall_relative, "must be in [0, 1)"));
  if (std::isnan(target_cost))
    return InvalidArgument(FieldError(name("target_cost"), target_cost, "must not be NaN"));
  if (!std::isfinite(error_cost))
    return InvalidArgument(FieldError(name("error_cost"), error_cost, "must be finite"));
  if (islands < 1 || islands > kMaxIslands) {
    return InvalidArgument(FieldError(name("islands"), islands,
                                      "must be in [1, " + std::to_string(kMaxIslands) + "]"));
  }
  if (migration_interval < 0) {
    return InvalidArgument(FieldError(name("migration_interval"), migration_interval,
                                      "must be >= 0 (0 = no migration)"));
  }
  if (migrants < 0 || migrants >= population_size) {
    return InvalidArgument(FieldError(name("migrants"), migrants,
                                      "must be in [0, " + name("population_size") +
                                          " - 1 = " + std::to_string(population_size - 1) + "]"));
  }
  if (migration_interval > 0 && migrants == 0) {
    return InvalidArgument(FieldError(name("migrants"), migrants,
                                      "must be >= 1 when " + name("migration_interval") + " = " +
                                          std::to_string(migration_interval) + " > 0 (" +
                                          name("migration_interval") +
                                          " 0 runs the islands independently)"));
  }
  if (!(migration_margin >= 0 && migration_margin < 1)) {
    return InvalidArgument(FieldError(name("migration_margin"), migration_margin,
                                      "must be in [0, 1) (0 = every source)"));
  }
  if (!ValidTopology(topology)) {
    return InvalidArgument(FieldError(name("topology"), static_cast<int>(topology), kTopologyRule));
  }
  if (broadcast_interval < 0) {
    return InvalidArgument(FieldError(name("broadcast_interval"), broadcast_interval,
                                      "must be >= 0 (0 = no broadcast)"));
  }
  if (broadcast_interval > 0 && migrants == 0) {
    return InvalidArgument(FieldError(name("migrants"), migrants,
                                      "must be >= 1 when " + name("broadcast_interval") + " = " +
                                          std::to_string(broadcast_interval) + " > 0"));
  }
  if (!(broadcast_margin > 0 && broadcast_margin < 1)) {
    return InvalidArgument(
        FieldError(name("broadcast_margin"), broadcast_margin, "must be in (0, 1)"));
  }
  if (island_stall_generations < 0) {
    return InvalidArgument(FieldError(name("island_stall_generations"), island_stall_generations,
                                      "must be >= 0 (0 = never)"));
  }
  if (!island_mutation.empty() && island_mutation.size() != static_cast<size_t>(islands)) {
    return InvalidArgument(FieldError(name("island_mutation") + ".size()", island_mutation.size(),
                                      "must be 0 (the ladder: " + name("mutation_probability") +
                                          " × 1, 2, 3, 5) or " + name("islands") + " = " +
                                          std::to_string(islands)));
  }
  for (size_t i = 0; i < island_mutation.size(); ++i) {
    if (Status s = CheckProbability(name("island_mutation") + "[" + std::to_string(i) + "]",
                                    island_mutation[i]);
        !s.ok())
      return s;
  }
  if (output_moves < kAutoOutputMoves || output_moves > population_size - e) {
    return InvalidArgument(FieldError(
        name("output_moves"), output_moves,
        "must be in [0, " + name("population_size") + " − the elite = " +
            std::to_string(population_size - e) + "] (" + std::to_string(kAutoOutputMoves) +
            ": 0 with one island, " + "16 % of the offspring with several)"));
  }
  return Status::Ok();
}

std::vector<int> GaOptions::MigrationSources(int i) const {
  const int k = islands;
  if (k < 2) return {};
  switch (topology) {
    case MigrationTopology::kRing:
      return {(i + k - 1) % k};
    case MigrationTopology::kFullyConnected: {
      std::vector<int> all;
      for (int j = 0; j < k; ++j)
        if (j != i) all.push_back(j);
      return all;
    }
    case MigrationTopology::kRandom: {
      // A ring in a random order: Fisher–Yates with the topology's own stream.
      Rng rng(StreamSeed(seed, kTopologyStream));
      std::vector<int> order(k);
      std::iota(order.begin(), order.end(), 0);
      for (int j = k - 1; j > 0; --j) std::swap(order[j], order[rng.UniformBelow(j + 1)]);
      const int at = static_cast<int>(std::find(order.begin(), order.end(), i) - order.begin());
      return {order[(at + k - 1) % k]};
    }
  }
  return {};
}

bool GenerationSummary::SameOutcome(const GenerationSummary& o) const {
  return generation == o.generation && best_cost == o.best_cost && mean_cost == o.mean_cost &&
         median_cost == o.median_cost && worst_cost == o.worst_cost && improved == o.improved &&
         stall == o.stall && best_description == o.best_description &&
         evaluations == o.evaluations && evaluations_total == o.evaluations_total &&
         failures == o.failures && penalized == o.penalized && errors == o.errors &&
         quarantined == o.quarantined && failure_reasons == o.failure_reasons &&
         best_island == o.best_island && migrated == o.migrated && islands == o.islands;
}

std::string GenerationSummary::BriefReport() const {
  std::ostringstream os;
  os.precision(10);
  os << "gen " << generation << ": best " << best_cost << " mean " << mean_cost << " worst "
     << worst_cost << " stall " << stall << " evals " << evaluations << "/" << evaluations_total
     << " fail " << failures;
  if (!best_description.empty()) os << " [" << best_description << "]";
  if (!islands.empty()) {
    os << " island " << best_island << " of " << islands.size();
    int restarted = 0, immigrants = 0;
    for (const IslandSummary& i : islands) {
      restarted += i.restarted;
      immigrants += i.immigrants;
    }
    if (migrated) os << ", migrated " << immigrants;
    if (restarted) os << ", restarted " << restarted;
  }
  return os.str();
}

const char* GaTerminationName(GaTermination t) {
  switch (t) {
    case GaTermination::kMaxGenerations:
      return "MAX_GENERATIONS";
    case GaTermination::kStall:
      return "STALL";
    case GaTermination::kCancelled:
      return "CANCELLED";
    case GaTermination::kTargetReached:
      return "TARGET_REACHED";
  }
  return "UNKNOWN";
}

std::string DescribeTermination(GaTermination termination, double best_cost, int stall,
                                uint64_t best_generation, uint64_t generations, int max_generations,
                                double target_cost) {
  std::ostringstream os;
  os.precision(10);
  switch (termination) {
    case GaTermination::kMaxGenerations:
      os << "reached the maximum of " << max_generations << " generations";
      break;
    case GaTermination::kStall:
      os << "no improvement of the best cost " << best_cost << " in " << stall
         << " generations (since generation " << best_generation << ")";
      break;
    case GaTermination::kCancelled:
      os << "cancelled after generation " << generations;
      break;
    case GaTermination::kTargetReached:
      os << "best cost " << best_cost << " <= target " << target_cost;
      break;
  }
  return os.str();
}

std::string GaSummary::BriefReport() const {
  std::ostringstream os;
  os.precision(10);
  os << "GA " << GaTerminationName(termination) << " after generation " << generations
     << ": best cost " << best_fitness.cost << " (generation " << best_generation
     << (islands > 1 ? ", island " + std::to_string(best_island) + " of " + std::to_string(islands)
                     : std::string())
     << "), " << evaluations << " evaluations, " << failures << " failures, " << wall_time_s
     << " s. " << message;
  return os.str();
}

Status GaState::Validate(const GaOptions& options) const {
  if (!initialized) return Status::Ok();
  const size_t n = options.population_size;
  if (islands.size() != static_cast<size_t>(options.islands)) {
    return InvalidArgument(FieldError("state.islands.size()", islands.size(),
                                      "must equal islands = " + std::to_string(options.islands)));
  }
  double top = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < islands.size(); ++k) {
    const IslandState& is = islands[k];
    const std::string f = "state.islands[" + std::to_string(k) + "]";
    if (is.population.size() != n) {
      return InvalidArgument(FieldError(f + ".population.size()", is.population.size(),
                                        "must equal population_size = " + std::to_string(n)));
    }
    if (is.fitness.size() != n) {
      return InvalidArgument(FieldError(f + ".fitness.size()", is.fitness.size(),
                                        "must equal population_size = " + std::to_string(n)));
    }
    for (size_t i = 0; i < n; ++i) {
      Status s = CheckGenome(is.population[i], options.genome_bits,
                             f + ".population[" + std::to_string(i) + "]");
      if (!s.ok()) return s;
      const std::string fc = f + ".fitness[" + std::to_string(i) + "].cost";
      if (!std::isfinite(is.fitness[i].cost))
        return InvalidArgument(FieldError(fc, is.fitness[i].cost, "must be finite"));
      if (i > 0 && is.fitness[i].cost < is.fitness[i - 1].cost) {
        return InvalidArgument(FieldError(
            fc, is.fitness[i].cost, "population must be ranked: cost below its predecessor's"));
      }
    }
    if (!std::isfinite(is.best_cost) || is.best_cost < is.fitness[0].cost) {
      return InvalidArgument(FieldError(f + ".best_cost", is.best_cost,
                                        "must be finite and not below the island's best"));
    }
    if (is.stall < 0) return InvalidArgument(FieldError(f + ".stall", is.stall, "must be >= 0"));
    if (is.restarts < 0)
      return InvalidArgument(FieldError(f + ".restarts", is.restarts, "must be >= 0"));
    if (Status s = is.rng.Validate(); !s.ok()) return InvalidArgument(f + "." + s.message());
    top = std::min(top, is.fitness[0].cost);
  }
  Status s = CheckGenome(best, options.genome_bits, "state.best");
  if (!s.ok()) return s;
  if (!std::isfinite(best_fitness.cost) || best_fitness.cost < top) {
    return InvalidArgument(FieldError("state.best_fitness.cost", best_fitness.cost,
                                      "must be finite and not below the islands' best"));
  }
  if (best_island < 0 || best_island >= options.islands) {
    return InvalidArgument(
        FieldError("state.best_island", best_island,
                   "must be in [0, islands - 1 = " + std::to_string(options.islands - 1) + "]"));
  }
  if (stall < 0) return InvalidArgument(FieldError("state.stall", stall, "must be >= 0"));
  if (best_generation > generation) {
    return InvalidArgument(
        FieldError("state.best_generation", best_generation,
                   "must be <= state.generation = " + std::to_string(generation)));
  }
  if (evaluations < 0 || failures < 0 || failures > evaluations) {
    return InvalidArgument(FieldError(
        "state.failures", failures,
        "counters must satisfy 0 <= failures <= evaluations = " + std::to_string(evaluations)));
  }
  return Status::Ok();
}

// ---------------------------------------------------------------------------------------------
// GeneticAlgorithm

GeneticAlgorithm::GeneticAlgorithm(const GaOptions& options, BatchEvaluator* evaluator)
    : options_(options), evaluator_(evaluator) {
  ThrowIfError(options_.Validate());
  if (evaluator_ == nullptr) throw InputError("evaluator: must not be null");
  state_.islands.resize(options_.islands);
  for (int i = 0; i < options_.islands; ++i) {
    rngs_.emplace_back(StreamSeed(options_.seed, static_cast<uint64_t>(i)));
    state_.islands[i].rng = rngs_.back().state();
    sources_.push_back(options_.MigrationSources(i));
    everyone_.emplace_back();
    for (int j = 0; j < options_.islands; ++j)
      if (j != i) everyone_.back().push_back(j);
  }
}

void GeneticAlgorithm::AddGenerationCallback(GenerationCallback callback) {
  callbacks_.push_back(std::move(callback));
}

void GeneticAlgorithm::SetDescriber(Describer describer) { describer_ = std::move(describer); }
void GeneticAlgorithm::SetMove(Move move) { move_ = std::move(move); }

void GeneticAlgorithm::SetRepair(Repair repair) { repair_ = std::move(repair); }

void GeneticAlgorithm::RestoreState(GaState state) {
  ThrowIfError(state.Validate(options_));
  if (!state.initialized)
    state.islands = state_.islands;  // nothing drawn yet: the seeded generators
  for (int i = 0; i < options_.islands; ++i) rngs_[i] = Rng(state.islands[i].rng);
  state_ = std::move(state);
}

int GeneticAlgorithm::Tournament(Rng& rng) {
  const uint64_t elite = static_cast<uint64_t>(options_.elite_count());
  // The population is ranked, so the best of the draws is the smallest index.
  uint64_t winner = rng.UniformBelow(elite);
  for (int k = 1; k < options_.tournament_size; ++k)
    winner = std::min(winner, rng.UniformBelow(elite));
  return static_cast<int>(winner);
}

const GeometricGaps& GeneticAlgorithm::MutationGaps(int i) {
  const double p = options_.MutationProbability(i);
  auto it = mutation_gaps_.find(p);
  if (it == mutation_gaps_.end()) it = mutation_gaps_.try_emplace(p, p, options_.genome_bits).first;
  return it->second;
}

void GeneticAlgorithm::DrawUniform(Rng& rng, int count, std::vector<Genome>* out) {
  // Uniform bits, 64 per draw, most significant first.
  const int bits = options_.genome_bits;
  for (int i = 0; i < count; ++i) {
    Genome& g = out->emplace_back();
    g.bits.resize(bits);
    for (int b = 0; b < bits; b += 64) {
      const uint64_t x = rng.NextU64();
      for (int k = 0; k < 64 && b + k < bits; ++k) g.bits[b + k] = (x >> (63 - k)) & 1u;
    }
  }
}

std::vector<std::vector<FitnessResult>> GeneticAlgorithm::Evaluate(std::vector<Draft>& drafts) {
  // One batch for all islands: island i's fresh genome j has population index
  // i · population_size + (kept count + j). One island's fresh genomes are the batch as they are;
  // several islands' are moved into one batch and back (no copy either way).
  const int n = options_.population_size;
  if (repair_)
    for (Draft& d : drafts)
      for (Genome& g : d.fresh) repaired_ += repair_(g) ? 1 : 0;
  std::vector<Genome> joined;
  std::vector<int> indices;
  for (size_t i = 0; i < drafts.size(); ++i) {
    const int first = static_cast<int>(i) * n + drafts[i].kept_count();
    for (size_t j = 0; j < drafts[i].fresh.size(); ++j) {
      if (drafts.size() > 1) joined.push_back(std::move(drafts[i].fresh[j]));
      indices.push_back(first + static_cast<int>(j));
    }
  }
  const std::span<const Genome> genomes = drafts.size() == 1
                                              ? std::span<const Genome>(drafts[0].fresh)
                                              : std::span<const Genome>(joined);
  std::vector<FitnessResult> out(genomes.size());
  const uint64_t generation = state_.initialized ? state_.generation + 1 : 0;
  try {
    evaluator_->Evaluate(EvalBatch{generation, genomes, indices}, out);
  } catch (...) {
    // leave the GA as it was before this generation
    for (size_t i = 0; i < rngs_.size(); ++i) rngs_[i] = Rng(state_.islands[i].rng);
    throw;
  }
  if (drafts.size() > 1) {
    size_t from = 0;
    for (Draft& d : drafts)
      for (Genome& g : d.fresh) g = std::move(joined[from++]);
  }
  std::vector<std::vector<FitnessResult>> split(drafts.size());
  size_t at = 0;
  for (size_t i = 0; i < drafts.size(); ++i) {
    for (size_t j = 0; j < drafts[i].fresh.size(); ++j, ++at) {
      SanitizeFitness(out[at], options_.error_cost);
      split[i].push_back(std::move(out[at]));
    }
  }
  return split;
}

const GenerationSummary& GeneticAlgorithm::Initialize(std::span<const Genome> seeds) {
  PZ_CHECK_MSG(!state_.initialized, "GeneticAlgorithm::Initialize called twice");
  const double start = NowSeconds();
  const int n = options_.population_size, bits = options_.genome_bits;
  if (seeds.size() > static_cast<size_t>(n)) {
    throw InputError(FieldError("seeds.size()", seeds.size(), "must be <= population_size"));
  }
  std::vector<Draft> drafts(options_.islands);
  for (size_t i = 0; i < seeds.size(); ++i) {
    ThrowIfError(CheckGenome(seeds[i], bits, "seeds[" + std::to_string(i) + "]"));
    drafts[0].fresh.push_back(seeds[i]);
  }
  for (int k = 0; k < options_.islands; ++k)
    DrawUniform(rngs_[k], n - static_cast<int>(drafts[k].fresh.size()), &drafts[k].fresh);
  auto evaluated = Evaluate(drafts);
  return Finish(std::move(drafts), std::move(evaluated), start);
}

GeneticAlgorithm::Draft GeneticAlgorithm::Breed(int island) {
  const int n = options_.population_size, bits = options_.genome_bits;
  const int elite = options_.elite_count(), n_off = n - elite;
  const BernoulliThreshold cross(options_.crossover_probability);
  const GeometricGaps& mutate = MutationGaps(island);
  Rng& rng = rngs_[island];
  const IslandState& is = state_.islands[island];

  // The last `moves` offspring are the move's (file comment, 9.), made after the bred ones.
  const int moves = move_ ? options_.OutputMoves() : 0, n_bred = n_off - moves;
  Draft d;
  d.fresh.resize(n_off);
  for (int o = 0; o < n_bred; o += 2) {
    const Genome& pa = is.population[Tournament(rng)];
    const Genome& pb = is.population[Tournament(rng)];
    Genome& c1 = d.fresh[o];
    Genome c2_storage;
    Genome& c2 = o + 1 < n_bred ? d.fresh[o + 1] : c2_storage;  // an odd last child is dropped
    c1.bits = pa.bits;
    c2.bits = pb.bits;
    if (rng.Bernoulli(cross)) {
      // Two distinct cut points in 1 … bits − 1; the segment [lo, hi) is exchanged.
      const int p = 1 + static_cast<int>(rng.UniformBelow(bits - 1));
      int q = 1 + static_cast<int>(rng.UniformBelow(bits - 2));
      if (q >= p) ++q;
      const int lo = std::min(p, q), hi = std::max(p, q);
      std::swap_ranges(c1.bits.begin() + lo, c1.bits.begin() + hi, c2.bits.begin() + lo);
    }
    for (Genome* c : {&c1, &c2}) {
      if (c == &c2_storage) continue;
      // Each bit flips with probability p, independently: the positions of the flips are drawn
      // as geometric gaps (one draw per flip, plus one that ends the genome) instead of one
      // Bernoulli draw per bit.
      for (int pos = rng.Gap(mutate); pos < bits; pos += 1 + rng.Gap(mutate)) c->bits[pos] ^= 1u;
    }
  }
  if (moves > 0) {
    move_(is.population.front(), rng, std::span<Genome>(d.fresh).subspan(n_bred));
    for (int o = n_bred; o < n_off; ++o)
      PZ_CHECK_MSG(CheckGenome(d.fresh[o], bits, "move").ok(),
                   "the move wrote a genome of the wrong length or non-0/1 bits");
  }
  d.elite = elite;  // kept: moved from the state once the generation is evaluated (Finish)
  return d;
}

std::vector<std::pair<Genome, FitnessResult>> GeneticAlgorithm::Immigrants(
    int island, const std::vector<int>& sources, double below) const {
  std::vector<std::pair<Genome, FitnessResult>> in;
  const int m = options_.migrants;
  for (int s : sources) {
    const IslandState& src = state_.islands[s];
    if (!(src.fitness.front().cost < below)) continue;
    for (int r = 0; r < m; ++r) in.emplace_back(src.population[r], src.fitness[r]);
  }
  // Best first; ties keep source order, then rank.
  std::stable_sort(in.begin(), in.end(),
                   [](const auto& a, const auto& b) { return a.second.cost < b.second.cost; });
  if (in.size() > static_cast<size_t>(m)) in.resize(m);
  return in;
}

GeneticAlgorithm::Draft GeneticAlgorithm::Restart(int island) {
  Draft d;
  d.restarted = true;
  // From the topology's sources as a migration would send them; none without migration.
  const std::vector<int> none;
  for (auto& [g, f] : Immigrants(island, options_.migrates() ? sources_[island] : none,
                                 std::numeric_limits<double>::infinity())) {
    d.kept.push_back(std::move(g));
    d.kept_fitness.push_back(std::move(f));
  }
  DrawUniform(rngs_[island], options_.population_size - static_cast<int>(d.kept.size()), &d.fresh);
  return d;
}

const GenerationSummary& GeneticAlgorithm::Step() {
  PZ_CHECK_MSG(state_.initialized, "GeneticAlgorithm::Step before Initialize");
  const double start = NowSeconds();
  std::vector<Draft> drafts;
  drafts.reserve(options_.islands);
  for (int k = 0; k < options_.islands; ++k) {
    const bool restart = options_.island_stall_generations > 0 &&
                         state_.islands[k].stall >= options_.island_stall_generations;
    drafts.push_back(restart ? Restart(k) : Breed(k));
  }
  auto evaluated = Evaluate(drafts);
  return Finish(std::move(drafts), std::move(evaluated), start);
}

std::vector<int> GeneticAlgorithm::Migrate(const std::vector<std::vector<int>>& sources, double m) {
  const int k_islands = options_.islands, n = options_.population_size;
  // Every island's immigrants are chosen before any island receives (the order cannot matter).
  std::vector<std::vector<std::pair<Genome, FitnessResult>>> incoming(k_islands);
  for (int k = 0; k < k_islands; ++k) {
    // The margin's gate (file comment of ga.h, 6.): sources better than this island's best by more
    // than m · |its best|; without a margin, every source.
    const double own = state_.islands[k].fitness.front().cost;
    incoming[k] = Immigrants(
        k, sources[k], m > 0 ? own - m * std::abs(own) : std::numeric_limits<double>::infinity());
  }
  std::vector<int> taken(k_islands, 0);
  for (int k = 0; k < k_islands; ++k) {
    IslandState& is = state_.islands[k];
    // Best migrant ↔ worst resident, while the migrant is strictly better.
    for (size_t j = 0; j < incoming[k].size(); ++j) {
      const size_t slot = n - 1 - j;
      if (!(incoming[k][j].second.cost < is.fitness[slot].cost)) break;
      is.population[slot] = std::move(incoming[k][j].first);
      is.fitness[slot] = std::move(incoming[k][j].second);
      ++taken[k];
    }
    if (taken[k] == 0) continue;
    std::vector<int> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::stable_sort(order.begin(), order.end(),
                     [&is](int a, int b) { return is.fitness[a].cost < is.fitness[b].cost; });
    std::vector<Genome> population(n);
    std::vector<FitnessResult> fitness(n);
    for (int r = 0; r < n; ++r) {
      population[r] = std::move(is.population[order[r]]);
      fitness[r] = std::move(is.fitness[order[r]]);
    }
    is.population = std::move(population);
    is.fitness = std::move(fitness);
    if (is.fitness.front().cost < is.best_cost) {
      is.best_cost = is.fitness.front().cost;
      is.stall = 0;
    }
  }
  return taken;
}

namespace {

/// A generation's evaluations, failures and their reasons counted into its summary.
void CountFailures(const std::vector<FitnessResult>& ev, GenerationSummary& s) {
  s.evaluations += static_cast<int>(ev.size());
  for (const FitnessResult& f : ev) {
    if (f.status == FitnessStatus::kOk) continue;
    ++s.failures;
    (f.status == FitnessStatus::kPenalized ? s.penalized : s.errors)++;
    ++s.failure_reasons[f.reason];
  }
}

/// Mean, median and worst cost over every island's population.
void SetCostSpread(const std::vector<IslandState>& islands, int k_islands, GenerationSummary& s) {
  std::vector<double> costs;
  for (const IslandState& is : islands)
    for (const FitnessResult& f : is.fitness) costs.push_back(f.cost);
  if (k_islands > 1) std::sort(costs.begin(), costs.end());  // one island is ranked already
  const int n = static_cast<int>(costs.size());
  s.worst_cost = costs.back();
  double mean = 0;
  for (double c : costs) mean += c / n;  // cannot overflow for finite costs
  s.mean_cost = std::isfinite(mean) ? mean : std::numeric_limits<double>::max();
  // The costs are sorted: the median is their middle (the mean of the two middle costs).
  const double lo = costs[(n - 1) / 2], hi = costs[n / 2];
  const double median = lo + (hi - lo) / 2;
  s.median_cost = std::isfinite(median) ? median : std::numeric_limits<double>::max();
}

}  // namespace

const GenerationSummary& GeneticAlgorithm::Finish(std::vector<Draft> drafts,
                                                  std::vector<std::vector<FitnessResult>> evaluated,
                                                  double start_s) {
  const int k_islands = options_.islands;
  GenerationSummary s;
  s.generation = state_.initialized ? state_.generation + 1 : 0;
  for (int k = 0; k < k_islands; ++k) {
    Draft& d = drafts[k];
    const std::vector<FitnessResult>& ev = evaluated[k];
    CountFailures(ev, s);
    IslandState& is = state_.islands[k];
    if (d.elite >
        0) {  // the elite, left in the state while the generation was evaluated, goes first
      std::vector<Genome> kept(std::make_move_iterator(is.population.begin()),
                               std::make_move_iterator(is.population.begin() + d.elite));
      std::vector<FitnessResult> kept_fitness(
          std::make_move_iterator(is.fitness.begin()),
          std::make_move_iterator(is.fitness.begin() + d.elite));
      kept.insert(kept.end(), std::make_move_iterator(d.kept.begin()),
                  std::make_move_iterator(d.kept.end()));
      kept_fitness.insert(kept_fitness.end(), std::make_move_iterator(d.kept_fitness.begin()),
                          std::make_move_iterator(d.kept_fitness.end()));
      d.kept = std::move(kept);
      d.kept_fitness = std::move(kept_fitness);
      d.elite = 0;
    }
    // kept first, then the evaluated ones; ranked by (cost, index), stable.
    const int n = static_cast<int>(d.kept.size() + d.fresh.size());
    auto genome = [&d](int i) -> Genome& {
      return i < static_cast<int>(d.kept.size()) ? d.kept[i] : d.fresh[i - d.kept.size()];
    };
    auto fit = [&d, &ev](int i) -> const FitnessResult& {
      return i < static_cast<int>(d.kept.size()) ? d.kept_fitness[i] : ev[i - d.kept.size()];
    };
    std::vector<int> order(n);
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(),
              [&fit](int a, int b) { return Better(fit(a), a, fit(b), b); });
    is.population.resize(n);
    is.fitness.resize(n);
    for (int r = 0; r < n; ++r) {
      is.population[r] = std::move(genome(order[r]));
      is.fitness[r] = fit(order[r]);
    }
    const double top = is.fitness.front().cost;
    if (!state_.initialized || d.restarted || top < is.best_cost) {
      is.best_cost = top;
      is.stall = 0;
    } else {
      ++is.stall;
    }
    is.restarts += d.restarted;
    is.rng = rngs_[k].state();
  }

  // The job's best: the best island's (ties: the lowest island index).
  int best_island = 0;
  for (int k = 1; k < k_islands; ++k)
    if (state_.islands[k].fitness.front().cost < state_.islands[best_island].fitness.front().cost)
      best_island = k;
  const IslandState& bi = state_.islands[best_island];
  const FitnessResult& top = bi.fitness.front();
  s.improved = !state_.initialized || top.cost < state_.best_fitness.cost;
  const bool had_best = state_.initialized;
  const double previous = state_.best_fitness.cost;
  if (s.improved) {
    state_.best = bi.population.front();
    state_.best_fitness = top;
    state_.best_generation = s.generation;
    state_.best_island = best_island;
    // A step below the relative threshold keeps the best but does not reset the stall count.
    const bool step = !had_best || top.cost < previous * (1 - options_.stall_relative);
    state_.stall = step ? 0 : state_.stall + 1;
  } else {
    ++state_.stall;
  }
  state_.initialized = true;
  state_.generation = s.generation;

  s.stall = state_.stall;
  s.best_cost = top.cost;
  s.best_island = best_island;
  if (describer_) s.best_description = describer_(bi.population.front());
  SetCostSpread(state_.islands, k_islands, s);

  std::vector<int> taken(k_islands, 0);
  if (options_.migrates() && s.generation > 0 && s.generation % options_.migration_interval == 0) {
    taken = Migrate(sources_, options_.migration_margin);
    s.migrated = true;
  } else if (options_.broadcasts() && s.generation > 0 &&
             s.generation % options_.broadcast_interval == 0) {
    taken = Migrate(everyone_, options_.broadcast_margin);
    s.migrated = true;
  }
  if (k_islands > 1) {
    for (int k = 0; k < k_islands; ++k) {
      const IslandState& is = state_.islands[k];
      s.islands.push_back({is.best_cost, is.stall, taken[k], drafts[k].restarted});
    }
  }
  state_.evaluations += s.evaluations;
  state_.failures += s.failures;
  s.evaluations_total = state_.evaluations;
  s.wall_time_s = NowSeconds() - start_s;
  state_.log.push_back(std::move(s));
  const GenerationSummary& logged = state_.log.back();
  for (const GenerationCallback& cb : callbacks_) cb(logged);
  return state_.log.back();
}

std::optional<GaTermination> GeneticAlgorithm::CheckTermination() const {
  if (!state_.initialized)
    return cancel_.load() ? std::optional(GaTermination::kCancelled) : std::nullopt;
  if (state_.best_fitness.cost <= options_.target_cost) return GaTermination::kTargetReached;
  if (options_.stall_generations > 0 && state_.stall >= options_.stall_generations)
    return GaTermination::kStall;
  if (state_.generation >= static_cast<uint64_t>(options_.max_generations))
    return GaTermination::kMaxGenerations;
  if (cancel_.load()) return GaTermination::kCancelled;
  return std::nullopt;
}

GaSummary GeneticAlgorithm::MakeSummary(GaTermination termination, double wall_time_s) const {
  GaSummary s;
  s.termination = termination;
  s.generations = state_.generation;
  s.best = state_.best;
  s.best_fitness = state_.best_fitness;
  s.best_generation = state_.best_generation;
  s.best_island = state_.best_island;
  s.islands = options_.islands;
  s.evaluations = state_.evaluations;
  s.failures = state_.failures;
  s.wall_time_s = wall_time_s;
  s.message = DescribeTermination(termination, state_.best_fitness.cost, state_.stall,
                                  state_.best_generation, state_.generation,
                                  options_.max_generations, options_.target_cost);
  return s;
}

GaSummary GeneticAlgorithm::Run() {
  const double start = NowSeconds();
  for (;;) {
    if (std::optional<GaTermination> t = CheckTermination())
      return MakeSummary(*t, NowSeconds() - start);
    if (!state_.initialized) {
      Initialize();
    } else {
      Step();
    }
  }
}

}  // namespace pz::opt
