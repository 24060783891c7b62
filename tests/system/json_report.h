// Helpers of the system tests that compare a local run's JSON report (fit.json, report.json, …)
// with the same command's run on the service: the report read without the keys that depend on the
// machine, and compared value for value, numbers bit for bit (the reports print them to
// round-trip).
#pragma once

#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <sstream>
#include <string>

namespace pz::testing {

/// The JSON file `file` without the keys `drop`, at any depth (a test failure when it does not
/// parse).
inline google::protobuf::Struct ReadJsonWithout(const std::filesystem::path& file,
                                                std::initializer_list<const char*> drop) {
  std::ifstream in(file);
  std::stringstream ss;
  ss << in.rdbuf();
  google::protobuf::Struct s;
  EXPECT_TRUE(google::protobuf::util::JsonStringToMessage(ss.str(), &s).ok()) << file;
  std::function<void(google::protobuf::Struct*)> strip = [&](google::protobuf::Struct* x) {
    for (const char* key : drop) x->mutable_fields()->erase(key);
    for (auto& [key, v] : *x->mutable_fields()) {
      if (v.has_struct_value()) strip(v.mutable_struct_value());
      if (v.has_list_value())
        for (auto& item : *v.mutable_list_value()->mutable_values())
          if (item.has_struct_value()) strip(item.mutable_struct_value());
    }
  };
  strip(&s);
  return s;
}

/// Same keys and values, numbers bit for bit; the differences in the failure's message.
template <class Message>
void ExpectSameJson(const Message& a, const Message& b, const std::string& what = "") {
  google::protobuf::util::MessageDifferencer d;
  std::string diff;
  d.ReportDifferencesToString(&diff);
  EXPECT_TRUE(d.Compare(a, b)) << what << (what.empty() ? "" : ":\n") << diff;
}

}  // namespace pz::testing
