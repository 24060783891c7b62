// Network files: .pb and .json round trips give predictions identical to the bit; loading rejects
// bad files with errors that name the field.
#include "io/network_io.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <random>

#include "model/chromosome.h"
#include "network.pb.h"

namespace pz::io {
namespace {

using model::TransferFunction;

std::string TempPath(const std::string& name) {
  return (std::filesystem::path(testing::TempDir()) / ("network_io_test_" + name)).string();
}

SavedNetwork FromGa(uint64_t seed) {
  std::mt19937_64 g(seed);
  std::vector<uint8_t> bits(model::kChromosomeBits);
  for (uint8_t& b : bits) b = static_cast<uint8_t>(g() >> 63);
  const double v[] = {375, 500, 500, 750}, f[] = {0.25, 0.5, 1.0, 0.25};
  SavedNetwork s;
  s.network = model::DecodeChromosome(bits, model::InputNormalization::FromCases(v, f),
                                      model::ParameterRanges::PaperTable3());
  s.chromosome = bits;
  s.provenance.job_id = "job-42";
  s.provenance.seed = 1234567890123456789ULL;
  s.provenance.generation = 750;
  s.provenance.fitness = 10.53;
  s.provenance.created_unix_ms = 1700000000123;
  s.provenance.piezoid_version = "0.1.0";
  s.provenance.training_cases = {"case1", "case5", "case6", "case7"};
  return s;
}

// A hand-made network (weights off the chromosome grid, no chromosome).
SavedNetwork HandMade() {
  SavedNetwork s;
  model::Network& n = s.network;
  n.input_tf = {TransferFunction::kSatlin, TransferFunction::kTribas};
  n.hidden_tf = {TransferFunction::kTribas, TransferFunction::kSatlins, TransferFunction::kTansig};
  n.output_tf.fill(TransferFunction::kLogsig);
  n.w1 = Eigen::MatrixXd::Constant(2, 3, 0.1234567890123);
  n.c1 = Eigen::VectorXd::Constant(3, -1.0 / 3.0);
  n.w2 = Eigen::MatrixXd::Constant(3, 7, std::sqrt(2.0));
  n.w2(2, 6) = -1e-300;
  n.c2 = Eigen::VectorXd::Constant(7, 0.7307);
  n.normalization = {375, 750, 0.25, 1.0};
  return s;
}

void ExpectSamePredictions(const model::Network& a, const model::Network& b) {
  for (double v : {0.0, 375.0, 437.5, 500.0, 612.0, 750.0, 900.0}) {
    for (double f : {0.1, 0.25, 0.5, 0.75, 1.0, 2.0}) {
      const auto pa = a.Predict(v, f).ToArray(), pb = b.Predict(v, f).ToArray();
      ASSERT_EQ(std::memcmp(pa.data(), pb.data(), sizeof(pa)), 0) << v << " V " << f << " Hz";
    }
  }
}

TEST(NetworkIo, RoundTripsThroughBinaryAndJsonFiles) {
  for (const SavedNetwork& original : {FromGa(1), FromGa(2), HandMade()}) {
    for (const char* ext : {".pb", ".json", ".JSON"}) {
      const std::string path = TempPath(std::string("roundtrip") + ext);
      ASSERT_TRUE(SaveNetwork(original, path).ok()) << SaveNetwork(original, path).message();
      SavedNetwork loaded;
      const Status s = LoadNetwork(path, &loaded);
      ASSERT_TRUE(s.ok()) << s.message();
      EXPECT_TRUE(loaded == original) << ext;
      ExpectSamePredictions(original.network, loaded.network);
      EXPECT_FALSE(std::filesystem::exists(path + ".tmp"));
    }
  }
}

TEST(NetworkIo, JsonIsReadable) {
  std::string json;
  ASSERT_TRUE(SerializeNetwork(FromGa(3), NetworkFormat::kJson, &json).ok());
  for (const char* text : {"\"format_version\": 1", "\"name\": \"alpha\"", "\"unit\": \"N/V\"",
                           "\"name\": \"amplitude\"", "NETWORK_TF_", "\"job_id\": \"job-42\"",
                           "\"created\": \"2023-11-14T22:13:20.123Z\"", "\"chromosome\":"}) {
    EXPECT_NE(json.find(text), std::string::npos) << text << "\n" << json;
  }
}

TEST(NetworkIo, FormatFollowsTheExtension) {
  EXPECT_EQ(NetworkFormatForPath("a/b/net.json"), NetworkFormat::kJson);
  EXPECT_EQ(NetworkFormatForPath("net.Json"), NetworkFormat::kJson);
  EXPECT_EQ(NetworkFormatForPath("net.pb"), NetworkFormat::kBinary);
  EXPECT_EQ(NetworkFormatForPath("json"), NetworkFormat::kBinary);
}

// Serialises a tampered proto and returns the load error.
template <typename Tamper>
std::string LoadError(const SavedNetwork& good, Tamper tamper) {
  proto::NetworkFile file;
  ToProto(good, &file);
  tamper(file);
  SavedNetwork out;
  const Status s = ParseNetwork(file.SerializeAsString(), NetworkFormat::kBinary, &out);
  EXPECT_FALSE(s.ok());
  return s.message();
}

TEST(NetworkIo, BadContentsGiveFieldNamedErrors) {
  const SavedNetwork good = FromGa(5);
  const int h = good.network.hidden();
  using F = proto::NetworkFile;
  auto has = [](const std::string& msg, const std::string& part) {
    EXPECT_NE(msg.find(part), std::string::npos) << "'" << part << "' not in: " << msg;
  };
  has(LoadError(good, [](F& f) { f.set_format_version(2); }), "format_version = 2");
  has(LoadError(good, [](F& f) { f.set_hidden(10); }), "hidden = 10");
  has(LoadError(good, [](F& f) { f.mutable_w1()->RemoveLast(); }),
      "w1: has " + std::to_string(2 * h - 1) +
          " values, expected 2 x H = " + std::to_string(2 * h));
  has(LoadError(good, [](F& f) { f.add_c2(0); }), "c2: has 8 values");
  has(LoadError(good, [](F& f) { f.mutable_hidden_tf()->RemoveLast(); }), "hidden_tf: has");
  has(LoadError(good,
                [](F& f) { f.set_hidden_tf(1, static_cast<proto::NetworkTransferFunction>(9)); }),
      "hidden_tf[1] = 9");
  has(LoadError(good, [](F& f) { f.set_output_tf(0, proto::NETWORK_TF_UNSPECIFIED); }),
      "output_tf[0] = 0");
  has(LoadError(good, [](F& f) { f.set_w2(3, std::numeric_limits<double>::quiet_NaN()); }),
      "w2[3] = nan: must be finite");
  has(LoadError(good, [](F& f) { f.set_c1(0, std::numeric_limits<double>::infinity()); }),
      "c1[0] = inf");
  has(LoadError(good, [](F& f) { f.mutable_parameters(2)->set_name("beta"); }),
      "parameters[2].name = \"beta\": expected \"alpha\"");
  has(LoadError(good, [](F& f) { f.mutable_parameters(4)->set_upper(-1); }), "ranges.gamma.upper");
  has(LoadError(good, [](F& f) { f.mutable_inputs(1)->set_hi(0.1); }),
      "normalization.frequency_hi_hz");
  has(LoadError(good, [](F& f) { f.mutable_inputs()->RemoveLast(); }), "inputs: has 1 values");
  has(LoadError(good, [](F& f) { f.set_w1(0, f.w1(0) + 1e-3); }), "chromosome: does not decode");
  has(LoadError(good, [](F& f) { f.mutable_chromosome()->pop_back(); }),
      "chromosome: packed bits size");
  has(LoadError(good,
                [](F& f) {
                  f.mutable_provenance()->set_fitness(std::numeric_limits<double>::quiet_NaN());
                }),
      "provenance.fitness");
}

TEST(NetworkIo, UnreadableFilesAreErrors) {
  SavedNetwork out;
  Status s = LoadNetwork(TempPath("does_not_exist.pb"), &out);
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_NE(s.message().find("does_not_exist.pb: cannot open"), std::string::npos) << s.message();

  const std::string garbage = TempPath("garbage.pb");
  std::ofstream(garbage, std::ios::binary) << "\xff\xff\xff\xff not a protobuf";
  s = LoadNetwork(garbage, &out);
  EXPECT_EQ(s.code(), StatusCode::kDataLoss) << s.ToString();

  const std::string bad_json = TempPath("bad.json");
  std::ofstream(bad_json) << "{\"format_version\": 1, \"hiden\": 3}";
  s = LoadNetwork(bad_json, &out);
  EXPECT_NE(s.message().find("bad.json: not a NetworkFile JSON"), std::string::npos) << s.message();

  const std::string empty = TempPath("empty.pb");
  std::ofstream(empty, std::ios::binary).flush();
  s = LoadNetwork(empty, &out);
  EXPECT_NE(s.message().find("format_version = 0"), std::string::npos) << s.message();
}

TEST(NetworkIo, SaveRefusesAnInvalidNetwork) {
  SavedNetwork bad = HandMade();
  bad.network.c2(6) = std::numeric_limits<double>::quiet_NaN();
  const std::string path = TempPath("invalid.pb");
  const Status s = SaveNetwork(bad, path);
  EXPECT_NE(s.message().find("c2(6)"), std::string::npos) << s.message();
  EXPECT_FALSE(std::filesystem::exists(path));
}

}  // namespace
}  // namespace pz::io
