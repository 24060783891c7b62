// The report of `piezoid diagnose --records PATH --family NAME` (the diagnosis of
// diagnose/diagnose.h on a record set of any drive; the command: client/cmd_diagnose.cc):
// report.md, diagnosis.json, withheld traces and figures, the excitation report and its proposed
// training drive excitation_drive.csv.
#pragma once

#include <filesystem>
#include <ostream>
#include <string>
#include <vector>

#include "diagnose/diagnose.h"
#include "io/records.h"
#include "records/select.h"

namespace google::protobuf {
class Value;
}
namespace pz::proto {
class Diagnosis;
class DiagnosisCandidate;
class RunnerUp;
}  // namespace pz::proto

namespace pz::reports {

/// The report folder of a records diagnosis `d` of `set` (`piezoid diagnose --records`): report.md,
/// diagnosis.json, the proposed training drive (kProposedDriveFile), the withheld traces and the
/// residual spectra in figures/, rendered when `plots` and gnuplot is installed. `selection`:
/// --family auto's choice (null: none). Returns the figures' rendering errors (warnings).
std::vector<std::string> WriteRecordsDiagnosisFolder(
    const std::filesystem::path& out, const io::RecordSet& set, const diagnose::RecordDiagnosis& d,
    double settle_s, const records::SelectionResult* selection, bool plots);

/// `proposal`: the training drive proposed from d.excitation (written as excitation_drive.csv).
void WriteRecordsDiagnosisMarkdown(std::ostream& os, const io::RecordSet& set,
                                   const diagnose::RecordDiagnosis& d,
                                   const records::TrainingDriveProposal& proposal,
                                   double settle_s = 0,
                                   const records::SelectionResult* selection = nullptr);
/// The one fill of diagnosis.json's message from a records result, for both kinds (this file's
/// `diagnose --records` and the fin bench's, reports/diagnose_report.h): the verdict and its kind.
void DiagnosisCommonOf(const diagnose::RecordDiagnosis& d, proto::Diagnosis* out);
/// A candidate's fields of both kinds: effect, score, closed, pattern, qualifies, note.
void CandidateCommonOf(const diagnose::RecordCandidate& c, proto::DiagnosisCandidate* out);
/// The effect named among ranked `candidates` (index `named`): its name, or null for −1.
void NamedOf(const std::vector<diagnose::RecordCandidate>& candidates, int named,
             google::protobuf::Value* out);
/// The runner-up `runner_up` (≥ 0) and its paired block z against the named effect.
void RunnerUpOf(const std::vector<diagnose::RecordCandidate>& candidates, int runner_up, double z,
                proto::RunnerUp* out);

/// The diagnosis as its stored message (diagnosis.json, proto/diagnosis.proto; the one
/// conversion; `out` replaced). `selection`: --family auto's choice (null: none).
void RecordsDiagnosisOf(const io::RecordSet& set, const diagnose::RecordDiagnosis& d,
                        const records::TrainingDriveProposal& proposal,
                        const records::SelectionResult* selection, proto::Diagnosis* out);
/// diagnosis.json (io/diagnosis_json.h).
void WriteRecordsDiagnosisJson(std::ostream& os, const io::RecordSet& set,
                               const diagnose::RecordDiagnosis& d,
                               const records::TrainingDriveProposal& proposal,
                               const records::SelectionResult* selection = nullptr);

}  // namespace pz::reports
