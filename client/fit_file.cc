#include "client/fit_file.h"

#include <algorithm>
#include <cmath>

#include "fit.pb.h"
#include "io/csv.h"

namespace pz::client {
namespace {

/// The model → its stored message (the one conversion this way).
proto::FitModel ToProto(const records::ModelSpec& s) {
  proto::FitModel f;
  f.set_family(s.family);
  f.set_substeps(s.substeps);
  f.set_pi_operators(s.pi_operators);
  auto* sc = f.mutable_scale();
  sc->set_u_min(s.scale.u_min);
  sc->set_u_max(s.scale.u_max);
  sc->set_u_half(s.scale.u_half);
  sc->set_y_half(s.scale.y_half);
  sc->set_gain(s.scale.gain);
  sc->set_polarity(s.scale.polarity);
  sc->set_f_dom_hz(s.scale.f_dom);
  sc->set_fs_hz(s.scale.fs);
  sc->set_duration_s(s.scale.duration);
  f.set_sample_period_s(s.dt);
  for (records::EffectKind e : s.effects) f.add_effects(records::EffectName(e));
  const auto model = s.Model();
  for (size_t i = 0; i < s.params.size(); ++i) {
    auto* p = f.add_params();
    p->set_name(model->params()[i].name);
    p->set_value(s.params[i]);
  }
  for (double w : s.weights) f.add_weights(w);
  f.set_polarity(s.polarity);
  f.set_offset(s.offset);
  f.set_drive_min(s.drive_min);
  f.set_drive_max(s.drive_max);
  f.set_drive_unit(s.drive_unit);
  f.set_response_unit(s.response_unit);
  f.set_initial_state(model::InitialStateName(s.initial_state));
  return f;
}

/// The stored message → the model, checked (the one conversion this way). Throws InputError
/// naming the field.
records::ModelSpec FromProto(const proto::FitModel& m) {
  records::ModelSpec s;
  s.family = m.family();
  s.substeps = m.substeps();
  s.pi_operators = m.pi_operators();
  const auto& sc = m.scale();
  s.scale = {.u_min = sc.u_min(),
             .u_max = sc.u_max(),
             .u_half = sc.u_half(),
             .y_half = sc.y_half(),
             .gain = sc.gain(),
             .polarity = sc.polarity(),
             .f_dom = sc.f_dom_hz(),
             .fs = sc.fs_hz(),
             // Files written before duration_s was stored: the default scale's 1 s (it set only
             // drift's range then).
             .duration = sc.duration_s() > 0 ? sc.duration_s() : 1.0};
  for (double v : {s.scale.u_min, s.scale.u_max, s.scale.u_half, s.scale.y_half, s.scale.f_dom,
                   s.scale.fs, s.scale.duration}) {
    if (!std::isfinite(v)) throw InputError("model.scale holds a value that is not finite");
  }
  if (!(s.scale.u_half > 0 && s.scale.y_half > 0 && s.scale.fs > 0 && s.scale.f_dom > 0)) {
    throw InputError("model.scale: u_half, y_half, f_dom_hz and fs_hz must be > 0");
  }
  s.dt = m.sample_period_s();
  records::FamilyNamed(s.family, "model.family");
  for (const auto& e : m.effects()) {
    try {
      s.effects.push_back(records::ParseEffect(e));
    } catch (const InputError& x) {
      throw InputError(std::string("model.effects: ") + x.what());
    }
  }
  // Empty (a fit.json written before the field, fitted centred): centred.
  s.initial_state = model::ParseInitialState(
      m.initial_state().empty() ? "centred" : m.initial_state(), "model.initial_state");
  const auto rm = s.Model();  // the family and its options, checked
  if (static_cast<size_t>(m.params_size()) != rm->params().size()) {
    throw InputError("model.params: " + std::to_string(m.params_size()) + " values for " +
                     rm->Describe() + ", " + std::to_string(rm->params().size()) + " expected");
  }
  for (int i = 0; i < m.params_size(); ++i) {
    const std::string& want = rm->params()[i].name;
    if (m.params(i).name() != want) {
      throw InputError("model.params[" + std::to_string(i) + "].name '" + m.params(i).name() +
                       "': expected '" + want + "' for " + rm->Describe());
    }
    s.params.push_back(m.params(i).value());
  }
  s.weights.assign(m.weights().begin(), m.weights().end());
  s.polarity = m.polarity();
  s.offset = m.offset();
  s.drive_min = m.drive_min();
  s.drive_max = m.drive_max();
  s.drive_unit = m.drive_unit();
  s.response_unit = m.response_unit();
  if (s.drive_unit.empty() || s.response_unit.empty())
    throw InputError("model.drive_unit / response_unit: empty");
  s.Validate();
  return s;
}

}  // namespace

records::ModelSpec FittedModelSpec(const io::RecordSet& set, const records::FitResult& r,
                                   int substeps, int pi_operators) {
  const records::RecordModel& m = *r.model;
  records::ModelSpec s;
  s.family = m.family().name();
  s.initial_state = m.family().initial_state();
  s.substeps = substeps;
  s.pi_operators = pi_operators;
  s.scale = m.scale();
  double offset = 0;
  int train = 0;
  for (size_t i = 0; i < set.records.size(); ++i) {
    if (set.records[i].role != model::CaseRole::kTrain) continue;
    offset += r.metrics[i].offset;
    if (train == 0) s.dt = set.records[i].dt;
    ++train;
  }
  s.effects = m.effects();
  s.params = r.params;
  s.weights = r.weights;
  s.polarity = s.scale.polarity;
  s.offset = train > 0 ? offset / train : 0.0;
  s.drive_min = s.scale.u_min;
  s.drive_max = s.scale.u_max;
  s.drive_unit = set.drive_unit;
  s.response_unit = set.response_unit;
  return s;
}

void WriteFitModel(const records::ModelSpec& m, google::protobuf::Struct* fit_json) {
  io::WriteFitModel(ToProto(m), fit_json);
}

bool LooksLikeFitJson(const std::string& path) {
  try {
    return io::LooksLikeFitJson(io::ReadTextFile(path));
  } catch (const InputError&) {
    return false;
  }
}

records::ModelSpec LoadFit(const std::string& path) {
  return LoadFitText(path, io::ReadTextFile(path));
}

records::ModelSpec LoadFitText(const std::string& path, const std::string& text) {
  proto::FitModel m;
  io::ReadFitModel(path, text, &m);
  try {
    return FromProto(m);
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
}

}  // namespace pz::client
