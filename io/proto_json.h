// Stored JSON through protobuf's JSON util: the files and reports the product writes as JSON are
// messages of proto/ printed here (fit.json, truth.json: io/fit_model.h; diagnosis.json,
// check.json: io/diagnosis_json.h; committee.json; `piezoid boucwen`'s report.json; `piezoid pi
// --json`; `piezoid dahl --json`), none by hand. (A network's .json is protobuf's own printing,
// io/network_io.h; the dashboard's documents are served, not stored: service/wire_codec.h, and a
// report folder's file list in dashboard/dashboard.cc.) Here: a message <-> an indented JSON object
// whose bytes do not vary from run to run, and a reader that names the bad field. One walker
// (WalkJsonObject) goes over a message's JSON object by its fields, for the rules below and for a
// codec's own (io/diagnosis_json.cc).
//
// Written: the message's proto field names; every field without presence (an empty list, a zero),
// a proto3 optional or message field only when set; keys sorted at every level; a non-finite
// double as null (protobuf would write the string "NaN"); a 64-bit integer as a number (protobuf
// would write a string). Read: an unknown field or a value of another type is an InputError naming
// the field ("model.substeps: …"); null in a double field reads as NaN (what the writer wrote for a
// value that was not finite), anywhere else as the field's default.
#pragma once

#include <google/protobuf/descriptor.h>
#include <google/protobuf/message.h>
#include <google/protobuf/struct.pb.h>

#include <functional>
#include <string>

namespace pz::io {

/// The message as a JSON object (the rules above).
google::protobuf::Struct MessageToStruct(const google::protobuf::Message& m);

/// The object as indented JSON, keys sorted, with a final newline. Throws std::runtime_error
/// naming `what` (protobuf refused the document: never for a Struct built here).
std::string PrintJson(const google::protobuf::Struct& root, const std::string& what);

/// MessageToStruct then PrintJson.
std::string PrintJson(const google::protobuf::Message& m, const std::string& what);

/// JSON text as an object. Throws InputError "`where`: not a JSON object: …".
google::protobuf::Struct ParseJsonObject(const std::string& where, const std::string& text);

/// The object into `out` (replaced). Throws InputError "`where`: FIELD: …" naming the unknown or
/// mistyped field by its path (records[2].rmse).
void StructToMessage(const std::string& where, const google::protobuf::Struct& root,
                     google::protobuf::Message* out);

/// ParseJsonObject then StructToMessage.
void ReadJsonMessage(const std::string& where, const std::string& text,
                     google::protobuf::Message* out);

/// What WalkJsonObject does at each key and value of a message's JSON object (either may be empty).
struct JsonFieldWalk {
  /// Each key that names a field, with its path from the root (records[2].rmse) and its value,
  /// before its elements are walked: false erases the key (its elements are not walked).
  std::function<bool(const google::protobuf::FieldDescriptor& field, const std::string& path,
                     const google::protobuf::Value& value)>
      keep;
  /// Each element of a kept field that is not a message (the value, a list's item, a map's value),
  /// with the field (a map's value field for a map).
  std::function<void(const google::protobuf::FieldDescriptor& field, google::protobuf::Value* v)>
      scalar;
};

/// Walks `s`, the JSON object of a message of type `d`, depth first: a key that names no field (by
/// its proto or JSON name) is left for the parser to name; an element that is an object of a
/// message type (not a well-known type) is walked in turn, with its path (list[i], map.key).
void WalkJsonObject(const google::protobuf::Descriptor& d, google::protobuf::Struct* s,
                    const JsonFieldWalk& walk, const std::string& path = "");

}  // namespace pz::io
