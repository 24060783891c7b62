// `piezoid diagnose --records PATH --family NAME`: the diagnosis of diagnose/diagnose.h on a record
// set of any drive, with its report (report.md, diagnosis.json, withheld traces and figures, the
// excitation report and its proposed training drive excitation_drive.csv).
#pragma once

#include <functional>
#include <ostream>
#include <string>
#include <vector>

#include "io/records.h"
#include "diagnose/diagnose.h"
#include "records/select.h"

namespace google::protobuf {
class Value;
}
namespace pz::proto {
class Diagnosis;
class DiagnosisCandidate;
class RunnerUp;
}  // namespace pz::proto

namespace pz::client {

struct RecordsDiagnoseRequest {
  std::string records;
  std::string family = "auto";  ///< "auto": chosen by records/select.h first (--family not given)
  std::vector<std::string> train_windows, validate_windows, test_windows;
  double settle_s =
      0;  ///< --settle-s: scored from this long after each record's rest (io::SkipSettling)
  std::string initial_state;  ///< --initial-state (empty: FamilyOptions' default)
  std::string out;
  std::string candidates;  ///< comma-separated, empty = every applicable effect
  int threads = 2;
  uint64_t seed = 1;
  bool quick = false;
  bool no_plots = false;
  bool quiet = false;
  double significance_ratio = 1.25;
  records::RecordEvaluatorFactory evaluator_factory;  ///< --master (null: local threads)
  /// --master with --family auto: the factory for a family's options (the chosen resolution's).
  std::function<records::RecordEvaluatorFactory(const records::FamilyOptions&)> service;
};

int RunRecordsDiagnose(const RecordsDiagnoseRequest& request);

/// `proposal`: the training drive proposed from d.excitation (written as excitation_drive.csv).
void WriteRecordsDiagnosisMarkdown(std::ostream& os, const io::RecordSet& set,
                                   const records::RecordDiagnosis& d,
                                   const records::TrainingDriveProposal& proposal,
                                   double settle_s = 0,
                                   const records::SelectionResult* selection = nullptr);
/// The one fill of diagnosis.json's message from a records result, for both kinds (this file's
/// `diagnose --records` and the fin bench's, client/diagnose_report.h): the verdict and its kind.
void DiagnosisCommonOf(const records::RecordDiagnosis& d, proto::Diagnosis* out);
/// A candidate's fields of both kinds: effect, score, closed, pattern, qualifies, note.
void CandidateCommonOf(const records::RecordCandidate& c, proto::DiagnosisCandidate* out);
/// The effect named among ranked `candidates` (index `named`): its name, or null for −1.
void NamedOf(const std::vector<records::RecordCandidate>& candidates, int named,
             google::protobuf::Value* out);
/// The runner-up `runner_up` (≥ 0) and its paired block z against the named effect.
void RunnerUpOf(const std::vector<records::RecordCandidate>& candidates, int runner_up, double z,
                proto::RunnerUp* out);

/// The diagnosis as its stored message (diagnosis.json, proto/diagnosis.proto; the one
/// conversion; `out` replaced). `selection`: --family auto's choice (null: none).
void RecordsDiagnosisOf(const io::RecordSet& set, const records::RecordDiagnosis& d,
                        const records::TrainingDriveProposal& proposal,
                        const records::SelectionResult* selection, proto::Diagnosis* out);
/// diagnosis.json (io/diagnosis_json.h).
void WriteRecordsDiagnosisJson(std::ostream& os, const io::RecordSet& set,
                               const records::RecordDiagnosis& d,
                               const records::TrainingDriveProposal& proposal,
                               const records::SelectionResult* selection = nullptr);

}  // namespace pz::client
