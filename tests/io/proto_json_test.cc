// io/proto_json.h prints a protobuf Struct (what MessageToStruct gives for every stored file:
// fit.json, diagnosis.json, committee.json, report.json, ...), whose fields are a map that protobuf
// keeps in hash order: PrintJson writes them with their keys sorted at every level, so the same
// document is the same bytes in every run and process.
#include "io/proto_json.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace pz::io {
namespace {

using google::protobuf::Struct;
using google::protobuf::Value;

Value Num(double x) {
  Value v;
  v.set_number_value(x);
  return v;
}

Value Text(const std::string& s) {
  Value v;
  v.set_string_value(s);
  return v;
}

TEST(PrintJson, KeysAreSortedWhateverTheInsertionOrder) {
  const std::vector<std::string> keys = {"zeta",  "alpha", "mid", "beta", "omega",
                                         "gamma", "a1",    "a10", "a2"};
  Struct forward, backward;
  for (size_t i = 0; i < keys.size(); ++i) {
    (*forward.mutable_fields())[keys[i]] = Num(static_cast<double>(i));
    (*backward.mutable_fields())[keys[keys.size() - 1 - i]] =
        Num(static_cast<double>(keys.size() - 1 - i));
  }
  Struct inner;
  (*inner.mutable_fields())["y"] = Text("b");
  (*inner.mutable_fields())["x"] = Text("a");
  *(*forward.mutable_fields())["nested"].mutable_struct_value() = inner;
  *(*backward.mutable_fields())["nested"].mutable_struct_value() = inner;
  const std::string a = PrintJson(forward, "test"), b = PrintJson(backward, "test");
  EXPECT_EQ(a, b);
  size_t last = 0;
  for (const char* k : {"\"a1\"", "\"a10\"", "\"a2\"", "\"alpha\"", "\"beta\"", "\"gamma\"",
                        "\"mid\"", "\"nested\"", "\"omega\"", "\"zeta\""}) {
    const size_t at = a.find(k);
    ASSERT_NE(at, std::string::npos) << k;
    EXPECT_GT(at, last) << k << " out of order in\n" << a;
    last = at;
  }
  EXPECT_LT(a.find("\"x\""), a.find("\"y\""));
  EXPECT_EQ(a.back(), '\n');
}

}  // namespace
}  // namespace pz::io
