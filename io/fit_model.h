// fit.json's codec (proto/fit.proto, issue 23): the JSON of its model section <-> the stored shape
// proto::FitModel, through protobuf's JSON util, here only. Written by `piezoid fit`, read by
// `piezoid export FIT.json`, `piezoid compensate` and python's piezoid.Model; the one conversion of
// the message to the model (records::ModelSpec) is client/fit_file.h's.
//
// Versioning: fit.json's top-level "format_version" and the model's are kFitFormatVersion; a file
// of another version (or one of a piezoid before versions, without it) is refused with the version
// this reader needs; an unknown or mistyped field is named.
#pragma once

#include <string>

namespace google::protobuf {
class Struct;
}

namespace pz::proto {
class FitModel;
}

namespace pz::io {

inline constexpr int kFitFormatVersion = 1;

/// fit.json text → its model section (`out` replaced). Throws InputError naming `path` and: no or
/// another format_version (with the one needed), no "model" object, a bad field or value.
void ReadFitModel(const std::string& path, const std::string& text, proto::FitModel* out);

/// Sets fit.json's "format_version" and its "model" section (`m`, its format_version set here) on
/// the document `fit_json`; the rest of the document is the writer's report.
void WriteFitModel(const proto::FitModel& m, google::protobuf::Struct* fit_json);

/// True when the text is a JSON object with "model" (a fit.json; a network's JSON has none).
bool LooksLikeFitJson(const std::string& text);

}  // namespace pz::io
