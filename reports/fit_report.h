// What `piezoid fit` writes (client/cmd_fit.cc runs the fit): report.md (the model, its parameters
// with their uncertainty, RMSE / max / NRMSE on the training and the withheld records, the
// extrapolation guard, the search, the excitation report, the fitted mode, the residual spectrum
// and, with --family auto, the selection), fit.json (reports/fit_file.h), the proposed training
// drive, per-record traces (CSV) and figures (time traces, hysteresis loops less the training
// line, error by reversal depth, the averaged error as creep), and the terminal summary.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "io/records.h"
#include "records/excitation.h"
#include "records/fit.h"
#include "records/select.h"

namespace pz::records {
struct ExtrapolationCheck;  // records/extrapolation.h
}

namespace pz::reports {

/// The run a report describes besides its result: the command's flags that the report states.
struct FitReportRun {
  std::string records;    ///< --records
  std::string family;     ///< the family fitted (with --family auto: the chosen one)
  bool selected = false;  ///< the family was chosen by --family auto
  double settle_s = 0;    ///< --settle-s
  int substeps = 2;       ///< --substeps
  int pi_operators = 0;   ///< the plays / levels (the chosen ones with --family auto)
  std::string out;        ///< the report folder (--out)
  bool figures = true;    ///< not --no-figures: the gnuplot figures
  std::string master;     ///< --master (empty: the fit ran on this machine)
};

/// The report folder `run.out`: report.md, fit.json, the proposed training drive
/// (kProposedDriveFile), the traces and, with run.figures, the figures (rendered when gnuplot is
/// installed). `selection`: --family auto's (or null). Returns the warnings (figures not
/// rendered).
std::vector<std::string> WriteFitFolder(
    const io::RecordSet& set, const records::FitResult& r, const FitReportRun& run,
    const records::ExcitationReport& excitation, const records::TrainingDriveProposal& proposal,
    const std::vector<records::ExtrapolationCheck>& extrapolation,
    const records::SelectionResult* selection);

/// The terminal's summary: each record's errors, the resolution and regularisation chosen, the
/// extrapolation warnings, the search and where the report is.
void PrintFitSummary(std::ostream& out, const io::RecordSet& set, const records::FitResult& r,
                     const FitReportRun& run,
                     const std::vector<records::ExtrapolationCheck>& extrapolation);

}  // namespace pz::reports
