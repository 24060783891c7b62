// The fin bench's grid section of the diagnosis report (reports/diagnose_report.h: the records
// report plus this section with `DiagnosisReport::grid`): the terminal summary of `piezoid
// diagnose --cases`, the grid's part of diagnosis.json (proto::BenchGrid), its report.md section
// (the noise per case, the V × f table of PI before / after, where the base model's residual lies,
// the trends of the per-case fits, every greedy round, how far the gap shrinks, the
// identifiability tables) and each case's figures (residual vs drive phase, residual spectrum,
// loop; gnuplot, reports/plots.h).
#pragma once

#include <filesystem>
#include <ostream>
#include <vector>

#include "diagnose/fin_diagnose.h"

namespace pz::proto {
class BenchGrid;
}

namespace pz::reports {

/// The terminal summary: noise floor, where the gap lies, the candidates, the verdict, how far
/// the gap shrinks, the identifiability table.
void PrintBenchSummary(std::ostream& out, const diagnose::BenchDiagnosis& d);

/// The grid's part of diagnosis.json (`out` replaced).
void BenchGridOf(const diagnose::BenchDiagnosis& d, proto::BenchGrid* out);

/// The grid's section of report.md; its figures are WriteBenchGridFigures's (figures/).
void WriteBenchGridMarkdown(std::ostream& out, const diagnose::BenchDiagnosis& d);

/// Each case's trace and spectrum (CSV) and the scripts of its figures in `figures` (appended to
/// `scripts`): the model traces are the records fits' outputs.
void WriteBenchGridFigures(const std::filesystem::path& figures, const diagnose::BenchDiagnosis& d,
                           std::vector<std::filesystem::path>& scripts);

}  // namespace pz::reports
