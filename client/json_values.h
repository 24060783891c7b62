// JSON built key by key on protobuf's Struct / Value and printed by its JSON printer (not by hand):
// strings are escaped, a non-finite number is written as null. Left to `piezoid boucwen`'s
// report.json; the stored files (fit.json, diagnosis.json, committee.json, check.json) are
// messages of proto/, printed by io/proto_json.h.
#pragma once

#include <google/protobuf/struct.pb.h>

#include <string>

namespace pz::client::json {

using google::protobuf::Struct;
using google::protobuf::Value;

Value Num(double x);  ///< null when not finite
Value Text(const std::string& s);
Value Obj(const Struct& s);
/// The Struct as indented JSON with a final newline (io/proto_json.h PrintJson: keys sorted);
/// throws std::runtime_error naming `what`.
std::string Print(const Struct& root, const std::string& what);

}  // namespace pz::client::json
