// `piezoid identify`'s result folder: best network (.pb, .json), per-generation progress log,
// validation of every case (PI grid beside the paper's Table 8), identified parameters per case
// (paper Tables 6, 7, 9, 10, 12, 13) with the regression of μ on V and f (paper eq. 7), figures, and
// a report. The run itself is hgann/identify.h.
#pragma once

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "hgann/identify.h"
#include "io/bench_data.h"

namespace pz::client {

/// The run's options (hgann::IdentifyOptions) and where / how to write its report.
struct IdentifyOptions : hgann::IdentifyOptions {
  std::filesystem::path out_dir;  ///< result folder (created)
  bool plots = true;              ///< render figures with gnuplot
};

/// Writes the result folder and prints a summary to `terminal`. Returns the files written.
std::vector<std::filesystem::path> WriteIdentifyReport(const IdentifyOptions& options, const io::CaseSet& set,
                                                       const hgann::HgannFitness& fitness,
                                                       const hgann::IdentifyResult& result, std::ostream& terminal);

}  // namespace pz::client
