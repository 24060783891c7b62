// The JSON files the client writes (fit.json, diagnosis.json, committee.json, truth.json) are
// protobuf Structs, whose fields are a map that protobuf keeps in hash order: json::Print writes
// them with their keys sorted, so the same document is the same bytes in every run and process.
#include <gtest/gtest.h>

#include <string>

#include "client/json_values.h"

namespace pz::client::json {
namespace {

TEST(JsonPrint, KeysAreSortedWhateverTheInsertionOrder) {
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
  (*forward.mutable_fields())["nested"] = Obj(inner);
  (*backward.mutable_fields())["nested"] = Obj(inner);
  const std::string a = Print(forward, "test"), b = Print(backward, "test");
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
}  // namespace pz::client::json
