#include "client/json_values.h"

#include <google/protobuf/descriptor.h>
#include <google/protobuf/io/coded_stream.h>
#include <google/protobuf/io/zero_copy_stream_impl_lite.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/type_resolver.h>
#include <google/protobuf/util/type_resolver_util.h>

#include <cmath>
#include <memory>
#include <stdexcept>

namespace pz::client::json {

Value Num(double x) {
  Value v;
  if (std::isfinite(x))
    v.set_number_value(x);
  else
    v.set_null_value(google::protobuf::NULL_VALUE);
  return v;
}
Value Text(const std::string& s) {
  Value v;
  v.set_string_value(s);
  return v;
}
Value Bool(bool b) {
  Value v;
  v.set_bool_value(b);
  return v;
}
Value Null() {
  Value v;
  v.set_null_value(google::protobuf::NULL_VALUE);
  return v;
}
Value Obj(const Struct& s) {
  Value v;
  *v.mutable_struct_value() = s;
  return v;
}
Value List(const std::vector<Value>& items) {
  Value v;
  auto* l = v.mutable_list_value();
  for (const auto& i : items) *l->add_values() = i;
  return v;
}

std::string Print(const Struct& root, const std::string& what) {
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
  static const std::unique_ptr<google::protobuf::util::TypeResolver> resolver(
      google::protobuf::util::NewTypeResolverForDescriptorPool(
          "type.googleapis.com", google::protobuf::DescriptorPool::generated_pool()));
  std::string out;
  google::protobuf::util::JsonPrintOptions o;
  o.add_whitespace = true;
  o.preserve_proto_field_names = true;
  if (!google::protobuf::util::BinaryToJsonString(
           resolver.get(), "type.googleapis.com/" + Struct::descriptor()->full_name(), binary, &out,
           o)
           .ok())
    throw std::runtime_error("cannot format " + what);
  if (out.empty() || out.back() != '\n') out += '\n';
  return out;
}

}  // namespace pz::client::json
