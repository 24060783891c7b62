#include "io/diagnosis_json.h"

#include <google/protobuf/struct.pb.h>

#include <stdexcept>

#include "diagnosis.pb.h"
#include "io/csv.h"
#include "io/proto_json.h"
#include "model/status.h"

namespace pz::io {
namespace {

using google::protobuf::Struct;
using google::protobuf::Value;

/// The bench's top-level parts of a version-1 file: version 2's BenchGrid.
constexpr const char* kGridKeys[] = {
    "thresholds", "noise",       "base",       "base_residuals", "trends",
    "rounds",     "absorbed_by", "absorbed",   "final",          "final_residuals",
    "gap",        "wall_time_s", "evaluations"};

/// Version 1's "named" at `at` as version 2's: a list of strings stays, a string is a list of
/// one, null an empty list (`list` false: a round's, a string or null, null removed).
void ConvertNamed(const std::string& path, const std::string& at, Struct* s, bool list) {
  auto it = s->mutable_fields()->find("named");
  if (it == s->mutable_fields()->end()) return;
  Value& v = it->second;
  const bool is_list = v.kind_case() == Value::kListValue;
  if (list && is_list) {
    for (const Value& x : v.list_value().values())
      if (x.kind_case() != Value::kStringValue)
        throw InputError(path + ": " + at + ": not a list of the effects named (strings)");
    return;
  }
  if (list) throw InputError(path + ": " + at + ": not a list of the effects named");
  if (v.kind_case() == Value::kNullValue) {
    s->mutable_fields()->erase(it);
  } else if (v.kind_case() != Value::kStringValue) {
    throw InputError(path + ": " + at + ": not the effect named (a string) or null");
  }
}

/// A version-1 file (its kind "records" or "bench") in version 2's shape.
void ConvertVersion1(const std::string& path, Struct* s) {
  auto& f = *s->mutable_fields();
  const bool records = f.contains("records"), bench = f.contains("bench");
  if (records == bench)
    throw InputError(path + (records ? ": both \"records\" and \"bench\" are given"
                                     : ": no format_version, and neither \"records\" (a records "
                                       "diagnosis) nor \"bench\" (the fin bench's) is given: not "
                                       "a diagnosis.json"));
  const std::string key = records ? "records" : "bench";
  if (f.at(key).kind_case() != Value::kStringValue)
    throw InputError(path + ": " + key + ": not a string (the " +
                     (records ? "record set" : "bench's folder") + ")");
  if (auto named = f.find("named"); named != f.end()) {
    Value& v = named->second;
    if (records && v.kind_case() == Value::kNullValue) {
      v.mutable_list_value();
    } else if (records && v.kind_case() == Value::kStringValue) {
      const std::string one = v.string_value();
      v.mutable_list_value()->add_values()->set_string_value(one);
    } else if (records) {
      throw InputError(path + ": named: not the effect named (a string) or null");
    }
    ConvertNamed(path, "named", s, true);
  }
  if (bench) {
    Struct& grid = *f["grid"].mutable_struct_value();
    for (const char* k : kGridKeys) {
      if (auto it = f.find(k); it != f.end()) {
        (*grid.mutable_fields())[k] = it->second;
        f.erase(it);
      }
    }
    f["records"] = f.at("bench");
    f.erase("bench");
    if (auto it = grid.mutable_fields()->find("rounds");
        it != grid.mutable_fields()->end() && it->second.has_list_value()) {
      auto& rounds = *it->second.mutable_list_value()->mutable_values();
      for (int i = 0; i < rounds.size(); ++i)
        if (rounds[i].has_struct_value())
          ConvertNamed(path, "rounds[" + std::to_string(i) + "].named",
                       rounds[i].mutable_struct_value(), false);
    }
  }
  f["format_version"].set_number_value(kDiagnosisFormatVersion);
}

}  // namespace

bool IsBenchDiagnosis(const proto::Diagnosis& d) { return d.has_grid(); }

std::string WriteDiagnosisFile(const proto::Diagnosis& d) {
  if (d.records().empty()) throw std::logic_error("diagnosis.json: \"records\" is not set");
  proto::Diagnosis m = d;
  m.set_format_version(kDiagnosisFormatVersion);
  return PrintJson(MessageToStruct(m), "diagnosis.json");
}

void ReadDiagnosisFile(const std::string& path, const std::string& text, proto::Diagnosis* out) {
  Struct s = ParseJsonObject(path, text);
  const auto version = s.fields().find("format_version");
  if (version == s.fields().end()) {
    ConvertVersion1(path, &s);
  } else if (version->second.kind_case() != Value::kNumberValue ||
             version->second.number_value() != kDiagnosisFormatVersion) {
    throw InputError(path + ": format_version " +
                     (version->second.kind_case() == Value::kNumberValue
                          ? FormatNumber(version->second.number_value())
                          : std::string("(not a number)")) +
                     ": this piezoid reads diagnosis.json format_version " +
                     std::to_string(kDiagnosisFormatVersion) + " and " +
                     std::to_string(kDiagnosisFormatVersionOldest) +
                     " (a file without format_version)");
  }
  StructToMessage(path, s, out);
}

}  // namespace pz::io
