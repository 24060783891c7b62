// io/proto_json.h prints a protobuf Struct (what MessageToStruct gives for every stored file:
// fit.json, diagnosis.json, committee.json, report.json, ...), whose fields are a map that protobuf
// keeps in hash order: PrintJson writes them with their keys sorted at every level, so the same
// document is the same bytes in every run and process. WalkJsonObject goes over such an object by
// the message's fields: every key with its path, every scalar element, a key erased on request.
#include "io/proto_json.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "committee.pb.h"

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

TEST(WalkJsonObject, SeesEveryFieldByItsPathAndErasesWhatKeepRefuses) {
  proto::CommitteeFile f;
  f.add_band_edges_hz(0);
  f.add_band_edges_hz(100);
  f.add_bands()->set_band("0-100 Hz");
  proto::CommitteeBand& b = *f.add_bands();
  b.set_selected("stack-bouc-wen/pso");
  proto::CommitteeModel& m = *b.add_models();
  (*m.mutable_parameters())["alpha"] = std::nan("");
  m.mutable_all_test()->set_samples(7);
  Struct s = MessageToStruct(f);
  // Written: the NaN of a map's value is null, the 64-bit integer a number.
  const Struct& model = s.fields()
                            .at("bands")
                            .list_value()
                            .values(1)
                            .struct_value()
                            .fields()
                            .at("models")
                            .list_value()
                            .values(0)
                            .struct_value();
  EXPECT_EQ(model.fields().at("parameters").struct_value().fields().at("alpha").kind_case(),
            Value::kNullValue);
  EXPECT_EQ(model.fields().at("all_test").struct_value().fields().at("samples").number_value(), 7);

  std::vector<std::string> paths;
  int scalars = 0, doubles = 0;
  JsonFieldWalk walk;
  walk.keep = [&](const google::protobuf::FieldDescriptor& field, const std::string& path,
                  const Value&) {
    paths.push_back(path);
    return field.name() != "selected";
  };
  walk.scalar = [&](const google::protobuf::FieldDescriptor& field, Value*) {
    ++scalars;
    doubles += field.cpp_type() == google::protobuf::FieldDescriptor::CPPTYPE_DOUBLE;
  };
  WalkJsonObject(*f.GetDescriptor(), &s, walk);
  for (const char* p : {"band_edges_hz", "bands", "bands[0].band", "bands[1].selected",
                        "bands[1].models[0].parameters", "bands[1].models[0].all_test.samples",
                        "bands[1].models[0].all_test.rmse_um"})
    EXPECT_NE(std::find(paths.begin(), paths.end(), p), paths.end()) << p;
  EXPECT_EQ(std::find(paths.begin(), paths.end(), "committee_test"), paths.end());  // unset
  EXPECT_EQ(std::find(paths.begin(), paths.end(), "bands[1].models[0].parameters.alpha"),
            paths.end());  // a map's entries are elements, not keys
  const std::string printed = PrintJson(s, "test");
  EXPECT_EQ(printed.find("\"selected\""), std::string::npos) << printed;  // erased at every level
  EXPECT_NE(printed.find("\"band\": \"0-100 Hz\""), std::string::npos) << printed;
  EXPECT_GT(scalars, doubles);
  EXPECT_GE(doubles, 3);  // the two band edges and alpha's null at least
}

}  // namespace
}  // namespace pz::io
