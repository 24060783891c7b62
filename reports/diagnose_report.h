// The one report of `piezoid diagnose` (issue 46; the command: client/cmd_diagnose.cc): the
// diagnosis of diagnose/diagnose.h on a record set of any drive (`--records`) and the fin bench's
// (`--cases`: the same records diagnosis plus its V × f grid, reports/bench_grid.h, written as an
// optional section): report.md, diagnosis.json (one shape, proto/diagnosis.proto), withheld
// traces and figures, the excitation report and its proposed training drive
// excitation_drive.csv; with the grid, its tables and each case's figures.
#pragma once

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "diagnose/diagnose.h"
#include "diagnose/fin_diagnose.h"
#include "io/records.h"
#include "records/select.h"

namespace pz::proto {
class Diagnosis;
class DiagnosisCandidate;
}  // namespace pz::proto

namespace pz::reports {

/// What a report holds beyond the records diagnosis.
struct DiagnosisReport {
  double settle_s = 0;                                  ///< --settle-s (0: none)
  const records::SelectionResult* selection = nullptr;  ///< --family auto's choice (null: none)
  /// The fin bench's diagnosis (its d.records is the diagnosis reported): its grid section
  /// (null: a record set's report).
  const diagnose::BenchDiagnosis* grid = nullptr;
};

/// The report folder of a diagnosis `d` of `set`: report.md, diagnosis.json, the proposed
/// training drive (kProposedDriveFile), the withheld traces and the residual spectra in figures/,
/// and with a grid each case's figures; rendered when `plots` and gnuplot is installed. Returns
/// the figures' rendering errors (warnings).
std::vector<std::string> WriteDiagnosisFolder(const std::filesystem::path& out,
                                              const io::RecordSet& set,
                                              const diagnose::RecordDiagnosis& d,
                                              const DiagnosisReport& report, bool plots);

/// report.md. `proposal`: the training drive proposed from d.excitation (excitation_drive.csv).
void WriteDiagnosisMarkdown(std::ostream& os, const io::RecordSet& set,
                            const diagnose::RecordDiagnosis& d,
                            const records::TrainingDriveProposal& proposal,
                            const DiagnosisReport& report = {});
/// A candidate of a round starting from `start` (its added parameters counted from it).
void CandidateOf(const diagnose::RecordCandidate& c, const records::FitResult& start,
                 proto::DiagnosisCandidate* out);

/// The diagnosis as its stored message (diagnosis.json, proto/diagnosis.proto; the one
/// conversion; `out` replaced): the records diagnosis's fields, and the grid's with one.
void DiagnosisOf(const io::RecordSet& set, const diagnose::RecordDiagnosis& d,
                 const records::TrainingDriveProposal& proposal, const DiagnosisReport& report,
                 proto::Diagnosis* out);
/// diagnosis.json (io/diagnosis_json.h).
void WriteDiagnosisJson(std::ostream& os, const io::RecordSet& set,
                        const diagnose::RecordDiagnosis& d,
                        const records::TrainingDriveProposal& proposal,
                        const DiagnosisReport& report = {});

}  // namespace pz::reports
