// The job specification as the master, the workers and the client library see it (conventions 3,
// 12): plain structs with defaults, decoded from proto/job.proto by service/wire_codec.h.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <sstream>
#include <variant>
#include <vector>

#include "model/case_role.h"
#include "model/status.h"
#include "opt/ga.h"
#include "opt/topology.h"

namespace pz::job {

inline constexpr uint32_t kJobSpecVersion = 1;

/// One violated rule of a job spec: the field path (as in the JSON spec) and what is wrong.
struct FieldViolation {
  std::string field;        ///< e.g. "ga.population"
  std::string description;  ///< e.g. "ga.population = 1: must be ≥ 2"
  bool operator==(const FieldViolation&) const = default;
};

/// The one collector of violations: every check of a spec adds to one list, so that a client is
/// told every violated field at once ("<field> = <value>: <rule>", model/status.h FieldError).
class Violations {
 public:
  template <typename T>
  void Require(bool ok, const std::string& field, const T& value, const std::string& rule) {
    if (!ok) out.push_back({field, FieldError(field, value, rule)});
  }
  template <typename T>
  void Range(const std::string& field, T value, T lo, T hi) {
    Require(value >= lo && value <= hi, field, value,
            "must be in [" + Num(lo) + ", " + Num(hi) + "]");
  }
  void Finite(const std::string& field, double value) {
    Require(std::isfinite(value), field, value, "must be finite");
  }
  void Add(const std::string& field, const std::string& description) {
    out.push_back({field, description});
  }
  std::vector<FieldViolation> out;

 private:
  template <typename T>
  static std::string Num(T v) {
    std::ostringstream os;
    os << v;
    return os.str();
  }
};

/// Override of the range of one of the seven identified parameters (proto ParameterRange).
struct ParameterRange {
  std::string name;  ///< "mu", "delta", "alpha", "beta", "gamma", "a1", "a2"
  double min = 0;    ///< lower bound, in the parameter's unit, finite
  double max = 1;    ///< upper bound, finite, ≥ min
};

using model::CaseRole;  // model/case_role.h: the one train / validate / test enum

/// One bench case of a bimorph-fin case set (proto HgannCase; io/bench_data.h BenchCase).
struct HgannCaseSpec {
  int number = 0;                          ///< > 0, unique
  double amplitude_v = 0;                  ///< V [V], finite, ≥ 0
  double frequency_hz = 0;                 ///< f [Hz], finite, > 0
  CaseRole role = CaseRole::kUnspecified;  ///< must be set
  double sample_rate_hz = 0;               ///< fs [Hz], finite, > 0
  std::vector<double> angle_deg;  ///< measured fin angle [deg] at t = k / fs, ≥ 2 samples, finite
  std::vector<double> voltage_v;  ///< recorded drive [V]: empty or as many as angle_deg, finite
  std::optional<double> b1, b2;   ///< saturations [deg] (only with Saturation::kGiven)
};

/// The search settings of an hgann preset (proto HgannProblem.preset; `piezoid identify
/// --preset`): what a spec's unset ga.islands, ga.generations, hgann.spread_penalty and
/// hgann.trend_seeds mean. "robust" — the default: 4 islands × 250 generations, λ 10, trend seeds;
/// the result does not depend on the seed beyond the noise of the fit (docs/performance.md,
/// "Trend seeds") — and "paper" (the paper's Table 2: one population, 1000 generations, the
/// paper's cost, uniform bits).
struct HgannSearchSettings {
  int islands = 1;
  int generations = 1000;
  double spread_penalty = 0;  ///< λ [deg²]
  bool trend_seeds = false;
  /// The GA's stop: stall_generations generations in which no generation lowers the best cost by
  /// more than stall_relative of it (opt::GaOptions). The robust preset's: 30 and 1e-6 (after
  /// the trend seeds the GA found nothing lower on every bench of docs/performance.md); the
  /// paper's: 200 and 0 (Table 2).
  int stall_generations = 200;
  double stall_relative = 0;
  /// A child whose Bouc–Wen loop is unbounded is repaired into the bounded region before it is
  /// evaluated (hgann/loop_repair.h): the robust preset's (a third of its evaluations were such
  /// refusals); the paper's GA evaluates genomes as made.
  bool repair_loops = false;
};
inline constexpr const char* kDefaultHgannPreset = "robust";
/// "" (= kDefaultHgannPreset), "robust" or "paper"; nullopt for another name (kHgannPresetRule).
std::optional<HgannSearchSettings> HgannSearchPreset(std::string_view name);
inline constexpr const char* kHgannPresetRule =
    "must be \"robust\" (the default: islands, spread penalty, trend seeds) or \"paper\" (the "
    "paper's Table 2)";

/// The HGANN identification problem (job kind "hgann", hgann/hgann_job.h).
struct HgannProblem {
  static constexpr std::string_view kKind = "hgann";  ///< JobSpec::kind()
  enum class Saturation { kFromExtremes = 0, kGiven = 1 };
  std::vector<HgannCaseSpec> cases;    ///< ≥ 1 training case
  std::string case_set_dir;            ///< client side only: must be empty at the master
  std::string source;                  ///< where the cases came from (reports), ≤ 1000 chars
  std::string ranges_preset;           ///< "" / "default" (spec §3) or "paper" (Table 3)
  std::vector<ParameterRange> ranges;  ///< per-parameter overrides of the preset
  double spread_penalty = 0;           ///< λ [deg²], finite, ≥ 0
  Saturation saturation = Saturation::kFromExtremes;
  /// Overrides of the bench's beam (model/beam.h BeamGeometry), by field name, e.g.
  /// {"tip_length_m", 0.02}; n_active and n_tip are whole numbers.
  std::map<std::string, double> geometry;
  /// Generation 0 holds the trend seeds of hgann/trend_seeds.h (networks fitted to per-case fits
  /// of the training cases) in island 0's first slots; false = uniform bits (the paper's GA).
  bool trend_seeds = false;
  /// The preset that filled the spec's unset settings when it was decoded (HgannSearchPreset;
  /// "" = the default, robust). The fields here hold the values: a spec encodes only what
  /// differs from its preset.
  std::string preset;
  /// The user's feasible operating points (V [V], f [Hz]) for the next-case proposal (query by
  /// committee, hgann/operating_law.h); empty: the case set's withheld cases are the candidates.
  /// Each finite and > 0 (kNextCandidateRule), at most kMaxNextCandidates.
  std::vector<std::pair<double, double>> next_candidates;
};
inline constexpr size_t kMaxNextCandidates = 1000;

/// A synthetic problem for tests and benchmarks (job kind "synthetic").
struct SyntheticProblem {
  static constexpr std::string_view kKind = "synthetic";
  enum class Cost { kNull, kFunction };
  Cost cost = Cost::kFunction;
  int genome_bits = 64;      ///< 1..65536
  double sleep_ms = 0;       ///< each evaluation sleeps this long, 0..60000 [ms]
  std::string crash_prefix;  ///< test aid: genomes starting with these 0/1 bits kill the evaluator
};

/// One sampled record of a complete-model identification (proto CompleteModelRecord).
struct CompleteModelRecord {
  std::string name;            ///< label in messages, ≤ 200 chars
  double sample_rate_hz = 0;   ///< fs [Hz], finite, > 0
  std::vector<double> input;   ///< u_k at t = k / fs, ≥ 2 samples, finite
  std::vector<double> output;  ///< measured y_k, as many as input, finite
  uint64_t first_counted = 0;  ///< oscillator: warm-up samples simulated but not counted;
                               ///< records: the first scored sample
  // Family kRecords only (records/fit.h, io::Record):
  double dt_s = 0;            ///< the record's step [s] (exact; sample_rate_hz is informative)
  uint64_t end_counted = 0;   ///< one past the last scored sample, ≤ samples
  uint64_t rest_samples = 1;  ///< leading samples at the first sample's drive, 1 … samples
  int offset_mode = 0;        ///< io::OffsetMode: 0 fit, 1 rest, 2 fixed
  double offset = 0;          ///< rest: the measured rest level; fixed: the offset
  /// bench_form: the record's stated sinusoid (io::Record::StatedSinusoid; proto StatedSinusoid).
  struct Sinusoid {
    int64_t case_number = 0;
    double amplitude_v = 0, frequency_hz = 0, cycles = 0, sample_rate_hz = 0;
  };
  std::optional<Sinusoid> sinusoid = std::nullopt;  ///< on the wire when set
};

/// Complete-model identification (job kind "complete_model", complete/job_kind.h): genome.reals =
/// the family's physical parameters; cost = the family's criterion on the records.
struct CompleteModelProblem {
  static constexpr std::string_view kKind = "complete_model";
  enum class Family {
    kUnspecified = 0,
    kBwOscillator = 1,
    kStackBoucWen = 2,
    kStackBacklashLike = 3,
    kRecords = 4
  };
  enum class Criterion { kIae = 1, kSse = 2, kRmse = 3, kMax = 4 };
  enum class Interpolation { kZoh = 1, kLinear = 2, kSpline = 3, kFourier = 4 };
  Family family = Family::kUnspecified;
  std::vector<CompleteModelRecord> records;  ///< ≥ 1
  Criterion criterion = Criterion::kIae;     ///< records with a window
  double t0_s = 0, t1_s = 0;  ///< records: the criterion's window [s] (0, 0: none, the MSE)
  int substeps = 0;           ///< 0 = the family's default (oscillator 4, records 2)
  Interpolation interpolation = Interpolation::kSpline;  ///< oscillator
  uint64_t period_samples = 0;                           ///< oscillator, Fourier (0 = whole record)
  double error_cost = 1e30;  ///< cost of a diverged / invalid parameter set
  std::string source;        ///< free text, ≤ 1000 chars
  // Family kRecords: `piezoid fit` / `diagnose --records` on the service (records/fit.h).
  std::string record_family;         ///< records/families.h name
  std::vector<std::string> effects;  ///< records/model.h effect names
  int pi_operators = 12;             ///< Prandtl–Ishlinskii plays, 1 … 10000
  std::string initial_state;  ///< FamilyOptions::initial_state by name ("" = its default, auto)
  /// The data scale the client measured (records::DataScale, in this order): u_min, u_max, u_half,
  /// y_half, gain, polarity, f_dom, fs, duration — sent so that the workers' search box and model
  /// are the client's, bit for bit.
  std::vector<double> scale;
  /// record_family bimorph-fin: its bench form (records/families.h FamilyOptions::bench_form) and
  /// the simulator's options (records/fin_effects.h EffectSimOptions; unset: its defaults).
  bool bench_form = false;
  struct FinSim {
    int oversample = 4;
    double rtol = 1e-6, atol = 1e-13;
    int64_t max_steps = 5000000;
    bool force_cvode = false;
  };
  std::optional<FinSim> fin_sim = std::nullopt;  ///< on the wire when set
  /// Records without a window: results carry the training residual vector (records/fit.h
  /// RecordResidualFitness), the polish's Jacobian columns; false: the cost alone.
  bool residuals = false;
};

/// An evaluation session (proto ExternalSettings): the client owning the job optimises and sends
/// batches of genomes; the master only evaluates them.
struct ExternalSettings {
  double idle_timeout_s = 120;  ///< cancelled after this long without a request from its client [s]
  std::string owner;            ///< free text, ≤ 200 chars
};

/// Settings of the HGANN binary GA (opt/ga.h GaOptions; genome length, seed, target and error
/// cost come from the problem, the spec's seed and its limits).
struct GaSettings {
  int population = 400;         ///< 2..1000000
  double elite_fraction = 0.5;  ///< (0, 1); round(population · fraction) in 1..population−1
  int tournament = 2;           ///< ≥ 1
  double crossover_probability = 1.0;  ///< 0..1
  double mutation_probability = 0.01;  ///< 0..1
  int generations = 1000;              ///< max generations after the initial one, ≥ 0
  int stall_generations = 200;         ///< ≥ 0 (0 = never stop for stall)
  // Islands (opt/ga.h GaOptions): population is per island.
  int islands = 1;              ///< 1..1024
  int migration_interval = 25;  ///< ≥ 0 (0 = never: independent islands)
  int migrants = 4;             ///< 0..population − 1, ≥ 1 when migration_interval > 0
  opt::MigrationTopology topology = opt::MigrationTopology::kFullyConnected;
  double migration_margin = 0.2;     ///< [0, 1) (0 = migrants from every source; opt/ga.h)
  int island_stall_generations = 0;  ///< ≥ 0 (0 = never restart an island)
  int broadcast_interval = 0;  ///< ≥ 0 (0 = no gated broadcast; opt/ga.h), ≥ 1 migrant when > 0
  double broadcast_margin = 0.2;  ///< (0, 1): the broadcast's gate (opt/ga.h)
  std::vector<double>
      island_mutation;  ///< empty (the ladder of opt/ga.h) or one rate per island, each 0..1
  int output_moves =
      opt::GaOptions::kAutoOutputMoves;  ///< offspring per island made by the kind's move
                                         ///< (opt/ga.h 9.), 0..population − elite; auto (−1): 0
                                         ///< with one island, 16 % of the offspring with several
  int offspring() const;                 ///< evaluated per generation: population − elite count
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
  /// The problem; each names its job kind (kKind). A new kind adds its problem struct here.
  std::variant<std::monostate, HgannProblem, SyntheticProblem, CompleteModelProblem> problem;
  /// The algorithm: exactly one of the GA (run by the master) and an external optimiser (an
  /// evaluation session driven by the client).
  std::optional<GaSettings> ga;
  std::optional<ExternalSettings> external;

  /// The problem's kKind ("hgann", "synthetic", "complete_model"), "" when no problem is set.
  std::string kind() const;
  /// "ga", "external" or "".
  std::string algorithm() const { return ga ? "ga" : external ? "external" : ""; }
  /// Generic checks (every field's range); kind-specific checks come from the job-kind registry.
  std::vector<FieldViolation> Validate() const;
};

/// The kinds of every problem a spec can hold, in the order of JobSpec::problem.
std::vector<std::string> JobKindNames();

}  // namespace pz::job
