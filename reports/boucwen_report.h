// What `piezoid boucwen` writes (client/cmd_boucwen.cc runs the identification): the terminal
// summary, report.json (proto::BoucwenReport of proto/boucwen.proto, printed by io/proto_json.h;
// the one conversion), report.md, the CSVs of the convergence and both test sets, and their
// gnuplot figures.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "opt/param_search.h"

namespace pz::reports {

/// The identification's outcome: the search, its box and result, and the test sets' scores.
struct BwOutcome {
  opt::SearchOptions options;
  opt::ParamBox box;
  opt::SearchResult result;
  int threads = 0;
  size_t n_train = 0;
  std::string where;  ///< " thread(s)" or " worker thread(s) of <master>"
  std::vector<double> theta_true;
  double train_rms = 0;
  size_t reach = 0;  ///< the first trace point within 1 % of the final best cost
  std::vector<double> measured_ms, measured_sw;  ///< the test sets' measured outputs
  std::vector<double> yms, ysw, yms_true, ysw_true;
  double rms_ms = 0, rms_sw = 0, rms_ms_true = 0, rms_sw_true = 0, max_ms = 0, max_sw = 0;
};

/// The flags a report states.
struct BoucwenRun {
  uint64_t seed = 1;        ///< --seed
  bool on_service = false;  ///< --master: evaluated on the service
  int substeps = 4;         ///< --substeps
  bool plots = true;        ///< not --no-plots: the gnuplot figures
};

/// The terminal's summary: training RMS, the search's cost, each parameter against the truth,
/// both test sets' errors.
void PrintBoucwenSummary(std::ostream& out, const BwOutcome& o);

/// report.json, report.md, the CSVs and (run.plots) the figures in `out`, created. Returns the
/// warnings (figures not rendered).
std::vector<std::string> WriteBoucwenReport(const std::filesystem::path& out, const BoucwenRun& run,
                                            const BwOutcome& o);

}  // namespace pz::reports
