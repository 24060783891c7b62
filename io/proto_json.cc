#include "io/proto_json.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/type_resolver.h>
#include <google/protobuf/util/type_resolver_util.h>

#include <memory>
#include <stdexcept>
#include <vector>

#include "model/status.h"

namespace pz::io {
namespace {

using google::protobuf::Descriptor;
using google::protobuf::FieldDescriptor;
using google::protobuf::Struct;
using google::protobuf::Value;
namespace util = google::protobuf::util;

bool IsReal(const FieldDescriptor& f) {
  return f.cpp_type() == FieldDescriptor::CPPTYPE_DOUBLE ||
         f.cpp_type() == FieldDescriptor::CPPTYPE_FLOAT;
}

bool Is64(const FieldDescriptor& f) {
  return f.cpp_type() == FieldDescriptor::CPPTYPE_INT64 ||
         f.cpp_type() == FieldDescriptor::CPPTYPE_UINT64;
}

/// Written, protobuf's "NaN" / "Infinity" of a double becomes null and the string of a 64-bit
/// integer its number.
const JsonFieldWalk kWritten{{}, [](const FieldDescriptor& f, Value* v) {
                               if (v->kind_case() != Value::kStringValue) return;
                               if (IsReal(f))
                                 v->set_null_value(google::protobuf::NULL_VALUE);
                               else if (Is64(f))
                                 v->set_number_value(std::stod(v->string_value()));
                             }};

/// Read, null in a double field becomes "NaN" (protobuf would take null as 0, or drop it from a
/// list).
const JsonFieldWalk kRead{{}, [](const FieldDescriptor& f, Value* v) {
                            if (IsReal(f) && v->kind_case() == Value::kNullValue)
                              v->set_string_value("NaN");
                          }};

void WalkElement(const FieldDescriptor& f, Value* v, const JsonFieldWalk& walk,
                 const std::string& path) {
  if (f.cpp_type() != FieldDescriptor::CPPTYPE_MESSAGE) {
    if (walk.scalar) walk.scalar(f, v);
    return;
  }
  const Descriptor& d = *f.message_type();
  if (d.well_known_type() == Descriptor::WELLKNOWNTYPE_UNSPECIFIED &&
      v->kind_case() == Value::kStructValue)
    WalkJsonObject(d, v->mutable_struct_value(), walk, path);
}

/// protobuf 3.21's "(records[1].rmse): invalid value …" / "(model) weigths: Cannot find field." as
/// "records[1].rmse: invalid value …" / "model.weigths: Cannot find field."; another form as is.
std::string FieldError(const std::string& m) {
  if (m.empty() || m[0] != '(') return m;
  const size_t close = m.find(')');
  if (close == std::string::npos) return m;
  const std::string path = m.substr(1, close - 1), rest = m.substr(close + 1);
  if (rest.starts_with(": ")) return path + rest;
  if (rest.starts_with(" ")) return path + (path.empty() ? "" : ".") + rest.substr(1);
  return m;
}

}  // namespace

void WalkJsonObject(const Descriptor& d, Struct* s, const JsonFieldWalk& walk,
                    const std::string& path) {
  std::vector<std::string> erased;
  for (auto& [key, v] : *s->mutable_fields()) {
    const FieldDescriptor* f = d.FindFieldByName(key);
    if (f == nullptr) f = d.FindFieldByCamelcaseName(key);
    if (f == nullptr) continue;  // the parser names it
    const std::string at = path.empty() ? key : path + "." + key;
    if (walk.keep && !walk.keep(*f, at, v)) {
      erased.push_back(key);
      continue;
    }
    if (f->is_map()) {
      if (v.kind_case() != Value::kStructValue) continue;
      const FieldDescriptor& value = *f->message_type()->map_value();
      for (auto& [k, x] : *v.mutable_struct_value()->mutable_fields())
        WalkElement(value, &x, walk, at + "." + k);
    } else if (f->is_repeated()) {
      if (v.kind_case() != Value::kListValue) continue;
      auto& items = *v.mutable_list_value()->mutable_values();
      const bool objects = f->cpp_type() == FieldDescriptor::CPPTYPE_MESSAGE;
      for (int i = 0; i < items.size(); ++i)  // a path only where it can be used
        WalkElement(*f, &items[i], walk, objects ? at + "[" + std::to_string(i) + "]" : "");
    } else {
      WalkElement(*f, &v, walk, at);
    }
  }
  for (const auto& key : erased) s->mutable_fields()->erase(key);
}

Struct MessageToStruct(const google::protobuf::Message& m) {
  util::JsonPrintOptions o;
  o.always_print_primitive_fields = true;
  o.preserve_proto_field_names = true;
  std::string json;
  Struct s;
  if (!util::MessageToJsonString(m, &json, o).ok() || !util::JsonStringToMessage(json, &s).ok())
    throw std::runtime_error("cannot write " + m.GetDescriptor()->full_name() + " as JSON");
  WalkJsonObject(*m.GetDescriptor(), &s, kWritten);
  return s;
}

std::string PrintJson(const Struct& root, const std::string& what) {
  // A Struct's fields are a map, which protobuf serialises in hash order (it varies from run to
  // run): serialised deterministically (keys sorted) and converted from that, the same document
  // prints the same bytes every time.
  std::string binary;
  {
    google::protobuf::io::StringOutputStream sink(&binary);
    google::protobuf::io::CodedOutputStream coded(&sink);
    coded.SetSerializationDeterministic(true);
    if (!root.SerializeToCodedStream(&coded)) throw std::runtime_error("cannot format " + what);
  }
  static const std::unique_ptr<util::TypeResolver> resolver(util::NewTypeResolverForDescriptorPool(
      "type.googleapis.com", google::protobuf::DescriptorPool::generated_pool()));
  std::string out;
  util::JsonPrintOptions o;
  o.add_whitespace = true;
  o.preserve_proto_field_names = true;
  if (!util::BinaryToJsonString(resolver.get(),
                                "type.googleapis.com/" + Struct::descriptor()->full_name(), binary,
                                &out, o)
           .ok())
    throw std::runtime_error("cannot format " + what);
  if (out.empty() || out.back() != '\n') out += '\n';
  return out;
}

std::string PrintJson(const google::protobuf::Message& m, const std::string& what) {
  return PrintJson(MessageToStruct(m), what);
}

Struct ParseJsonObject(const std::string& where, const std::string& text) {
  Struct root;
  const auto st = util::JsonStringToMessage(text, &root);
  if (!st.ok()) throw InputError(where + ": not a JSON object: " + std::string(st.message()));
  return root;
}

void StructToMessage(const std::string& where, const Struct& root, google::protobuf::Message* out) {
  Struct fixed = root;
  WalkJsonObject(*out->GetDescriptor(), &fixed, kRead);
  std::string json;
  if (!util::MessageToJsonString(fixed, &json).ok())
    throw InputError(where + ": cannot read the JSON object");
  util::JsonParseOptions o;
  o.ignore_unknown_fields = false;
  out->Clear();
  if (const auto st = util::JsonStringToMessage(json, out, o); !st.ok())
    throw InputError(where + ": " + FieldError(std::string(st.message())));
}

void ReadJsonMessage(const std::string& where, const std::string& text,
                     google::protobuf::Message* out) {
  StructToMessage(where, ParseJsonObject(where, text), out);
}

}  // namespace pz::io
