// fit.json's codec (proto/fit.proto, issues 23 and 38): the whole file <-> proto::FitFile, and
// truth.json of `piezoid synth-stack` <-> proto::SynthTruth, through protobuf's JSON util
// (io/proto_json.h: keys sorted, a non-finite number as null), here only. fit.json is written by
// `piezoid fit`, read by `piezoid export FIT.json`, `piezoid compensate` and python's
// piezoid.Model; the one conversion of a fit's result to the message, and of its model section to
// records::ModelSpec, is reports/fit_file.h's.
//
// Versioning: fit.json's top-level "format_version" and the model's are kFitFormatVersion when
// written. Version 1 (issue 38) is still read: its top-level copies of the model's units,
// polarity, parameters and weights are dropped (version 2 writes the model once, in "model"). A
// file of another version (or one of a piezoid before versions, without it) is refused with the
// versions this reader reads; an unknown or mistyped field, in the model or in the report, is
// named.
#pragma once

#include <string>

namespace pz::proto {
class FitFile;
class FitModel;
class SynthTruth;
}  // namespace pz::proto

namespace pz::io {

inline constexpr int kFitFormatVersion = 2;
/// The oldest version read.
inline constexpr int kFitFormatVersionOldest = 1;

/// fit.json text → the whole file (`out` replaced). Throws InputError naming `path` and: no or
/// another format_version (with the ones read), a model's format_version other than the file's, a
/// bad field or value (by its path).
void ReadFitFile(const std::string& path, const std::string& text, proto::FitFile* out);

/// ReadFitFile's model section (`out` replaced); also throws when the file has no "model" object.
void ReadFitModel(const std::string& path, const std::string& text, proto::FitModel* out);

/// The file's JSON text (its format_version and its model's set here to kFitFormatVersion).
std::string WriteFitFile(const proto::FitFile& f);

/// True when the text is a JSON object with "model" (a fit.json; a network's JSON has none).
bool LooksLikeFitJson(const std::string& text);

/// truth.json's text.
std::string WriteSynthTruth(const proto::SynthTruth& t);
/// truth.json text → the truth (`out` replaced). Throws InputError naming `path` and the field.
void ReadSynthTruth(const std::string& path, const std::string& text, proto::SynthTruth* out);

}  // namespace pz::io
