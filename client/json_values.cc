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
Value Obj(const Struct& s) {
  Value v;
  *v.mutable_struct_value() = s;
  return v;
}

std::string Print(const Struct& root, const std::string& what) { return io::PrintJson(root, what); }

}  // namespace pz::client::json
