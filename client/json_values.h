// Report JSON through protobuf's Struct / Value and its JSON printer (not by hand): strings are
// escaped, a non-finite number is written as null. Shared by the reports' *.json writers.
#pragma once

#include <google/protobuf/struct.pb.h>

#include <string>
#include <vector>

namespace pz::client::json {

using google::protobuf::Struct;
using google::protobuf::Value;

Value Num(double x);  ///< null when not finite
Value Text(const std::string& s);
Value Bool(bool b);
Value Null();
Value Obj(const Struct& s);
Value List(const std::vector<Value>& items);
/// The Struct as indented JSON with a final newline (io/proto_json.h PrintJson: keys sorted);
/// throws std::runtime_error naming `what`.
std::string Print(const Struct& root, const std::string& what);

}  // namespace pz::client::json
