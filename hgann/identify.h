// `piezoid identify` on one machine: the HGANN identification of a bench case set by the GA
// (opt/ga.h) over a thread pool, with the HGANN fitness (hgann/hgann_fitness.h). The report of the
// run is reports/identify_report.h; the same run on the service is the "hgann" job kind
// (hgann/hgann_job.h), bit for bit.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "hgann/hgann_fitness.h"
#include "hgann/trend_seeds.h"
#include "io/bench_data.h"
#include "io/network_io.h"
#include "job/job_spec.h"
#include "model/network.h"
#include "opt/ga.h"

namespace pz::hgann {

struct IdentifyOptions {
  std::filesystem::path cases_dir;  ///< bench case set (cases.csv + per-case CSV)
  opt::GaOptions ga;                ///< population, generations, stall, seed, …
  int threads = 0;                  ///< evaluator threads (0 = all cores)
  std::string ranges =
      "default";  ///< parameter ranges preset: "default" (spec §3) or "paper" (Table 3)
  double spread_penalty = 0;  ///< λ [deg²] of HgannFitnessConfig::spread_penalty (0 = paper's cost)
  bool trend_seeds = false;      ///< generation 0 starts with the trend seeds (hgann/trend_seeds.h)
  /// Children with an unbounded loop repaired before evaluation (hgann/loop_repair.h): the
  /// default preset's, as a spec's without a preset (HgannRepairsLoops); false: the paper's GA.
  bool repair_loops = true;
  std::string preset;            ///< the search preset the settings came from (reports; "" = none)
  /// The user's feasible (V [V], f [Hz]) points for the next-case proposal (CommitteeOptions::
  /// candidates); empty: the case set's withheld cases are the candidates.
  std::vector<std::pair<double, double>> next_candidates;
  std::string job_id = "local";  ///< provenance
};

struct IdentifyResult {
  opt::GaSummary summary;
  int64_t repaired = 0;  ///< fresh genomes the loop repair rewrote (IdentifyOptions::repair_loops)
  std::vector<opt::GenerationSummary> log;
  io::SavedNetwork best;
  std::vector<HgannCaseResult> cases;  ///< every case of the set, in manifest order
  std::optional<TrendSeeds>
      seeds;  ///< with IdentifyOptions::trend_seeds: the per-case fits and seeds
  /// With the seeds' law: the committee of laws that fit alike, the best network kept among them
  /// (which withheld cases stay open, the next case to measure: hgann/operating_law.h).
  std::optional<LawCommittee> committee;
};

/// The parameter ranges of a preset: "" or "default" (spec §3), "paper" (the paper's Table 3);
/// nullopt for another name (kRangesPresetRule says what is allowed). The one parser of preset
/// names: the CLI's --ranges and a job spec's hgann.ranges_preset both use it.
std::optional<model::ParameterRanges> RangesPreset(std::string_view name);
inline constexpr const char* kRangesPresetRule =
    "must be \"default\" (spec ranges) or \"paper\" (the paper's Table 3)";

/// The settings of a search preset (`piezoid identify --preset`): the job spec's presets
/// (job::HgannSearchPreset: "robust", the default, and "paper"), so that a spec's defaults and
/// identify's are one table. The other GA settings are GaOptions' defaults.
using SearchSettings = job::HgannSearchSettings;
/// nullopt for an unknown or empty name (kSearchPresetRule).
std::optional<SearchSettings> SearchPreset(std::string_view name);
inline constexpr const char* kDefaultSearchPreset = job::kDefaultHgannPreset;
inline constexpr const char* kSearchPresetRule = job::kHgannPresetRule;

/// The committee of a run with a law (LawCommittee of the seeds' law, the best network kept as a
/// member, the options' candidates); nullopt without one. identify and the hgann job kind alike.
std::optional<LawCommittee> RunCommittee(const HgannFitness& fitness,
                                         const std::optional<TrendSeeds>& seeds,
                                         const model::Network& best,
                                         const std::vector<std::pair<double, double>>& candidates,
                                         int threads);

/// Runs the GA on the case set's training cases. `on_generation` sees every generation summary.
IdentifyResult RunIdentify(const IdentifyOptions& options, const io::CaseSet& set,
                           const HgannFitness& fitness,
                           const std::function<void(const opt::GenerationSummary&)>& on_generation);

/// The paper's Table 8 PI [deg²] for an operating point, or NaN if it is not one of the nine.
double PaperTable8Pi(double amplitude_v, double frequency_hz);

}  // namespace pz::hgann
