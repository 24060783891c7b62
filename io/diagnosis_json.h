// diagnosis.json's codec (proto/diagnosis.proto, issues 38, 46): the file <-> proto::Diagnosis,
// through io/proto_json.h (keys sorted, a non-finite number as null, a bad field named by its
// path), here only. The one conversion of a diagnosis to the message is the report writer's
// (reports/diagnose_report.h DiagnosisOf).
//
// One shape (format_version 2): a record set's diagnosis, the fin bench's with its optional
// "grid". Version 1 (no "format_version": a file of one of two kinds, "records" or "bench", the
// bench's parts at the top level, "named" a string or null, or the bench's list) is converted on
// read: "bench" becomes "records", the bench's parts move into "grid", "named" becomes the list of
// the effects named (a round's: absent for null).
#pragma once

#include <string>

namespace pz::proto {
class Diagnosis;
}  // namespace pz::proto

namespace pz::io {

/// The version written; version 1 (kDiagnosisFormatVersionOldest) is read and converted.
inline constexpr int kDiagnosisFormatVersion = 2;
inline constexpr int kDiagnosisFormatVersionOldest = 1;

/// diagnosis.json's text, its format_version set to kDiagnosisFormatVersion. Throws
/// std::logic_error when "records" is empty (a writer's bug).
std::string WriteDiagnosisFile(const proto::Diagnosis& d);

/// diagnosis.json text of any version read → the message in version 2 (`out` replaced). Throws
/// InputError naming `path` and: an unknown format_version, a version-1 file of no kind or of
/// both, a "named" of the wrong shape, a bad field or value (by its path).
void ReadDiagnosisFile(const std::string& path, const std::string& text, proto::Diagnosis* out);

/// True when the message holds the fin bench's grid (`diagnose --cases`).
bool IsBenchDiagnosis(const proto::Diagnosis& d);

}  // namespace pz::io
