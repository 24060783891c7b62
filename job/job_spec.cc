#include "job/job_spec.h"

#include <cmath>
#include <set>
#include <type_traits>
#include <utility>

#include "model/status.h"

namespace pz::job {

int GaSettings::offspring() const {
  return population - static_cast<int>(std::lround(population * elite_fraction));
}

namespace {

using Problem = decltype(JobSpec::problem);
static_assert(std::is_same_v<std::variant_alternative_t<0, Problem>, std::monostate>,
              "JobSpec::problem starts with std::monostate (no problem set)");

template <typename P>
constexpr std::string_view KindOf() {
  if constexpr (std::is_same_v<P, std::monostate>) {
    return "";
  } else {
    return P::kKind;  // every problem names its kind
  }
}

template <size_t... I>
std::vector<std::string> KindNames(std::index_sequence<I...>) {
  return {std::string(KindOf<std::variant_alternative_t<I + 1, Problem>>())...};  // after monostate
}

}  // namespace

std::optional<HgannSearchSettings> HgannSearchPreset(std::string_view name) {
  if (name == "paper") return HgannSearchSettings{};
  if (name.empty() || name == kDefaultHgannPreset)
    return HgannSearchSettings{
        .islands = 4,
        .generations = 250,
        .spread_penalty = 10,
        .trend_seeds = true,
        .stall_generations = 30,
        .stall_relative = 1e-6,
        .repair_loops = true};
  return std::nullopt;
}

std::string JobSpec::kind() const {
  return std::visit([](const auto& p) { return std::string(KindOf<std::decay_t<decltype(p)>>()); },
                    problem);
}

std::vector<std::string> JobKindNames() {
  return KindNames(std::make_index_sequence<std::variant_size_v<Problem> - 1>());
}

std::vector<FieldViolation> JobSpec::Validate() const {
  Violations c;
  c.Require(
      version == kJobSpecVersion, "version", version,
      "unsupported job spec version (this master reads " + std::to_string(kJobSpecVersion) + ")");
  c.Require(name.size() <= 200, "name", name.size(), "must be ≤ 200 characters");
  c.Range("limits.task_timeout_s", limits.task_timeout_s, 0.001, 86400.0);
  c.Range("limits.quarantine_after", limits.quarantine_after, 1, 100);
  c.Finite("limits.penalty_cost", limits.penalty_cost);
  if (limits.target_cost) c.Finite("limits.target_cost", *limits.target_cost);

  if (std::holds_alternative<HgannProblem>(problem)) {
    // Checked by the "hgann" job kind (hgann/hgann_job.h), which knows the model.
  } else if (const auto* s = std::get_if<SyntheticProblem>(&problem)) {
    c.Range("synthetic.genome_bits", s->genome_bits, 1, 65536);
    c.Range("synthetic.sleep_ms", s->sleep_ms, 0.0, 60000.0);
    bool bits01 = s->crash_prefix.find_first_not_of("01") == std::string::npos;
    c.Require(bits01 && static_cast<int>(s->crash_prefix.size()) <= s->genome_bits,
              "synthetic.crash_prefix", s->crash_prefix, "must be a 0/1 string ≤ genome_bits");
  } else if (const auto* m = std::get_if<CompleteModelProblem>(&problem)) {
    // The generic ranges; the records and the family's rules are checked by the "complete_model"
    // job kind (complete/job_kind.h), which knows the models.
    c.Require(m->family != CompleteModelProblem::Family::kUnspecified, "complete_model.family",
              "COMPLETE_MODEL_FAMILY_UNSPECIFIED",
              "must be BW_OSCILLATOR, STACK_BOUC_WEN or STACK_BACKLASH_LIKE");
    c.Require(!m->records.empty(), "complete_model.records", "0 records",
              "at least one record is needed");
    c.Require(std::isfinite(m->error_cost) && m->error_cost > 0, "complete_model.error_cost",
              m->error_cost, "must be finite and > 0");
    c.Require(m->source.size() <= 1000, "complete_model.source", m->source.size(),
              "must be ≤ 1000 characters");
  } else if (std::holds_alternative<std::monostate>(problem)) {
    std::string kinds;
    for (const std::string& k : JobKindNames()) kinds += (kinds.empty() ? "" : ", ") + k;
    c.Add("problem", "problem: one of " + kinds + " must be set");
  }

  if (ga && external) {
    c.Add("algorithm", "algorithm: only one of ga, external may be set");
  } else if (external) {
    c.Range("external.idle_timeout_s", external->idle_timeout_s, 0.1, 86400.0);
    c.Require(external->owner.size() <= 200, "external.owner", external->owner.size(),
              "must be ≤ 200 characters");
  } else if (!ga) {
    c.Add("algorithm", "algorithm: one of ga, external must be set");
  } else {
    c.Range("ga.population", ga->population, 2, 1000000);
    c.Require(ga->elite_fraction > 0 && ga->elite_fraction < 1, "ga.elite_fraction",
              ga->elite_fraction, "must be in (0, 1)");
    const int elite = static_cast<int>(std::lround(ga->population * ga->elite_fraction));
    c.Require(elite >= 1 && elite <= ga->population - 1, "ga.elite_fraction", ga->elite_fraction,
              "round(population · elite_fraction) = " + std::to_string(elite) +
                  " must be in [1, population − 1]");
    c.Range("ga.tournament", ga->tournament, 1, 1000000);
    c.Range("ga.crossover_probability", ga->crossover_probability, 0.0, 1.0);
    c.Range("ga.mutation_probability", ga->mutation_probability, 0.0, 1.0);
    c.Range("ga.generations", ga->generations, 0, 100000000);
    c.Range("ga.stall_generations", ga->stall_generations, 0, 100000000);
    c.Range("ga.islands", ga->islands, 1, 1024);
    c.Require(static_cast<int64_t>(ga->islands) * ga->population <= 1000000, "ga.islands",
              ga->islands,
              "islands · population must be ≤ 1000000 (population " +
                  std::to_string(ga->population) + ")");
    c.Range("ga.migration_interval", ga->migration_interval, 0, 100000000);
    c.Range("ga.migrants", ga->migrants, 0, std::max(0, ga->population - 1));
    c.Require(ga->migration_interval == 0 || ga->migrants >= 1, "ga.migrants", ga->migrants,
              "must be ≥ 1 when ga.migration_interval > 0 (0 runs the islands independently)");
    c.Require(opt::ValidTopology(ga->topology), "ga.topology", static_cast<int>(ga->topology),
              "must be MIGRATION_TOPOLOGY_RING, _FULLY_CONNECTED or _RANDOM");
    c.Require(ga->migration_margin >= 0 && ga->migration_margin < 1, "ga.migration_margin",
              ga->migration_margin, "must be in [0, 1) (0 = migrants from every source)");
    c.Range("ga.island_stall_generations", ga->island_stall_generations, 0, 100000000);
    c.Range("ga.broadcast_interval", ga->broadcast_interval, 0, 100000000);
    c.Require(ga->broadcast_interval == 0 || ga->migrants >= 1, "ga.migrants", ga->migrants,
              "must be ≥ 1 when ga.broadcast_interval > 0");
    c.Require(ga->broadcast_margin > 0 && ga->broadcast_margin < 1, "ga.broadcast_margin",
              ga->broadcast_margin, "must be in (0, 1)");
    c.Require(
        ga->island_mutation.empty() ||
            ga->island_mutation.size() == static_cast<size_t>(ga->islands),
        "ga.island_mutation.size()", ga->island_mutation.size(),
        "must be 0 (the default ladder: ga.mutation_probability × 1, 2, 3, 5) or ga.islands = " +
            std::to_string(ga->islands));
    for (size_t i = 0; i < ga->island_mutation.size(); ++i)
      c.Range("ga.island_mutation[" + std::to_string(i) + "]", ga->island_mutation[i], 0.0, 1.0);
    // In 64 bits: population and elite_fraction may both be out of range here (a fuzzer found it).
    const int64_t offspring = int64_t{ga->population} - elite;
    c.Require(ga->output_moves == opt::GaOptions::kAutoOutputMoves ||
                  (ga->output_moves >= 0 && ga->output_moves <= offspring),
              "ga.output_moves", ga->output_moves,
              "must be in [0, population − round(population · elite_fraction) = " +
                  std::to_string(offspring) +
                  "] (unset: 0 with one island, 16 % of the offspring with several)");
  }
  return std::move(c.out);
}

}  // namespace pz::job
