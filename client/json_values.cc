#include "client/json_values.h"

#include <cmath>

#include "io/proto_json.h"

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

std::string Print(const Struct& root, const std::string& what) { return io::PrintJson(root, what); }

}  // namespace pz::client::json
