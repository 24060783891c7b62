// fit.json's model section as a records::ModelSpec: written by `piezoid fit`, read by
// `piezoid export FIT.json`, `piezoid compensate` and python's piezoid.Model.load. The JSON is
// io/fit_model.h's (protobuf JSON of proto/fit.proto); the one conversion between the stored
// message and the model, both ways, is here. A fit.json of another format_version is refused with
// the version needed; a bad field is named.
#pragma once

#include <google/protobuf/struct.pb.h>

#include <string>

#include "io/fit_model.h"
#include "io/records.h"
#include "records/fit.h"
#include "records/stepper.h"

namespace pz::client {

using io::kFitFormatVersion;

/// The model of a fit (the offset: the mean of the training records' offsets; the drive limits:
/// the training records' drive range; the sample step: the first training record's).
records::ModelSpec FittedModelSpec(const io::RecordSet& set, const records::FitResult& r,
                                   int substeps, int pi_operators);

/// Sets fit.json's format_version and model section (`m`) on the document `fit_json`.
void WriteFitModel(const records::ModelSpec& m, google::protobuf::Struct* fit_json);

/// The spec of a fit.json's model section. Throws InputError naming the file and the field, the
/// version needed, or a family/effect/parameter that does not fit.
records::ModelSpec LoadFit(const std::string& path);
/// LoadFit of a fit.json's text (`path` names it in the errors): the fuzzer's entry point.
records::ModelSpec LoadFitText(const std::string& path, const std::string& text);

/// True when the file is a fit.json (a JSON object with "model"), not a network file.
bool LooksLikeFitJson(const std::string& path);

}  // namespace pz::client
