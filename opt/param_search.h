// Complete-model identification (issue 7, seed 002): the physical parameters themselves are the
// search space. Three optimisers, all evaluating whole swarms / generations through the
// BatchEvaluator seam (opt/evaluator.h), so the same search runs inline, on a thread pool or on
// the service's workers:
//
//   kPso       particle swarm: inertia decreasing linearly from inertia_start to inertia_end over
//              the iterations, cognitive and social weights, velocity clamped to ± velocity_clamp
//              (a fraction of the unit box), positions reflected at the bounds (the velocity
//              component changes sign), global-best topology;
//   kGaReal    real-coded GA: elitism, k-tournament selection, SBX (or BLX-α) crossover, Gaussian
//              mutation, children reflected into the box;
//   kGaBinary  the project's binary GA (opt/ga.h), each parameter a bits_per_parameter gene
//              (Gray code by default) decoded to a real before evaluation;
//   kDe        differential evolution DE/rand-to-best/1/bin, a trial coordinate leaving the box put
//              between its parent and that bound; optional seeds take the first slots of the
//              initial population (the fin-bench diagnosis's search);
//   kLine      one parameter (a box of size 1): a uniform grid over the unit interval, evaluated as
//              one batch, then the grid's lowest local minima each refined within its neighbours by
//              Brent's method (parabolic interpolation with golden-section steps), the brackets
//              advancing side by side, one batch per step. No random choice; one repetition.
//
// The search space is the unit box [0, 1]^d: coordinate x maps to lower + x (upper − lower), or to
// 10^(log10 lower + x (log10 upper − log10 lower)) for log-scaled parameters. Genomes handed to the
// evaluator carry the physical values in Genome::reals (bits empty).
//
// Determinism: one generator (opt/random.h) per repetition, seeded with seed + repetition,
// drives every random choice in a fixed order on the calling thread; the evaluator only computes
// costs. So the result is a function of (box, options, fitness) alone, bit for bit, whatever the
// evaluator or its thread count. Ties between equal costs go to the lower index (particle,
// individual, repetition).
//
// Stopping (per repetition): the iteration / generation limit; `stall` iterations without a
// significant improvement of the best cost (an improvement counts when the new best is below
// old − tolerance · |old|: a relative tolerance, as costs here are tiny MSEs); the target cost;
// the optional wall-time limit (the only non-deterministic criterion, off by default); PSO only,
// when asked (PsoOptions::converged_spread): a swarm that has collapsed onto its best.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "opt/evaluator.h"
#include "opt/ga.h"
#include "model/status.h"

namespace pz::opt {

/// A box of physical parameters; genome.reals holds parameter values in these units.
struct ParamBox {
  std::vector<std::string> names;
  std::vector<double> lower, upper;
  std::vector<bool> log_scale;  ///< search in log10 space when true (needs lower > 0); may be empty
                                ///< (= all linear)

  size_t size() const { return names.size(); }
  /// Non-empty, equal sizes, distinct non-empty names, finite lower < upper, lower > 0 where
  /// log-scaled. The error names the field, e.g. "box.upper[2] (k) = 1: must be > lower = 5".
  Status Validate() const;
  /// Unit-box coordinates → physical values (x clamped to [0, 1]; result clamped to the bounds).
  void ToPhysical(const double* unit, double* physical) const;
  /// Physical values → unit-box coordinates (clamped to [0, 1]).
  void ToUnit(const double* physical, double* unit) const;
};

enum class SearchAlgorithm { kPso, kGaReal, kGaBinary, kDe, kLine };
/// "pso", "ga-real", "ga-binary", "de", "line".
const char* SearchAlgorithmName(SearchAlgorithm a);
/// Parses the names above; throws InputError naming the value otherwise.
SearchAlgorithm ParseSearchAlgorithm(const std::string& name);

struct PsoOptions {
  int particles = 40;           ///< ≥ 2
  int iterations = 300;         ///< swarm updates after the initial evaluation, ≥ 0
  double inertia_start = 0.9;   ///< w at the first update, finite ≥ 0
  double inertia_end = 0.4;     ///< w at the last update (linear in between), finite ≥ 0
  double cognitive = 1.49618;   ///< c1, finite ≥ 0
  double social = 1.49618;      ///< c2, finite ≥ 0
  double velocity_clamp = 0.2;  ///< |v| ≤ this fraction of the (unit) box width, in (0, 1]
  int stall_iterations = 60;    ///< ≥ 0 (0 = never stop for stall)
  double tolerance = 1e-6;      ///< relative improvement that resets the stall count, ≥ 0
  /// Stop when the swarm has converged: every particle within this distance (max-norm, unit box) of
  /// the swarm's best after an update — what is left is local, the polish's work. In [0, 1); 0 =
  /// never (the default: the iteration and stall limits alone).
  double converged_spread = 0;
  uint64_t seed = 1;
  Status Validate() const;  ///< names the field: "pso.particles = 1: must be >= 2"
};

enum class RealCrossover { kSbx, kBlxAlpha };

struct RealGaOptions {
  int population = 60;          ///< ≥ 2
  int generations = 300;        ///< after the initial one, ≥ 0
  double elite_fraction = 0.1;  ///< round(population · f) individuals pass unchanged; the
                                ///< count must be 1 … population − 1
  int tournament = 2;           ///< parent = best of k uniform draws of the population, ≥ 1
  double crossover_probability = 0.9;  ///< per offspring pair, in [0, 1]
  RealCrossover crossover = RealCrossover::kSbx;
  double sbx_eta = 15;                ///< SBX distribution index, finite > 0
  double blx_alpha = 0.5;             ///< BLX-α extension, finite ≥ 0
  double mutation_probability = 0.1;  ///< per gene, in [0, 1]
  double mutation_sigma = 0.1;        ///< Gaussian step at the first generation, fraction of the
                                      ///< unit box, finite > 0
  double mutation_sigma_end = 0;      ///< if > 0: the step decreases geometrically to this at the
                                  ///< last generation, in (0, sigma]; 0 = constant step. (On the
                                  ///< Bouc–Wen benchmark 0.1 → 0.001 converged early to a local
                                  ///< minimum: docs/performance.md.)
  int stall_generations = 60;  ///< ≥ 0 (0 = never stop for stall)
  double tolerance = 1e-6;     ///< relative improvement that resets the stall count, ≥ 0
  uint64_t seed = 1;
  Status Validate() const;  ///< names the field: "ga_real.tournament = 0: must be >= 1"
};

/// Differential evolution DE/rand-to-best/1/bin.
struct DeOptions {
  int population = 32;         ///< ≥ 4
  int generations = 60;        ///< generations after the initial one, ≥ 0
  int stall_generations = 15;  ///< stop after this many generations without a relative gain >
                               ///< tolerance, ≥ 0 (0 = never stop for stall)
  double tolerance = 1e-4;  ///< relative gain that counts as progress, ≥ 0
  double f = 0.6;           ///< differential weight, in (0, 2]
  double cr = 0.9;          ///< crossover probability, in [0, 1]
  uint64_t seed = 1;
  Status Validate() const;  ///< names the field: "de.population = 3: must be >= 4"
};

struct BinaryGaOptions {
  int bits_per_parameter = 16;  ///< 2 … 52
  bool gray_code = true;        ///< genes are Gray-coded (else plain binary)
  /// The project GA (opt/ga.h). genome_bits and seed are set by Search (bits_per_parameter ·
  /// parameters; seed + repetition); the other fields are used as given. The defaults below are
  /// a small-problem setting, not the HGANN paper's.
  GaOptions ga = [] {
    GaOptions o;
    o.population_size = 60;
    o.elite_fraction = 0.5;
    o.tournament_size = 2;
    o.crossover_probability = 0.9;
    o.mutation_probability = 0.02;
    o.max_generations = 300;
    o.stall_generations = 60;
    return o;
  }();
  Status Validate(size_t parameters) const;  ///< names the field: "ga_binary.bits_per_parameter"
};

/// The line search of one parameter (kLine). Its evaluations: `grid` (one batch), then at most
/// `brackets` × `max_steps` (batches of one point per bracket still refining).
struct LineOptions {
  int grid = 17;     ///< grid points over [0, 1], ends included, ≥ 3
  int brackets = 2;  ///< the lowest local minima of the grid refined, ≥ 1
  /// A bracket stops once its minimum is located within this (unit coordinates, absolute; Brent's
  /// tol), in (0, 0.5).
  double tolerance = 1e-4;
  int max_steps = 60;       ///< evaluations per bracket at most, ≥ 1
  Status Validate() const;  ///< names the field: "line.grid = 2: must be >= 3"
  /// "a grid of 17 points, then the lowest 2 of its local minima refined by Brent's method to
  /// 0.0001 of the range".
  std::string Describe() const;
};

/// Progress after each iteration / generation of any repetition.
struct SearchProgress {
  int repetition = 0;
  int iteration = 0;             ///< 0 = the initial evaluation
  int64_t evaluations = 0;       ///< since the start of the search (all repetitions)
  double best_cost = 0;          ///< best of this repetition so far
  double overall_best_cost = 0;  ///< best of the search so far
};

struct SearchOptions {
  SearchAlgorithm algorithm = SearchAlgorithm::kPso;
  PsoOptions pso;
  RealGaOptions ga_real;
  BinaryGaOptions ga_binary;
  DeOptions de;
  LineOptions line;
  /// Points of the unit box (each of the box's size, clamped into it) that take the first slots of
  /// the initial population; only the de search takes them.
  std::vector<std::vector<double>> seeds;
  int repetitions =
      5;  ///< seeds seed, seed+1, … (seed of the chosen algorithm's options); best kept
  double target_cost = -std::numeric_limits<double>::infinity();  ///< stop a repetition at ≤ this
  double max_wall_time_s = 0;  ///< per repetition, 0 = none (non-deterministic when it triggers)
  double error_cost = kDefaultErrorCost;                   ///< given to non-finite costs, finite
  std::function<void(const SearchProgress&)> on_progress;  ///< optional, called on this thread
  /// The chosen algorithm's options, repetitions ≥ 1, target not NaN, error_cost finite, …
  Status Validate(const ParamBox& box) const;
};

/// Best cost so far after each iteration of each repetition, against evaluations since the start
/// of the search (all repetitions), and the wall time (the only non-deterministic field).
struct SearchTrace {
  std::vector<int64_t> evaluations;
  std::vector<double> best_cost;  ///< best over the whole search so far (non-increasing)
  std::vector<double> wall_time_s;
};

struct SearchResult {
  std::vector<double> best;  ///< physical values, box order
  double best_cost = 0;
  int64_t evaluations = 0;  ///< all repetitions
  int iterations = 0;       ///< iterations / generations, all repetitions
  double wall_time_s = 0;
  std::string stop_reason;  ///< of the best repetition, e.g. "stall: no relative improvement
                            ///< > 1e-06 in 60 iterations"
  int best_repetition = 0;
  SearchTrace trace;
  std::vector<double> repetition_costs;              ///< best cost of each repetition
  std::vector<std::vector<double>> repetition_best;  ///< best parameters of each repetition
};

/// A FitnessFunction from a callable of the physical values (Genome::reals). The callable must be
/// thread-safe when used with a thread pool; exceptions and non-finite costs are turned into kError
/// results by the evaluators (opt/inline_evaluator.h).
class FunctionFitness final : public FitnessFunction {
 public:
  using Function = std::function<FitnessResult(std::span<const double> values)>;
  explicit FunctionFitness(Function f) : f_(std::move(f)) {}
  FitnessResult Evaluate(const Genome& genome) const override { return f_(genome.reals); }

 private:
  Function f_;
};

/// Minimises the FitnessFunction behind `evaluator` over the box (genomes carry reals = physical
/// values; for kGaBinary the bits are decoded to reals before evaluation). Deterministic for a
/// seed, whatever the evaluator (inline, thread pool, service). Throws InputError on invalid
/// box/options.
SearchResult Search(const ParamBox& box, const SearchOptions& options, BatchEvaluator& evaluator);

/// Decodes `bits` (bits_per_parameter per parameter, most significant first, Gray or plain) to
/// unit-box coordinates: code / (2^bits − 1). Exposed for tests.
void DecodeBits(const uint8_t* bits, size_t parameters, int bits_per_parameter, bool gray_code,
                double* unit);

}  // namespace pz::opt
