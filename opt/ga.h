// The binary genetic algorithm of HGANN (spec hgann.md §4, paper Table 2, Appendix C). Socket-free:
// individuals are evaluated through a BatchEvaluator (inline, threaded, or the broker).
//
// Generation 0: population_size genomes, bits drawn uniformly (or given seeds), all evaluated,
// ranked by (cost, index). Each later generation (Step):
//   1. the best E = round(elite_fraction · population_size) individuals pass unchanged, with their
//      costs (they are not re-evaluated);
//   2. the other population_size − E are offspring, made pair by pair: two parents, each the best
//      of tournament_size uniform draws from the elite; two-point crossover with probability
//      crossover_probability; then each offspring bit flips with probability mutation_probability,
//      independently (the flipped positions are drawn as geometric gaps, see GeometricGaps);
//   3. the offspring (and only they) are evaluated as one batch, population indices E … N − 1;
//   4. the N individuals are ranked by (cost, index), stable; penalised and failed individuals rank
//      by their finite penalty cost. The best individual never gets worse (elitism).
// One seeded generator (opt/random.h), owned by the GA, drives every random choice in a fixed
// order, so the run is a function of (options, seed, fitness) alone: the evaluator, its thread
// count and the order in which results arrive cannot change it.
//
// The whole run state is the plain struct GaState: a master can Step() generation by generation,
// save state() between generations, and RestoreState() into a new GeneticAlgorithm to continue
// bit for bit.
//
// Islands (an archipelago, after pagmo2's, but synchronous and reproducible). With islands = K > 1
// the GA holds K populations of population_size each; island i has its own generator, seeded by
// StreamSeed(seed, i) (island 0 by the seed itself, so K = 1 is the single-population GA above,
// draw for draw). Each generation, every island breeds its offspring with its own generator (in
// island order), and the offspring of all islands are evaluated as ONE batch (population index
// i · population_size + slot), so a generation gives an evaluator K times the work. Then:
//   5. each island is ranked as in 4. and its own stall is counted (generations without a lower
//      best since its last restart);
//   6. every migration_interval generations (0 = never: K independent runs, "multi-start"), each
//      island sends copies of its best `migrants` individuals along the topology (ring: i − 1 → i;
//      fully connected: every other island, in index order; random: a ring in an order drawn from
//      StreamSeed(seed, kTopologyStream), fixed for the run). All emigrants are taken before any
//      island receives, and islands receive in index order, so completion order cannot matter.
//      With migration_margin m > 0 an island hears only the sources whose best is below its own
//      by more than m · |its best| (a gate: on a plateau the islands stay apart, and a lineage
//      that steps down to a lower basin is copied to every island it leads by the margin).
//      An island takes the best `migrants` of what it receives (ties: source order, then rank);
//      they replace its worst individuals pair by pair (best migrant ↔ worst resident) where the
//      migrant's cost is strictly lower; the island is re-ranked;
//   6b. every broadcast_interval generations (0 = never), at a generation without the migration of
//      6., a gated broadcast: each island takes the best `migrants` of every other island whose
//      best is below its own by more than broadcast_margin · |its best|, as in 6. with the fully
//      connected topology and that margin. With an ungated ring every 200 and a broadcast every 25
//      (docs/performance.md, "Islands"), the islands on one plateau mix slowly while a lineage that
//      steps down is copied to every island it leads within 25 generations;
//   7. island i's offspring flip each bit with probability MutationProbability(i):
//   island_mutation[i]
//      when one rate per island is given, else, with more than one island, the ladder
//      mutation_probability · (1, 2, 3, 5)[i mod 4] (at 0.01: 0.01, 0.02, 0.03, 0.05; island 0 at
//      the one-island rate) — heterogeneous islands, the same operators at different rates, the
//      default by measurement (docs/performance.md, "Islands");
//   8. an island whose own stall reaches island_stall_generations (0 = never) is restarted at the
//      next generation: its population becomes the best `migrants` individuals its topology
//      sources hold (as a migration would send them; none for multi-start or K = 1) plus fresh
//      uniform individuals drawn from its generator, which are evaluated in that generation's
//      batch instead of its offspring.
//   9. output moves: with a move set (SetMove; a problem hook) island i's last OutputMoves()
//      offspring are not bred but made by the move from the island's best individual, with the
//      island's generator, after the bred ones. For HGANN (hgann/output_move.h) the move decodes
//      the network, takes its seven outputs' mean over the training cases, adds a random step and
//      writes them back as a network of constant outputs: a search in the model's parameter space
//      beside the GA's search in the network's bits, which leaves a plateau that bit flips cannot
//      (the default with several islands, by measurement: docs/performance.md, "Islands"). Without
//      a move (or with 0 moves) every offspring is bred.
//   10. repair: with a repair set (SetRepair; a problem hook) every fresh genome passes through it
//      before the batch is evaluated; HGANN's robust preset rewrites a child whose Bouc–Wen loop
//      is unbounded into the bounded region (hgann/loop_repair.h) instead of spending a slot on it.
// The job's best, stall and termination are over all islands (the best of the best); the
// generation's summary carries each island's best, stall, immigrants and restart (IslandSummary).
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "opt/evaluator.h"
#include "opt/inline_evaluator.h"
#include "opt/random.h"
#include "opt/topology.h"
#include "model/status.h"

namespace pz::opt {

inline constexpr int kMaxIslands = 1024;
/// The stream of the random topology's generator (island streams are 0 … kMaxIslands − 1).
inline constexpr uint64_t kTopologyStream = uint64_t{1} << 32;

/// Every setting of the GA; defaults are the paper's Table 2 / spec §4.
struct GaOptions {
  int population_size = 400;    ///< individuals, ≥ 2
  int genome_bits = 1415;       ///< bits per genome, ≥ 3 (two distinct cut points)
  double elite_fraction = 0.5;  ///< share passed unchanged, in (0, 1); the elite count
                                ///< round(population_size · elite_fraction) must be 1 … N − 1
  int tournament_size = 2;      ///< parent = best of k uniform draws from the elite, k ≥ 1
  double crossover_probability = 1.0;  ///< two-point crossover of an offspring pair, in [0, 1]
  double mutation_probability = 0.01;  ///< flip probability of each offspring bit, in [0, 1]
  int max_generations = 1000;          ///< generations after the initial one, ≥ 0
  int stall_generations = 200;         ///< stop after this many generations without a strictly
                                       ///< lower best cost, ≥ 0 (0 = never stop for stall)
  /// A generation resets the stall count only when it lowers the best cost by more than this
  /// share of it, in [0, 1) (0: any lower cost; the best is kept whatever the step).
  double stall_relative = 0;
  double target_cost =
      -std::numeric_limits<double>::infinity();  ///< stop once best ≤ this; not NaN
  double error_cost = kDefaultErrorCost;         ///< cost given to non-finite results, finite
  uint64_t seed = 0;  ///< seeds the generators (island i: StreamSeed(seed, i))
  // Islands (file comment). With islands = 1 the other four are not used.
  int islands = 1;  ///< populations, 1 … kMaxIslands
  // The migration defaults are the measured archipelago (docs/performance.md, "Islands"): with 4
  // islands and 560 generations, every 25 generations, fully connected, gated by a margin of 0.2,
  // mutation by the ladder of 7.
  int migration_interval = 25;  ///< generations between migrations, ≥ 0 (0 = never: multi-start)
  int migrants = 4;  ///< individuals each island sends per migration, 0 … population_size − 1
                     ///< (≥ 1 when migration_interval > 0)
  MigrationTopology topology = MigrationTopology::kFullyConnected;
  double migration_margin = 0.2;  ///< a migration reaches an island only from sources whose best is
                                  ///< below its own by more than this share of |its best|, [0, 1)
                                  ///< (0 = every source)
  int broadcast_interval = 0;     ///< generations between gated broadcasts to every island, ≥ 0
                                  ///< (0 = none; file comment, 6b.); ≥ 1 migrant when > 0
  double broadcast_margin = 0.2;  ///< the broadcast's gate, (0, 1): a source's best must be below
                                  ///< the island's by more than this share of it
  int island_stall_generations = 0;     ///< restart an island after this many generations without
                                        ///< a lower best of its own, ≥ 0 (0 = never)
  std::vector<double> island_mutation;  ///< per-bit mutation probability of island i, each in [0,
                                        ///< 1]; empty (the ladder of 7.) or `islands` entries
  int output_moves =
      kAutoOutputMoves;  ///< offspring per island and generation made by the move (9.),
                         ///< 0 … population_size − elite_count(); kAutoOutputMoves: 0 with
                         ///< one island, kIslandOutputMoveShare of the offspring with several

  /// What Validate() calls a field, given the member's name (e.g. "islands" → "--islands" for a
  /// command line); without one, the member's name.
  using FieldNamer = std::function<std::string(std::string_view field)>;
  /// The error names the field (through `namer`), its value and the rule broken.
  Status Validate(const FieldNamer& namer = nullptr) const;
  /// round(population_size · elite_fraction).
  int elite_count() const;
  /// The islands island `i` receives migrants from, in the order it takes them (empty for one
  /// island). A function of (islands, topology, seed) alone.
  std::vector<int> MigrationSources(int i) const;
  /// migration_interval > 0 and more than one island.
  bool migrates() const { return islands > 1 && migration_interval > 0; }
  /// broadcast_interval > 0 and more than one island.
  bool broadcasts() const { return islands > 1 && broadcast_interval > 0; }
  /// The per-bit mutation probability of island `i`: island_mutation[i]; else, with one island,
  /// mutation_probability, and with several, min(1, mutation_probability · kIslandMutationLadder[i
  /// mod 4]).
  double MutationProbability(int i) const {
    if (!island_mutation.empty()) return island_mutation[i];
    if (islands <= 1) return mutation_probability;
    return std::min(
        1.0, mutation_probability * kIslandMutationLadder[i % std::size(kIslandMutationLadder)]);
  }
  /// The default rates of the islands, as multiples of mutation_probability (file comment, 7.).
  static constexpr double kIslandMutationLadder[4] = {1, 2, 3, 5};
  /// The offspring per island made by the move (9.): output_moves, or with kAutoOutputMoves, 0 for
  /// one island (the paper's GA, bit for bit) and round(kIslandOutputMoveShare · offspring) for
  /// several (32 of the paper's 200).
  int OutputMoves() const {
    if (output_moves != kAutoOutputMoves) return output_moves;
    if (islands <= 1) return 0;
    return static_cast<int>(
        std::lround(kIslandOutputMoveShare * (population_size - elite_count())));
  }
  static constexpr int kAutoOutputMoves = -1;
  static constexpr double kIslandOutputMoveShare = 0.16;
};

/// One island's part of a generation's record (GenerationSummary::islands).
struct IslandSummary {
  double best_cost = 0;  ///< the island's best after this generation (and its migration), finite
  int stall = 0;         ///< generations since the island's best last went down (since its restart)
  int immigrants = 0;    ///< migrants it took in this generation's migration (0 when none)
  bool restarted = false;  ///< its population was restarted in this generation
  bool operator==(const IslandSummary&) const = default;
};

/// One generation's record, delivered to the on_generation callbacks and kept in GaState::log.
struct GenerationSummary {
  uint64_t generation = 0;  ///< 0 = the initial population
  double best_cost = 0;     ///< finite
  double mean_cost = 0;     ///< over the whole population, finite
  double median_cost = 0;   ///< of the whole population (robust to penalised individuals), finite
  double worst_cost = 0;    ///< finite
  bool improved = false;    ///< best cost strictly lower than before (always true for generation 0)
  int stall = 0;            ///< generations since the best cost last improved
  std::string best_description;   ///< from the describer hook (e.g. "2-3-7 …"), empty without one
  int evaluations = 0;            ///< genomes evaluated in this generation
  int64_t evaluations_total = 0;  ///< since the start of the run
  int failures = 0;               ///< non-ok results among this generation's evaluations
  int penalized = 0;              ///< of which FitnessStatus::kPenalized
  int errors = 0;                 ///< of which FitnessStatus::kError
  int quarantined = 0;  ///< of which quarantined by the service (a kError each; 0 in a local run)
  std::map<std::string, int> failure_reasons;  ///< reason → count, this generation
  int best_island = 0;    ///< island holding this generation's best (0 with one island)
  bool migrated = false;  ///< a migration took place at the end of this generation
  std::vector<IslandSummary> islands;  ///< one per island when there are several; empty for one
  double wall_time_s = 0;  ///< wall time of the generation (the only non-deterministic field)

  /// Equal in every field but wall_time_s.
  bool SameOutcome(const GenerationSummary& other) const;
  /// SameOutcome: two runs that did the same have equal records, whatever their wall times.
  bool operator==(const GenerationSummary& other) const { return SameOutcome(other); }
  /// One line, e.g. "gen 12: best 10.53 mean 30.1 worst 1e+30 stall 3 evals 200/2600 fail 4".
  std::string BriefReport() const;
};

enum class GaTermination : int {
  kMaxGenerations = 1,  ///< generation == max_generations
  kStall = 2,           ///< stall_generations generations without improvement
  kCancelled = 3,       ///< Cancel() was called
  kTargetReached = 4,   ///< best cost ≤ target_cost
};
const char* GaTerminationName(GaTermination t);

/// One island of a run between generations (GaState::islands).
struct IslandState {
  std::vector<Genome> population;      ///< ranked, best first; population_size genomes
  std::vector<FitnessResult> fitness;  ///< fitness[i] of population[i]
  RngState rng;                        ///< the island's generator, ready for the next generation
  int stall = 0;         ///< generations since its best last went down (since its restart)
  double best_cost = 0;  ///< its best since its last restart
  int restarts = 0;      ///< times it was restarted
};

/// The complete state of a run between generations. Plain data: save it to checkpoint, restore it
/// with GeneticAlgorithm::RestoreState() to continue bit for bit.
struct GaState {
  bool initialized = false;  ///< generation 0 has been evaluated
  uint64_t generation = 0;   ///< last completed generation
  int stall = 0;             ///< generations since the best cost (over islands) last improved
  std::vector<IslandState> islands;  ///< options.islands of them (one before Initialize too)
  Genome best;                       ///< best so far, over all islands
  FitnessResult best_fitness;
  uint64_t best_generation = 0;        ///< generation in which the best cost was reached
  int best_island = 0;                 ///< island in which it was found
  int64_t evaluations = 0;             ///< genomes evaluated since the start
  int64_t failures = 0;                ///< non-ok results since the start
  std::vector<GenerationSummary> log;  ///< one record per generation (may be trimmed by the owner)

  /// Consistency with the options: sizes, 0/1 bits, finite costs, ranking order, RNG state. The
  /// error names the field, e.g. "state.islands[0].population[3].bits.size()".
  Status Validate(const GaOptions& options) const;
};

/// The final record of Run().
struct GaSummary {
  GaTermination termination = GaTermination::kMaxGenerations;
  std::string message;       ///< why it stopped, with the figures
  uint64_t generations = 0;  ///< last completed generation
  Genome best;
  FitnessResult best_fitness;
  uint64_t best_generation = 0;
  int best_island = 0;  ///< island in which the best was found
  int islands = 1;      ///< the run's islands
  int64_t evaluations = 0;
  int64_t failures = 0;
  double wall_time_s = 0;  ///< of the Run() call
  std::string BriefReport() const;
};

/// Why a run stopped, with the figures (GaSummary::message): what Run() says, and what a client
/// that holds only a job's stored state (its termination, best, stall and settings) says too.
std::string DescribeTermination(GaTermination termination, double best_cost, int stall,
                                uint64_t best_generation, uint64_t generations, int max_generations,
                                double target_cost);

class GeneticAlgorithm {
 public:
  using GenerationCallback = std::function<void(const GenerationSummary&)>;
  using Describer = std::function<std::string(const Genome&)>;

  /// Throws InputError if the options are invalid. `evaluator` is not owned and must outlive the
  /// GA.
  GeneticAlgorithm(const GaOptions& options, BatchEvaluator* evaluator);

  /// Called after every generation (0 included), once state() is complete for that generation:
  /// a checkpoint callback may save state() from here.
  void AddGenerationCallback(GenerationCallback callback);
  /// Optional problem hook describing an individual (e.g. its decoded architecture) for the
  /// per-generation summary. Called on the best individual of each generation.
  void SetDescriber(Describer describer);
  /// A problem's move (file comment, 9.): writes into each of `children`, in order, a genome made
  /// from `parent` (an island's best) with draws from `rng` only — one call per island and
  /// generation, so the parent is read once. Must be a function of (parent, the draws): the run
  /// stays a function of (options, seed, fitness, move). Without one, every offspring is bred.
  using Move = std::function<void(const Genome& parent, Rng& rng, std::span<Genome> children)>;
  void SetMove(Move move);
  /// A problem's repair (e.g. hgann/loop_repair.h): applied to every fresh genome of a generation
  /// (seeded, drawn, bred or moved) before the batch is evaluated; true when it rewrote the genome.
  /// Must be a function of the genome alone (no draws), so the run stays a function of (options,
  /// seed, fitness, move, repair). Without one (the paper's GA) genomes are evaluated as made.
  using Repair = std::function<bool(Genome&)>;
  void SetRepair(Repair repair);
  /// Fresh genomes the repair rewrote in this object's generations (not part of the state).
  int64_t repaired() const { return repaired_; }

  /// Creates generation 0: `seeds` (≤ population_size genomes of genome_bits 0/1 bits) fill the
  /// first slots of island 0, the rest are drawn uniformly (each island from its own generator);
  /// evaluates all islands as one batch and ranks them. Throws InputError on bad
  /// seeds; requires !state().initialized (checked).
  const GenerationSummary& Initialize(std::span<const Genome> seeds = {});
  /// Runs one generation (selection, crossover, mutation, evaluation of the offspring, ranking).
  /// Requires state().initialized (checked). Does not check the termination criteria.
  const GenerationSummary& Step();
  /// The criterion met by the current state, if any (target, stall, max generations, cancel, in
  /// that order of precedence).
  std::optional<GaTermination> CheckTermination() const;
  /// Initialize() if needed, then Step() until CheckTermination() says stop.
  GaSummary Run();
  /// Thread-safe; Run() stops after the current generation. Sticky until ClearCancel().
  void Cancel() { cancel_.store(true); }
  void ClearCancel() { cancel_.store(false); }

  /// Replaces the run state (e.g. from a checkpoint). Throws InputError if it is inconsistent with
  /// the options.
  void RestoreState(GaState state);
  const GaState& state() const { return state_; }
  /// Empties state().log, for an owner that keeps the records itself (the log is not needed to
  /// continue; the last Step()'s record is gone with it).
  void ClearLog() { state_.log.clear(); }
  const GaOptions& options() const { return options_; }
  /// The summary Run() would return if the run stopped now for `termination`.
  GaSummary MakeSummary(GaTermination termination, double wall_time_s = 0) const;

 private:
  /// An island's new generation before ranking: kept individuals (with their costs) first, then
  /// `fresh` ones to evaluate.
  struct Draft {
    std::vector<Genome> kept, fresh;
    std::vector<FitnessResult> kept_fitness;
    /// The island's first `elite` individuals stay in the state until the generation is evaluated
    /// (then Finish moves them in front of `kept`): no copy, and a failed evaluation leaves the
    /// state untouched.
    int elite = 0;
    bool restarted = false;
    int kept_count() const { return elite + static_cast<int>(kept.size()); }
  };
  int Tournament(Rng& rng);
  /// The mutation's gap table of island `i` for (MutationProbability(i), genome_bits), built on
  /// first use (one table per distinct rate).
  const GeometricGaps& MutationGaps(int i);
  void DrawUniform(Rng& rng, int count, std::vector<Genome>* out);
  Draft Breed(int island);
  Draft Restart(int island);
  /// The best `migrants` individuals island `i` receives from its `sources` (ties: source order,
  /// rank), counting only the sources whose best cost is below `below`.
  std::vector<std::pair<Genome, FitnessResult>> Immigrants(int island,
                                                           const std::vector<int>& sources,
                                                           double below) const;
  /// Evaluates every draft's fresh genomes as one batch (generation 0 if !initialized).
  std::vector<std::vector<FitnessResult>> Evaluate(std::vector<Draft>& drafts);
  /// Ranks each island by (cost, index), updates island and job best, stall and counters, migrates
  /// when due, logs the summary and calls the callbacks.
  const GenerationSummary& Finish(std::vector<Draft> drafts,
                                  std::vector<std::vector<FitnessResult>> evaluated,
                                  double start_s);
  /// A migration at the end of a generation (file comment, 6. and 6b.) from each island's
  /// `sources`, gated by `margin` (0 = every source); immigrants taken per island.
  std::vector<int> Migrate(const std::vector<std::vector<int>>& sources, double margin);

  GaOptions options_;
  BatchEvaluator* evaluator_;
  std::vector<GenerationCallback> callbacks_;
  Describer describer_;
  Move move_;
  Repair repair_;
  int64_t repaired_ = 0;
  std::atomic<bool> cancel_{false};
  std::vector<Rng> rngs_;                  ///< one per island
  std::vector<std::vector<int>> sources_;  ///< MigrationSources(i), computed once
  std::vector<std::vector<int>>
      everyone_;  ///< the broadcast's sources: every other island, in index order
  std::map<double, GeometricGaps> mutation_gaps_;  ///< by mutation probability
  GaState state_;
};

}  // namespace pz::opt
