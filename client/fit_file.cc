#include "client/fit_file.h"

#include <google/protobuf/util/json_util.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "io/csv.h"

namespace pz::client {

google::protobuf::Value FitModelJson(const io::RecordSet& set, const records::FitResult& r, int substeps,
                                     int pi_operators) {
  const records::RecordModel& m = *r.model;
  const records::DataScale& s = m.scale();
  io::FitModelFile f;
  f.family = m.family().name();
  f.initial_state = model::InitialStateName(m.family().initial_state());
  f.substeps = substeps;
  f.pi_operators = pi_operators;
  f.scale = s;
  double offset = 0;
  int train = 0;
  for (size_t i = 0; i < set.records.size(); ++i) {
    if (set.records[i].role != model::CaseRole::kTrain) continue;
    offset += r.metrics[i].offset;
    if (train == 0) f.sample_period_s = set.records[i].dt;
    ++train;
  }
  for (records::EffectKind e : m.effects()) f.effects.push_back(records::EffectName(e));
  for (size_t i = 0; i < r.params.size(); ++i) f.params.emplace_back(m.params()[i].name, r.params[i]);
  f.weights = r.weights;
  f.polarity = s.polarity;
  f.offset = train > 0 ? offset / train : 0.0;
  f.drive_min = s.u_min;
  f.drive_max = s.u_max;
  f.drive_unit = set.drive_unit;
  f.response_unit = set.response_unit;
  google::protobuf::Value v;
  if (!google::protobuf::util::JsonStringToMessage(io::FitModelJson(f), &v).ok()) {
    throw std::runtime_error("fit.json: the model section");
  }
  return v;
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
  const io::FitModelFile m = io::ParseFitJson(path, text);
  records::ModelSpec s;
  s.family = m.family;
  s.substeps = m.substeps;
  s.pi_operators = m.pi_operators;
  s.scale = m.scale;
  // Files written before duration_s was stored: the default scale's 1 s (it set only drift's range then).
  if (!(s.scale.duration > 0)) s.scale.duration = 1.0;
  try {
    for (double v : {s.scale.u_min, s.scale.u_max, s.scale.u_half, s.scale.y_half, s.scale.f_dom, s.scale.fs,
                     s.scale.duration}) {
      if (!std::isfinite(v)) throw InputError("model.scale holds a value that is not finite");
    }
    if (!(s.scale.u_half > 0 && s.scale.y_half > 0 && s.scale.fs > 0 && s.scale.f_dom > 0)) {
      throw InputError("model.scale: u_half, y_half, f_dom_hz and fs_hz must be > 0");
    }
    s.dt = m.sample_period_s;
    records::FamilyNamed(s.family, "model.family");
    for (const auto& e : m.effects) {
      try {
        s.effects.push_back(records::ParseEffect(e));
      } catch (const InputError& x) {
        throw InputError(std::string("model.effects: ") + x.what());
      }
    }
    s.initial_state = model::ParseInitialState(m.initial_state, "model.initial_state");
    const auto rm = s.Model();  // the family and its options, checked
    if (m.params.size() != rm->params().size()) {
      throw InputError("model.params: " + std::to_string(m.params.size()) + " values for " + rm->Describe() + ", " +
                       std::to_string(rm->params().size()) + " expected");
    }
    for (size_t i = 0; i < m.params.size(); ++i) {
      const std::string& want = rm->params()[i].name;
      if (m.params[i].first != want) {
        throw InputError("model.params[" + std::to_string(i) + "].name '" + m.params[i].first + "': expected '" + want +
                         "' for " + rm->Describe());
      }
      s.params.push_back(m.params[i].second);
    }
    s.weights = m.weights;
    s.polarity = m.polarity;
    s.offset = m.offset;
    s.drive_min = m.drive_min;
    s.drive_max = m.drive_max;
    s.drive_unit = m.drive_unit;
    s.response_unit = m.response_unit;
    if (s.drive_unit.empty() || s.response_unit.empty()) throw InputError("model.drive_unit / response_unit: empty");
    s.Validate();
  } catch (const InputError& e) {
    throw InputError(path + ": " + e.what());
  }
  return s;
}

}  // namespace pz::client
