// `piezoid identify`'s result folder: best network (.pb, .json), per-generation progress log,
// validation of every case (PI grid beside the paper's Table 8), identified parameters per case
// (paper Tables 6, 7, 9, 10, 12, 13) with the regression of μ on V and f (paper eq. 7), figures,
// and a report. The run itself is hgann/identify.h.
#pragma once

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "hgann/identify.h"
#include "io/bench_data.h"

namespace pz::reports {

/// The run's options (hgann::IdentifyOptions) and where / how to write its report.
struct IdentifyOptions : hgann::IdentifyOptions {
  std::filesystem::path out_dir;  ///< result folder (created)
  bool plots = true;              ///< render figures with gnuplot
};

/// The island columns of a progress.csv (both identify's and a fetched job's): empty for a run of
/// one island (its file is as before islands), else ",best_island,migrated,immigrants,restarted,
/// island_0_best,…,island_<K−1>_best" — the header, then each generation's cells in that order.
std::string IslandCsvHeader(const std::vector<opt::GenerationSummary>& log);
std::string IslandCsvCells(const opt::GenerationSummary& g);
/// The islands of a progress line (identify's, watch's): "" for one island, else e.g.
/// "  island 2/4 (islands 0.93…1.4)": the best's island and the range of the islands' bests.
std::string IslandsBrief(const opt::GenerationSummary& g);

/// Writes the result folder and prints a summary to `terminal`. Returns the files written.
std::vector<std::filesystem::path> WriteIdentifyReport(const IdentifyOptions& options,
                                                       const io::CaseSet& set,
                                                       const hgann::HgannFitness& fitness,
                                                       const hgann::IdentifyResult& result,
                                                       std::ostream& terminal);

}  // namespace pz::reports
