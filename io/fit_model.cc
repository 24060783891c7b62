#include "io/fit_model.h"

#include <google/protobuf/struct.pb.h>

#include "fit.pb.h"
#include "io/csv.h"
#include "io/proto_json.h"
#include "model/status.h"

namespace pz::io {
namespace {

using google::protobuf::Struct;
using google::protobuf::Value;

std::string Needed() {
  return "this piezoid reads fit.json format_version " + std::to_string(kFitFormatVersionOldest) +
         " or " + std::to_string(kFitFormatVersion);
}

/// The file's format_version (kFitFormatVersionOldest … kFitFormatVersion).
int CheckTopVersion(const std::string& path, const Struct& root) {
  const auto& f = root.fields();
  auto version = f.find("format_version");
  if (version == f.end()) {
    throw InputError(path +
                     ": no format_version (a fit.json of a piezoid before versioned fits, without "
                     "the model section): " +
                     Needed() + "; run piezoid fit again");
  }
  const Value& v = version->second;
  const bool number = v.kind_case() == Value::kNumberValue;
  for (int read = kFitFormatVersionOldest; number && read <= kFitFormatVersion; ++read)
    if (v.number_value() == read) return read;
  const std::string got = number ? FormatNumber(v.number_value()) : "(not a number)";
  throw InputError(path + ": format_version " + got + ": " + Needed());
}

/// Version 1's top-level copies of the model's fields (the model section is the one read).
constexpr const char* kVersion1Copies[] = {"response_unit", "drive_unit", "polarity", "params",
                                           "weights"};

}  // namespace

bool LooksLikeFitJson(const std::string& text) {
  Struct root;
  try {
    root = ParseJsonObject("", text);
  } catch (const InputError&) {
    return false;
  }
  // A fit.json has "model" (an object since format_version 1, a description string before); a
  // network's JSON (io/network_io.h) has a format_version of its own but no "model".
  return root.fields().contains("model");
}

void ReadFitFile(const std::string& path, const std::string& text, proto::FitFile* out) {
  Struct root = ParseJsonObject(path, text);
  const int version = CheckTopVersion(path, root);
  if (version == 1)
    for (const char* key : kVersion1Copies) root.mutable_fields()->erase(key);
  proto::FitFile f;
  StructToMessage(path, root, &f);
  if (f.has_model() && f.model().format_version() != static_cast<unsigned>(version)) {
    throw InputError(path + ": model.format_version " + std::to_string(f.model().format_version()) +
                     ": not the file's format_version " + std::to_string(version));
  }
  *out = std::move(f);
}

void ReadFitModel(const std::string& path, const std::string& text, proto::FitModel* out) {
  proto::FitFile f;
  ReadFitFile(path, text, &f);
  if (!f.has_model()) {
    throw InputError(path +
                     ": no \"model\" object (the section piezoid export and compensate read)");
  }
  *out = std::move(*f.mutable_model());
}

std::string WriteFitFile(const proto::FitFile& f) {
  proto::FitFile versioned = f;
  versioned.set_format_version(kFitFormatVersion);
  versioned.mutable_model()->set_format_version(kFitFormatVersion);
  return PrintJson(versioned, "fit.json");
}

std::string WriteSynthTruth(const proto::SynthTruth& t) { return PrintJson(t, "truth.json"); }

void ReadSynthTruth(const std::string& path, const std::string& text, proto::SynthTruth* out) {
  ReadJsonMessage(path, text, out);
}

}  // namespace pz::io
