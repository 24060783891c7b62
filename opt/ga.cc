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

Status CheckProbability(const char* field, double p) {
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
      return InvalidArgument(FieldError(field + ".bits[" + std::to_string(i) + "]", int(g.bits[i]),
                                        "must be 0 or 1"));
    }
  }
  if (!g.reals.empty()) {
    return InvalidArgument(FieldError(field + ".reals.size()", g.reals.size(),
                                      "the binary GA carries no real genes"));
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

Status GaOptions::Validate() const {
  if (population_size < 2) return InvalidArgument(FieldError("population_size", population_size, "must be >= 2"));
  if (genome_bits < 3) return InvalidArgument(FieldError("genome_bits", genome_bits, "must be >= 3"));
  if (!(elite_fraction > 0 && elite_fraction < 1)) {
    return InvalidArgument(FieldError("elite_fraction", elite_fraction, "must be in (0, 1)"));
  }
  const int e = elite_count();
  if (e < 1 || e > population_size - 1) {
    return InvalidArgument(FieldError("elite_fraction", elite_fraction,
                                      "round(population_size * elite_fraction) = " + std::to_string(e) +
                                          " must be 1 … population_size − 1"));
  }
  if (tournament_size < 1) return InvalidArgument(FieldError("tournament_size", tournament_size, "must be >= 1"));
  for (Status s : {CheckProbability("crossover_probability", crossover_probability),
                   CheckProbability("mutation_probability", mutation_probability)}) {
    if (!s.ok()) return s;
  }
  if (max_generations < 0) return InvalidArgument(FieldError("max_generations", max_generations, "must be >= 0"));
  if (stall_generations < 0) {
    return InvalidArgument(FieldError("stall_generations", stall_generations, "must be >= 0 (0 = never)"));
  }
  if (std::isnan(target_cost)) return InvalidArgument(FieldError("target_cost", target_cost, "must not be NaN"));
  if (!std::isfinite(error_cost)) return InvalidArgument(FieldError("error_cost", error_cost, "must be finite"));
  return Status::Ok();
}

bool GenerationSummary::SameOutcome(const GenerationSummary& o) const {
  return generation == o.generation && best_cost == o.best_cost && mean_cost == o.mean_cost &&
         median_cost == o.median_cost &&
         worst_cost == o.worst_cost && improved == o.improved && stall == o.stall &&
         best_description == o.best_description && evaluations == o.evaluations &&
         evaluations_total == o.evaluations_total && failures == o.failures &&
         penalized == o.penalized && errors == o.errors && quarantined == o.quarantined &&
         failure_reasons == o.failure_reasons;
}

std::string GenerationSummary::BriefReport() const {
  std::ostringstream os;
  os.precision(10);
  os << "gen " << generation << ": best " << best_cost << " mean " << mean_cost << " worst "
     << worst_cost << " stall " << stall << " evals " << evaluations << "/" << evaluations_total
     << " fail " << failures;
  if (!best_description.empty()) os << " [" << best_description << "]";
  return os.str();
}

const char* GaTerminationName(GaTermination t) {
  switch (t) {
    case GaTermination::kMaxGenerations: return "MAX_GENERATIONS";
    case GaTermination::kStall: return "STALL";
    case GaTermination::kCancelled: return "CANCELLED";
    case GaTermination::kTargetReached: return "TARGET_REACHED";
  }
  return "UNKNOWN";
}

std::optional<GaTermination> ParseGaTermination(std::string_view name) {
  for (GaTermination t : {GaTermination::kMaxGenerations, GaTermination::kStall, GaTermination::kCancelled,
                          GaTermination::kTargetReached})
    if (name == GaTerminationName(t)) return t;
  return std::nullopt;
}

std::string DescribeTermination(GaTermination termination, double best_cost, int stall, uint64_t best_generation,
                                uint64_t generations, int max_generations, double target_cost) {
  std::ostringstream os;
  os.precision(10);
  switch (termination) {
    case GaTermination::kMaxGenerations:
      os << "reached the maximum of " << max_generations << " generations";
      break;
    case GaTermination::kStall:
      os << "no improvement of the best cost " << best_cost << " in " << stall << " generations (since generation "
         << best_generation << ")";
      break;
    case GaTermination::kCancelled: os << "cancelled after generation " << generations; break;
    case GaTermination::kTargetReached: os << "best cost " << best_cost << " <= target " << target_cost; break;
  }
  return os.str();
}

std::string GaSummary::BriefReport() const {
  std::ostringstream os;
  os.precision(10);
  os << "GA " << GaTerminationName(termination) << " after generation " << generations << ": best cost "
     << best_fitness.cost << " (generation " << best_generation << "), " << evaluations
     << " evaluations, " << failures << " failures, " << wall_time_s << " s. " << message;
  return os.str();
}

Status GaState::Validate(const GaOptions& options) const {
  if (!initialized) return Status::Ok();
  const size_t n = options.population_size;
  if (population.size() != n) {
    return InvalidArgument(FieldError("state.population.size()", population.size(),
                                      "must equal population_size = " + std::to_string(n)));
  }
  if (fitness.size() != n) {
    return InvalidArgument(FieldError("state.fitness.size()", fitness.size(),
                                      "must equal population_size = " + std::to_string(n)));
  }
  for (size_t i = 0; i < n; ++i) {
    Status s = CheckGenome(population[i], options.genome_bits, "state.population[" + std::to_string(i) + "]");
    if (!s.ok()) return s;
    if (!std::isfinite(fitness[i].cost)) {
      return InvalidArgument(FieldError("state.fitness[" + std::to_string(i) + "].cost", fitness[i].cost,
                                        "must be finite"));
    }
    if (i > 0 && fitness[i].cost < fitness[i - 1].cost) {
      return InvalidArgument(FieldError("state.fitness[" + std::to_string(i) + "].cost", fitness[i].cost,
                                        "population must be ranked: cost below its predecessor's"));
    }
  }
  Status s = CheckGenome(best, options.genome_bits, "state.best");
  if (!s.ok()) return s;
  if (!std::isfinite(best_fitness.cost) || best_fitness.cost < fitness[0].cost) {
    return InvalidArgument(FieldError("state.best_fitness.cost", best_fitness.cost,
                                      "must be finite and not below the population's best"));
  }
  if (stall < 0) return InvalidArgument(FieldError("state.stall", stall, "must be >= 0"));
  if (best_generation > generation) {
    return InvalidArgument(FieldError("state.best_generation", best_generation,
                                      "must be <= state.generation = " + std::to_string(generation)));
  }
  if (evaluations < 0 || failures < 0 || failures > evaluations) {
    return InvalidArgument(FieldError("state.failures", failures,
                                      "counters must satisfy 0 <= failures <= evaluations = " +
                                          std::to_string(evaluations)));
  }
  return rng.Validate();
}

// ---------------------------------------------------------------------------------------------
// GeneticAlgorithm

GeneticAlgorithm::GeneticAlgorithm(const GaOptions& options, BatchEvaluator* evaluator)
    : options_(options), evaluator_(evaluator), rng_(options.seed) {
  ThrowIfError(options_.Validate());
  if (evaluator_ == nullptr) throw InputError("evaluator: must not be null");
  state_.rng = rng_.state();
}

void GeneticAlgorithm::AddGenerationCallback(GenerationCallback callback) {
  callbacks_.push_back(std::move(callback));
}

void GeneticAlgorithm::SetDescriber(Describer describer) { describer_ = std::move(describer); }

void GeneticAlgorithm::RestoreState(GaState state) {
  ThrowIfError(state.Validate(options_));
  rng_ = Rng(state.rng);
  state_ = std::move(state);
}

int GeneticAlgorithm::Tournament() {
  const uint64_t elite = static_cast<uint64_t>(options_.elite_count());
  // The population is ranked, so the best of the draws is the smallest index.
  uint64_t winner = rng_.UniformBelow(elite);
  for (int k = 1; k < options_.tournament_size; ++k) winner = std::min(winner, rng_.UniformBelow(elite));
  return static_cast<int>(winner);
}

const GeometricGaps& GeneticAlgorithm::MutationGaps() {
  if (!mutation_gaps_) mutation_gaps_.emplace(options_.mutation_probability, options_.genome_bits);
  return *mutation_gaps_;
}

void GeneticAlgorithm::Evaluate(std::span<const Genome> genomes, int first_index,
                                std::span<FitnessResult> out) {
  std::vector<int> indices(genomes.size());
  std::iota(indices.begin(), indices.end(), first_index);
  const uint64_t generation = state_.initialized ? state_.generation + 1 : 0;
  try {
    evaluator_->Evaluate(EvalBatch{generation, genomes, indices}, out);
  } catch (...) {
    rng_ = Rng(state_.rng);  // leave the GA as it was before this generation
    throw;
  }
  for (FitnessResult& r : out) SanitizeFitness(r, options_.error_cost);
}

const GenerationSummary& GeneticAlgorithm::Initialize(std::span<const Genome> seeds) {
  PZ_CHECK_MSG(!state_.initialized, "GeneticAlgorithm::Initialize called twice");
  const double start = NowSeconds();
  const int n = options_.population_size, bits = options_.genome_bits;
  if (seeds.size() > static_cast<size_t>(n)) {
    throw InputError(FieldError("seeds.size()", seeds.size(), "must be <= population_size"));
  }
  std::vector<Genome> population(n);
  for (size_t i = 0; i < seeds.size(); ++i) {
    ThrowIfError(CheckGenome(seeds[i], bits, "seeds[" + std::to_string(i) + "]"));
    population[i] = seeds[i];
  }
  // Uniform bits, 64 per draw, most significant first.
  for (int i = static_cast<int>(seeds.size()); i < n; ++i) {
    population[i].bits.resize(bits);
    for (int b = 0; b < bits; b += 64) {
      const uint64_t x = rng_.NextU64();
      for (int k = 0; k < 64 && b + k < bits; ++k) population[i].bits[b + k] = (x >> (63 - k)) & 1u;
    }
  }
  std::vector<FitnessResult> fitness(n);
  Evaluate(population, 0, fitness);
  return Finish(std::move(population), std::move(fitness), 0, start);
}

const GenerationSummary& GeneticAlgorithm::Step() {
  PZ_CHECK_MSG(state_.initialized, "GeneticAlgorithm::Step before Initialize");
  const double start = NowSeconds();
  const int n = options_.population_size, bits = options_.genome_bits;
  const int elite = options_.elite_count(), n_off = n - elite;
  const BernoulliThreshold cross(options_.crossover_probability);
  const GeometricGaps& mutate = MutationGaps();

  std::vector<Genome> offspring(n_off);
  for (int o = 0; o < n_off; o += 2) {
    const Genome& pa = state_.population[Tournament()];
    const Genome& pb = state_.population[Tournament()];
    Genome& c1 = offspring[o];
    Genome c2_storage;
    Genome& c2 = o + 1 < n_off ? offspring[o + 1] : c2_storage;  // an odd last child is dropped
    c1.bits = pa.bits;
    c2.bits = pb.bits;
    if (rng_.Bernoulli(cross)) {
      // Two distinct cut points in 1 … bits − 1; the segment [lo, hi) is exchanged.
      const int p = 1 + static_cast<int>(rng_.UniformBelow(bits - 1));
      int q = 1 + static_cast<int>(rng_.UniformBelow(bits - 2));
      if (q >= p) ++q;
      const int lo = std::min(p, q), hi = std::max(p, q);
      std::swap_ranges(c1.bits.begin() + lo, c1.bits.begin() + hi, c2.bits.begin() + lo);
    }
    for (Genome* c : {&c1, &c2}) {
      if (c == &c2_storage) continue;
      // Each bit flips with probability p, independently: the positions of the flips are drawn
      // as geometric gaps (one draw per flip, plus one that ends the genome) instead of one
      // Bernoulli draw per bit.
      for (int pos = rng_.Gap(mutate); pos < bits; pos += 1 + rng_.Gap(mutate)) c->bits[pos] ^= 1u;
    }
  }
  std::vector<FitnessResult> evaluated(n_off);
  Evaluate(offspring, elite, evaluated);

  std::vector<Genome> population;
  std::vector<FitnessResult> fitness;
  population.reserve(n);
  fitness.reserve(n);
  for (int i = 0; i < elite; ++i) {
    population.push_back(std::move(state_.population[i]));
    fitness.push_back(std::move(state_.fitness[i]));
  }
  for (int o = 0; o < n_off; ++o) {
    population.push_back(std::move(offspring[o]));
    fitness.push_back(evaluated[o]);
  }
  return Finish(std::move(population), std::move(fitness), elite, start);
}

const GenerationSummary& GeneticAlgorithm::Finish(std::vector<Genome> population,
                                                   std::vector<FitnessResult> fitness,
                                                   int first_evaluated, double start_s) {
  const int n = static_cast<int>(population.size());
  GenerationSummary s;
  s.evaluations = n - first_evaluated;
  for (int i = first_evaluated; i < n; ++i) {
    const FitnessResult& f = fitness[i];
    if (f.status == FitnessStatus::kOk) continue;
    ++s.failures;
    (f.status == FitnessStatus::kPenalized ? s.penalized : s.errors)++;
    ++s.failure_reasons[f.reason];
  }
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(),
            [&fitness](int a, int b) { return Better(fitness[a], a, fitness[b], b); });
  state_.population.resize(n);
  state_.fitness.resize(n);
  for (int r = 0; r < n; ++r) {
    state_.population[r] = std::move(population[order[r]]);
    state_.fitness[r] = std::move(fitness[order[r]]);
  }

  s.generation = state_.initialized ? state_.generation + 1 : 0;
  const FitnessResult& top = state_.fitness.front();
  s.improved = !state_.initialized || top.cost < state_.best_fitness.cost;
  if (s.improved) {
    state_.best = state_.population.front();
    state_.best_fitness = top;
    state_.best_generation = s.generation;
    state_.stall = 0;
  } else {
    ++state_.stall;
  }
  state_.initialized = true;
  state_.generation = s.generation;
  state_.rng = rng_.state();

  s.stall = state_.stall;
  s.best_cost = top.cost;
  s.worst_cost = state_.fitness.back().cost;
  double mean = 0;
  for (const FitnessResult& f : state_.fitness) mean += f.cost / n;  // cannot overflow for finite costs
  s.mean_cost = std::isfinite(mean) ? mean : std::numeric_limits<double>::max();
  // The population is ranked: the median is its middle (the mean of the two middle costs).
  const double lo = state_.fitness[(n - 1) / 2].cost, hi = state_.fitness[n / 2].cost;
  const double median = lo + (hi - lo) / 2;
  s.median_cost = std::isfinite(median) ? median : std::numeric_limits<double>::max();
  if (describer_) s.best_description = describer_(state_.population.front());
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
  if (!state_.initialized) return cancel_.load() ? std::optional(GaTermination::kCancelled) : std::nullopt;
  if (state_.best_fitness.cost <= options_.target_cost) return GaTermination::kTargetReached;
  if (options_.stall_generations > 0 && state_.stall >= options_.stall_generations) return GaTermination::kStall;
  if (state_.generation >= static_cast<uint64_t>(options_.max_generations)) return GaTermination::kMaxGenerations;
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
  s.evaluations = state_.evaluations;
  s.failures = state_.failures;
  s.wall_time_s = wall_time_s;
  s.message = DescribeTermination(termination, state_.best_fitness.cost, state_.stall, state_.best_generation,
                                  state_.generation, options_.max_generations, options_.target_cost);
  return s;
}

GaSummary GeneticAlgorithm::Run() {
  const double start = NowSeconds();
  for (;;) {
    if (std::optional<GaTermination> t = CheckTermination()) return MakeSummary(*t, NowSeconds() - start);
    if (!state_.initialized) {
      Initialize();
    } else {
      Step();
    }
  }
}

}  // namespace pz::opt
