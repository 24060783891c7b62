// `piezoid identify`: an HGANN identification on one machine (GA + thread pool), and its result
// folder: best network (.pb, .json), per-generation progress log, validation of every case (PI grid
// beside the paper's Table 8), identified parameters per case (paper Tables 6, 7, 9, 10, 12, 13) with
// the regression of μ on V and f (paper eq. 7), figures, and a report.
#pragma once

#include <filesystem>
#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "io/bench_data.h"
#include "io/network_io.h"
#include "opt/ga.h"
#include "hgann/hgann_fitness.h"

namespace pz::client {

struct IdentifyOptions {
  std::filesystem::path cases_dir;  ///< bench case set (cases.csv + per-case CSV)
  std::filesystem::path out_dir;    ///< result folder (created)
  opt::GaOptions ga;             ///< population, generations, stall, seed, …
  int threads = 0;                  ///< evaluator threads (0 = all cores)
  std::string ranges = "default";   ///< parameter ranges preset: "default" (spec §3) or "paper" (Table 3)
  double spread_penalty = 0;        ///< λ [deg²] of HgannFitnessConfig::spread_penalty (0 = paper's cost)
  bool plots = true;                ///< render figures with gnuplot
  std::string job_id = "local";     ///< provenance
};

struct IdentifyResult {
  opt::GaSummary summary;
  std::vector<opt::GenerationSummary> log;
  io::SavedNetwork best;
  std::vector<hgann::HgannCaseResult> cases;  ///< every case of the set, in manifest order
};

/// The parameter ranges of a preset name; throws InputError naming the value.
model::ParameterRanges RangesPreset(const std::string& name);

/// Runs the GA on the case set's training cases. `on_generation` sees every generation summary.
IdentifyResult RunIdentify(const IdentifyOptions& options, const io::CaseSet& set,
                           const hgann::HgannFitness& fitness,
                           const std::function<void(const opt::GenerationSummary&)>& on_generation);

/// Writes the result folder and prints a summary to `terminal`. Returns the files written.
std::vector<std::filesystem::path> WriteIdentifyReport(const IdentifyOptions& options, const io::CaseSet& set,
                                                       const hgann::HgannFitness& fitness,
                                                       const IdentifyResult& result, std::ostream& terminal);

/// The paper's Table 8 PI [deg²] for an operating point, or NaN if it is not one of the nine.
double PaperTable8Pi(double amplitude_v, double frequency_hz);

}  // namespace pz::client
