// diagnosis.json's codec (proto/diagnosis.proto, issue 38): the file <-> proto::Diagnosis, for
// both diagnoses (the records diagnosis of `piezoid diagnose --records` and the fin bench's of
// `piezoid diagnose --cases`), through io/proto_json.h (keys sorted, a non-finite number as null, a
// bad field named by its path), here only. The one conversion of each diagnosis to the message is
// its report writer's (reports/records_diagnose.cc, reports/diagnose_report.cc).
//
// A file is of one kind: "records" given (a records diagnosis) or "bench" (the fin bench's). The
// fields of the other kind (the option diagnosis_only) are not written — a list as [] neither —
// and a file that holds one is refused, naming it; "named" is a string or null in a records
// diagnosis and in every round, a list of strings in the bench's.
#pragma once

#include <string>

namespace pz::proto {
class Diagnosis;
}  // namespace pz::proto

namespace pz::io {

/// diagnosis.json's text. Throws std::logic_error when the message is of no kind or of both, or
/// holds a field of the other kind or a "named" of the wrong shape (a writer's bug).
std::string WriteDiagnosisFile(const proto::Diagnosis& d);

/// diagnosis.json text → the message (`out` replaced). Throws InputError naming `path` and: the
/// kind missing or both given, a field of the other kind, a bad field or value (by its path).
void ReadDiagnosisFile(const std::string& path, const std::string& text, proto::Diagnosis* out);

/// True when the message is a records diagnosis ("records" given), false for the fin bench's.
bool IsRecordsDiagnosis(const proto::Diagnosis& d);

}  // namespace pz::io
