#include "io/fit_model.h"

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>

#include <stdexcept>

#include "fit.pb.h"
#include "io/csv.h"
#include "model/status.h"

namespace pz::io {
namespace {

using google::protobuf::Struct;
using google::protobuf::Value;
namespace util = google::protobuf::util;

Struct ParseObject(const std::string& path, const std::string& text) {
  Struct root;
  const auto st = util::JsonStringToMessage(text, &root);
  if (!st.ok()) throw InputError(path + ": not a JSON object: " + std::string(st.message()));
  return root;
}

std::string Needed() {
  return "this piezoid reads fit.json format_version " + std::to_string(kFitFormatVersion);
}

void CheckTopVersion(const std::string& path, const Struct& root) {
  const auto& f = root.fields();
  auto version = f.find("format_version");
  if (version == f.end()) {
    throw InputError(path +
                     ": no format_version (a fit.json of a piezoid before versioned fits, without "
                     "the model section): " +
                     Needed() + "; run piezoid fit again");
  }
  const Value& v = version->second;
  if (v.kind_case() != Value::kNumberValue || v.number_value() != kFitFormatVersion) {
    const std::string got =
        v.kind_case() == Value::kNumberValue ? FormatNumber(v.number_value()) : "(not a number)";
    throw InputError(path + ": format_version " + got + ": " + Needed());
  }
}

}  // namespace

bool LooksLikeFitJson(const std::string& text) {
  Struct root;
  if (!util::JsonStringToMessage(text, &root).ok()) return false;
  // A fit.json has "model" (an object since format_version 1, a description string before); a
  // network's JSON (io/network_io.h) has a format_version of its own but no "model".
  return root.fields().contains("model");
}

void ReadFitModel(const std::string& path, const std::string& text, proto::FitModel* out) {
  const Struct root = ParseObject(path, text);
  CheckTopVersion(path, root);
  auto model = root.fields().find("model");
  if (model == root.fields().end() || model->second.kind_case() != Value::kStructValue) {
    throw InputError(path +
                     ": no \"model\" object (the section piezoid export and compensate read)");
  }
  std::string json;
  (void)util::MessageToJsonString(model->second.struct_value(), &json);
  proto::FitModel m;
  util::JsonParseOptions o;
  o.ignore_unknown_fields = false;
  if (auto st = util::JsonStringToMessage(json, &m, o); !st.ok()) {
    throw InputError(path + ": model: " + std::string(st.message()));
  }
  if (m.format_version() != static_cast<unsigned>(kFitFormatVersion)) {
    throw InputError(path + ": model.format_version " + std::to_string(m.format_version()) + ": " +
                     Needed());
  }
  *out = std::move(m);
}

void WriteFitModel(const proto::FitModel& m, Struct* fit_json) {
  proto::FitModel versioned = m;
  versioned.set_format_version(kFitFormatVersion);
  util::JsonPrintOptions po;
  po.always_print_primitive_fields = true;
  po.preserve_proto_field_names = true;
  std::string json;
  Value model;
  if (!util::MessageToJsonString(versioned, &json, po).ok() ||
      !util::JsonStringToMessage(json, &model).ok()) {
    throw std::runtime_error("fit.json: the model section");
  }
  auto& f = *fit_json->mutable_fields();
  f["format_version"].set_number_value(kFitFormatVersion);
  f["model"] = std::move(model);
}

}  // namespace pz::io
