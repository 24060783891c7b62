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

Struct ParseObject(const std::string& path, const std::string& text) {
  Struct root;
  const auto st = google::protobuf::util::JsonStringToMessage(text, &root);
  if (!st.ok()) throw InputError(path + ": not a JSON object: " + std::string(st.message()));
  return root;
}

}  // namespace

std::string FitModelJson(const FitModelFile& m) {
  proto::FitModel f;
  f.set_format_version(kFitFormatVersion);
  f.set_family(m.family);
  f.set_substeps(m.substeps);
  f.set_pi_operators(m.pi_operators);
  auto* sc = f.mutable_scale();
  sc->set_u_min(m.scale.u_min);
  sc->set_u_max(m.scale.u_max);
  sc->set_u_half(m.scale.u_half);
  sc->set_y_half(m.scale.y_half);
  sc->set_gain(m.scale.gain);
  sc->set_polarity(m.scale.polarity);
  sc->set_f_dom_hz(m.scale.f_dom);
  sc->set_fs_hz(m.scale.fs);
  sc->set_duration_s(m.scale.duration);
  f.set_sample_period_s(m.sample_period_s);
  for (const auto& e : m.effects) f.add_effects(e);
  for (const auto& [name, value] : m.params) {
    auto* p = f.add_params();
    p->set_name(name);
    p->set_value(value);
  }
  for (double w : m.weights) f.add_weights(w);
  f.set_polarity(m.polarity);
  f.set_offset(m.offset);
  f.set_drive_min(m.drive_min);
  f.set_drive_max(m.drive_max);
  f.set_drive_unit(m.drive_unit);
  f.set_response_unit(m.response_unit);
  f.set_initial_state(m.initial_state);
  std::string json;
  google::protobuf::util::JsonPrintOptions po;
  po.always_print_primitive_fields = true;
  po.preserve_proto_field_names = true;
  if (!google::protobuf::util::MessageToJsonString(f, &json, po).ok()) throw std::runtime_error("fit.json: model");
  return json;
}

bool LooksLikeFitJson(const std::string& text) {
  Struct root;
  if (!google::protobuf::util::JsonStringToMessage(text, &root).ok()) return false;
  // A fit.json has "model" (an object since format_version 1, a description string before); a
  // network's JSON (io/network_io.h) has a format_version of its own but no "model".
  return root.fields().contains("model");
}

FitModelFile ParseFitJson(const std::string& path, const std::string& text) {
  const Struct root = ParseObject(path, text);
  const auto& f = root.fields();
  const std::string need = "this piezoid reads fit.json format_version " + std::to_string(kFitFormatVersion);
  auto version = f.find("format_version");
  if (version == f.end()) {
    throw InputError(path + ": no format_version (a fit.json of a piezoid before versioned fits, without the model "
                            "section): " + need + "; run piezoid fit again");
  }
  if (version->second.kind_case() != Value::kNumberValue || version->second.number_value() != kFitFormatVersion) {
    const std::string got = version->second.kind_case() == Value::kNumberValue
                                ? FormatNumber(version->second.number_value())
                                : "(not a number)";
    throw InputError(path + ": format_version " + got + ": " + need);
  }
  auto model = f.find("model");
  if (model == f.end() || model->second.kind_case() != Value::kStructValue) {
    throw InputError(path + ": no \"model\" object (the section piezoid export and compensate read)");
  }
  std::string json;
  (void)google::protobuf::util::MessageToJsonString(model->second.struct_value(), &json);
  proto::FitModel m;
  google::protobuf::util::JsonParseOptions o;
  o.ignore_unknown_fields = false;
  if (auto st = google::protobuf::util::JsonStringToMessage(json, &m, o); !st.ok()) {
    throw InputError(path + ": model: " + std::string(st.message()));
  }
  if (m.format_version() != static_cast<unsigned>(kFitFormatVersion)) {
    throw InputError(path + ": model.format_version " + std::to_string(m.format_version()) + ": " + need);
  }
  FitModelFile out;
  out.family = m.family();
  out.substeps = m.substeps();
  out.pi_operators = m.pi_operators();
  const auto& sc = m.scale();
  out.scale = {.u_min = sc.u_min(),
               .u_max = sc.u_max(),
               .u_half = sc.u_half(),
               .y_half = sc.y_half(),
               .gain = sc.gain(),
               .polarity = sc.polarity(),
               .f_dom = sc.f_dom_hz(),
               .fs = sc.fs_hz(),
               .duration = sc.duration_s()};
  out.sample_period_s = m.sample_period_s();
  out.effects.assign(m.effects().begin(), m.effects().end());
  for (const auto& p : m.params()) out.params.emplace_back(p.name(), p.value());
  out.weights.assign(m.weights().begin(), m.weights().end());
  out.polarity = m.polarity();
  out.offset = m.offset();
  out.drive_min = m.drive_min();
  out.drive_max = m.drive_max();
  out.drive_unit = m.drive_unit();
  out.response_unit = m.response_unit();
  out.initial_state = m.initial_state().empty() ? "centred" : m.initial_state();  // before the field: centred
  return out;
}

}  // namespace pz::io
