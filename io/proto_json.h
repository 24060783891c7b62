// Stored JSON through protobuf's JSON util: every JSON file the product writes is a message of
// proto/ printed here (fit.json, truth.json: io/fit_model.h; diagnosis.json, check.json:
// io/diagnosis_json.h; committee.json; `piezoid boucwen`'s report.json; `piezoid pi --json`): a
// message <-> an indented JSON object whose bytes do not vary from run to run, and a reader that
// names the bad field.
//
// Written: the message's proto field names; every field without presence (an empty list, a zero),
// a proto3 optional or message field only when set; keys sorted at every level; a non-finite
// double as null (protobuf would write the string "NaN"); a 64-bit integer as a number (protobuf
// would write a string). Read: an unknown field or a value of another type is an InputError naming
// the field ("model.substeps: …"); null in a double field reads as NaN (what the writer wrote for a
// value that was not finite), anywhere else as the field's default.
#pragma once

#include <google/protobuf/message.h>
#include <google/protobuf/struct.pb.h>

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

}  // namespace pz::io
