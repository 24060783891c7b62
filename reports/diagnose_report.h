// Reports of `piezoid diagnose --cases` (the fin bench; diagnose-check's: reports/check_report.h):
// the terminal summary, the JSON record and the HTML report with its figures (gnuplot,
// reports/plots.h): residual vs drive phase per case, residual spectra, loops before/after, and the
// amplitude × frequency grid of PI before/after.
#pragma once

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "diagnose/fin_diagnose.h"

namespace pz::proto {
class Diagnosis;
}

namespace pz::reports {

/// The terminal summary: noise floor, where the gap lies, the candidates, the verdict, how far
/// the gap shrinks, the identifiability table.
void PrintDiagnosis(std::ostream& out, const diagnose::BenchDiagnosis& d,
                    const diagnose::DiagnoseOptions& options);

/// The diagnosis as its stored message (diagnosis.json, proto/diagnosis.proto; `out` replaced):
/// the records result's common fields (reports/records_diagnose.h DiagnosisCommonOf) and the
/// bench's own.
void BenchDiagnosisOf(const diagnose::BenchDiagnosis& d, const diagnose::DiagnoseOptions& options,
                      proto::Diagnosis* out);
/// diagnosis.json (io/diagnosis_json.h: keys sorted, a non-finite number as null).
void WriteDiagnosisJson(std::ostream& out, const diagnose::BenchDiagnosis& d,
                        const diagnose::DiagnoseOptions& options);

/// Writes dir/report.html with its data (CSV) and figures (gnuplot scripts, PNG if gnuplot runs):
/// the model traces are the records fits' outputs. Returns the files written; gnuplot problems
/// are appended to `warnings`.
std::vector<std::filesystem::path> WriteDiagnosisHtml(const std::filesystem::path& dir,
                                                      const diagnose::BenchDiagnosis& d,
                                                      const diagnose::DiagnoseOptions& options,
                                                      bool plots,
                                                      std::vector<std::string>* warnings);

}  // namespace pz::reports
