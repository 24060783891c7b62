// fit.json's model section (io/fit_model.h, proto/fit.proto) as a records::ModelSpec: written by
// `piezoid fit`, read by `piezoid export FIT.json`, `piezoid compensate` and python's
// piezoid.Model.load. A fit.json of another format_version is refused with the version needed; a
// bad field is named.
#pragma once

#include <google/protobuf/struct.pb.h>

#include <string>

#include "io/fit_model.h"
#include "io/records.h"
#include "records/fit.h"
#include "records/stepper.h"

namespace pz::client {

using io::kFitFormatVersion;

/// The model section of a fit (the offset: the mean of the training records' offsets; the drive
/// limits: the training records' drive range; the sample step: the first training record's) as a
/// JSON value for fit.json.
google::protobuf::Value FitModelJson(const io::RecordSet& set, const records::FitResult& r, int substeps,
                                     int pi_operators);

/// The spec of a fit.json's model section. Throws InputError naming the file and the field, the
/// version needed, or a family/effect/parameter that does not fit.
records::ModelSpec LoadFit(const std::string& path);
/// LoadFit of a fit.json's text (`path` names it in the errors): the fuzzer's entry point.
records::ModelSpec LoadFitText(const std::string& path, const std::string& text);

/// True when the file is a fit.json (a JSON object with format_version or model), not a network file.
bool LooksLikeFitJson(const std::string& path);

}  // namespace pz::client
