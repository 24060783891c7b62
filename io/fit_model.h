// fit.json's model section (proto/fit.proto, issue 23) as plain values: written by `piezoid fit`,
// read by `piezoid export FIT.json`, `piezoid compensate` and python's piezoid.Model. The protobuf
// JSON is parsed and printed here (io owns the generated messages); client/fit_file.h turns the
// values into a records::ModelSpec.
//
// Versioning: fit.json's top-level "format_version" and the model's are kFitFormatVersion; a file
// of another version (or one of a piezoid before versions, without it) is refused with the version
// this reader needs; an unknown or mistyped field is named.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "model/effect_library.h"

namespace pz::io {

inline constexpr int kFitFormatVersion = 1;

struct FitModelFile {
  std::string family;
  int substeps = 2, pi_operators = 12;
  model::DataScale scale;  ///< the data scale the family and effects were made for (duration 0: not stored)
  double sample_period_s = 0;
  std::vector<std::string> effects;
  std::vector<std::pair<std::string, double>> params;
  std::vector<double> weights;
  int polarity = 1;
  double offset = 0;
  double drive_min = 0, drive_max = 0;
  std::string drive_unit, response_unit;
  std::string initial_state = "centred";  ///< FamilyOptions::initial_state by name ("" read: centred)
};

/// The model section as a JSON object (protobuf JSON, field names as in fit.proto).
std::string FitModelJson(const FitModelFile& m);

/// fit.json text → its model section. Throws InputError naming `path` and: no or another
/// format_version (with the one needed), no "model" object, a bad field.
FitModelFile ParseFitJson(const std::string& path, const std::string& text);

/// True when the text is a JSON object with "model" (a fit.json; a network's JSON has none).
bool LooksLikeFitJson(const std::string& text);

}  // namespace pz::io
