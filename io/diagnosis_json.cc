#include "io/diagnosis_json.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/struct.pb.h>

#include <stdexcept>
#include <vector>

#include "diagnosis.pb.h"
#include "io/proto_json.h"
#include "model/status.h"

namespace pz::io {
namespace {

using google::protobuf::FieldDescriptor;
using google::protobuf::Struct;
using google::protobuf::Value;
using proto::DiagnosisOnly;

enum class Way { kWrite, kRead };

const char* KindName(DiagnosisOnly k) {
  return k == proto::DIAGNOSIS_ONLY_RECORDS ? "a records diagnosis" : "the fin bench's diagnosis";
}

/// A value the message's default prints as (a field of the other kind left unset).
bool IsDefault(const Value& v) {
  switch (v.kind_case()) {
    case Value::kNumberValue:
      return v.number_value() == 0;
    case Value::kStringValue:
      return v.string_value().empty();
    case Value::kBoolValue:
      return !v.bool_value();
    case Value::kListValue:
      return v.list_value().values().empty();
    default:
      return false;
  }
}

/// Written: drops the fields of the other kind (all at their defaults, or a writer's bug); read:
/// refuses them by their path (`where`: the file).
void Filter(Struct* s, DiagnosisOnly kind, const std::string& where, Way way) {
  JsonFieldWalk walk;
  walk.keep = [&](const FieldDescriptor& f, const std::string& at, const Value& v) {
    const DiagnosisOnly only = f.options().GetExtension(proto::diagnosis_only);
    if (only == proto::DIAGNOSIS_ONLY_UNSPECIFIED || only == kind) return true;
    if (way == Way::kRead)
      throw InputError(where + ": " + at + ": a field of " + KindName(only) + " in " +
                       KindName(kind));
    if (!IsDefault(v))
      throw std::logic_error("diagnosis.json: " + at + " set in " + KindName(kind));
    return false;
  };
  WalkJsonObject(*proto::Diagnosis::descriptor(), s, walk);
}

/// "" when `v` is of the shape "named" takes there (`list`: a list of strings; else a string or
/// null); else what is wrong.
std::string NamedShape(const Value& v, bool list) {
  if (list) {
    if (v.kind_case() != Value::kListValue) return "a list of the effects named";
    for (const Value& x : v.list_value().values())
      if (x.kind_case() != Value::kStringValue) return "a list of the effects named (strings)";
    return "";
  }
  if (v.kind_case() == Value::kStringValue || v.kind_case() == Value::kNullValue) return "";
  return "the effect named (a string) or null";
}

/// The first "named" of a wrong shape: its path and the shape it takes ("" when none).
std::pair<std::string, std::string> BadNamed(const proto::Diagnosis& d, DiagnosisOnly kind) {
  if (d.has_named()) {
    const std::string want = NamedShape(d.named(), kind == proto::DIAGNOSIS_ONLY_BENCH);
    if (!want.empty()) return {"named", want};
  }
  for (int i = 0; i < d.rounds_size(); ++i) {
    if (!d.rounds(i).has_named()) continue;
    const std::string want = NamedShape(d.rounds(i).named(), false);
    if (!want.empty()) return {"rounds[" + std::to_string(i) + "].named", want};
  }
  return {};
}

DiagnosisOnly KindOfMessage(const proto::Diagnosis& d) {
  if (d.has_records() == d.has_bench())
    throw std::logic_error(d.has_records()
                               ? "diagnosis.json: both \"records\" and \"bench\" are set"
                               : "diagnosis.json: neither \"records\" nor \"bench\" is set");
  return d.has_records() ? proto::DIAGNOSIS_ONLY_RECORDS : proto::DIAGNOSIS_ONLY_BENCH;
}

}  // namespace

bool IsRecordsDiagnosis(const proto::Diagnosis& d) { return d.has_records(); }

std::string WriteDiagnosisFile(const proto::Diagnosis& d) {
  const DiagnosisOnly kind = KindOfMessage(d);
  if (const auto [at, want] = BadNamed(d, kind); !at.empty())
    throw std::logic_error("diagnosis.json: " + at + " is not " + want);
  Struct s = MessageToStruct(d);
  Filter(&s, kind, "diagnosis.json", Way::kWrite);
  return PrintJson(s, "diagnosis.json");
}

void ReadDiagnosisFile(const std::string& path, const std::string& text, proto::Diagnosis* out) {
  Struct s = ParseJsonObject(path, text);
  const bool records = s.fields().contains("records"), bench = s.fields().contains("bench");
  if (records == bench)
    throw InputError(path + (records ? ": both \"records\" and \"bench\" are given"
                                     : ": neither \"records\" (a records diagnosis) nor \"bench\" "
                                       "(the fin bench's) is given: not a diagnosis.json"));
  const DiagnosisOnly kind = records ? proto::DIAGNOSIS_ONLY_RECORDS : proto::DIAGNOSIS_ONLY_BENCH;
  const std::string key = records ? "records" : "bench";
  if (s.fields().at(key).kind_case() != Value::kStringValue)
    throw InputError(path + ": " + key + ": not a string (the " +
                     (records ? "record set" : "bench's folder") + ")");
  Filter(&s, kind, path, Way::kRead);
  StructToMessage(path, s, out);
  if (const auto [at, want] = BadNamed(*out, kind); !at.empty())
    throw InputError(path + ": " + at + ": not " + want);
}

}  // namespace pz::io
