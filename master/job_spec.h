// The job specification as the master, the workers and the client library see it (conventions 3,
// 12): plain structs with defaults, decoded from proto/job.proto by master/wire_codec.h.
#pragma once

#include <algorithm>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace pz::master {

inline constexpr uint32_t kJobSpecVersion = 1;

/// One violated rule of a job spec: the field path (as in the JSON spec) and what is wrong.
struct FieldViolation {
  std::string field;        ///< e.g. "ga.population"
  std::string description;  ///< e.g. "ga.population = 1: must be ≥ 2"
  bool operator==(const FieldViolation&) const = default;
};

/// A searched parameter: `bits` bits decoded to [min, max].
struct ParameterRange {
  std::string name;
  double min = 0;  ///< lower bound, in the parameter's unit
  double max = 1;  ///< upper bound, > min
  int bits = 16;   ///< resolution, 1..32
};

/// A measured experiment, uniformly sampled.
struct BenchCase {
  std::string name;
  double sample_time_s = 0;       ///< > 0 [s]
  std::vector<double> input_v;    ///< drive voltage [V]
  std::vector<double> output_m;   ///< measured displacement [m], same length as input_v
  double weight = 1;              ///< > 0
};

/// The HGANN identification problem (its fitness is registered as job kind "hgann").
struct HgannProblem {
  std::string plant_model;                     ///< e.g. "bimorph"
  std::map<std::string, double> plant_options;
  std::string solver;                          ///< "" = plant default
  std::vector<BenchCase> cases;                ///< ≥ 1
  std::vector<ParameterRange> ranges;          ///< ≥ 1
  std::vector<int> hidden;                     ///< hidden layer widths, each 1..1024
  std::string metric;                          ///< "" = default
};

/// A synthetic problem for tests and benchmarks (job kind "synthetic").
struct SyntheticProblem {
  enum class Cost { kNull, kFunction };
  Cost cost = Cost::kFunction;
  int genome_bits = 64;      ///< 1..65536
  double sleep_ms = 0;       ///< each evaluation sleeps this long, 0..60000 [ms]
  std::string crash_prefix;  ///< test aid: genomes starting with these 0/1 bits kill the evaluator
};

/// Settings of the HGANN binary GA (master/ga.h GaOptions; genome length, seed, target and error
/// cost come from the problem, the spec's seed and its limits).
struct GaSettings {
  int population = 400;                ///< 2..1000000
  double elite_fraction = 0.5;         ///< (0, 1); round(population · fraction) in 1..population−1
  int tournament = 2;                  ///< ≥ 1
  double crossover_probability = 1.0;  ///< 0..1
  double mutation_probability = 0.01;  ///< 0..1
  int generations = 1000;              ///< max generations after the initial one, ≥ 0
  int stall_generations = 200;         ///< ≥ 0 (0 = never stop for stall)
  int offspring() const;               ///< evaluated per generation: population − elite count
};

/// Service limits of a job.
struct JobLimits {
  double task_timeout_s = 60;         ///< max wall time of one evaluation (0.001..86400) [s]
  int quarantine_after = 3;           ///< failed leases before quarantine, 1..100
  double penalty_cost = 1e9;          ///< finite cost of errored / quarantined individuals
  std::optional<double> target_cost;  ///< stop once best ≤ this
};

struct JobSpec {
  uint32_t version = kJobSpecVersion;
  std::string name;
  uint64_t seed = 0;
  JobLimits limits;
  std::variant<std::monostate, HgannProblem, SyntheticProblem> problem;
  std::optional<GaSettings> ga;  ///< the algorithm (only the GA so far)

  /// "hgann", "synthetic" or "" when no problem is set.
  std::string kind() const;
  /// Generic checks (every field's range); kind-specific checks come from the job-kind registry.
  std::vector<FieldViolation> Validate() const;
};

}  // namespace pz::master
