// fit.json's and truth.json's codec (io/fit_model.h over io/proto_json.h): the files of
// tests/data/fit-json (written by `piezoid fit` and `piezoid synth-stack` before the codec, when
// both were built key by key; fit.json's version 1) read, their top-level copies of the model
// dropped, and are written as version 2, which reads back to the same message and bytes; a number
// written as null (not finite) reads as NaN and is written back as null, in a list too; a bad field
// is named by its path.
#include "io/fit_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>

#include "fit.pb.h"
#include "io/csv.h"
#include "io/proto_json.h"
#include "model/status.h"
#include "tests/testing/text_edit.h"

namespace pz::io {
namespace {

namespace fs = std::filesystem;
using google::protobuf::Struct;
using testing::Replaced;

fs::path Data(const std::string& name) {
  return fs::path(PIEZOID_TEST_DATA_DIR) / "fit-json" / name;
}

std::string ErrorOf(const std::string& text) {
  proto::FitFile f;
  try {
    ReadFitFile("x/fit.json", text, &f);
  } catch (const InputError& e) {
    return e.what();
  }
  return "(read)";
}

/// Version 1's top-level copies of the model's fields (dropped on reading).
constexpr const char* kCopies[] = {"response_unit", "drive_unit", "polarity", "params", "weights"};

TEST(FitModelCodec, AVersion1FitJsonReadsAndIsWrittenAsVersion2WithTheModelOnce) {
  for (const char* name : {"auto.json", "preisach-auto.json", "line.json", "spectrum.json"}) {
    const std::string text = ReadTextFile(Data(name));
    const Struct old = ParseJsonObject(name, text);
    EXPECT_EQ(old.fields().at("format_version").number_value(), 1) << name;
    proto::FitFile f;
    ReadFitFile(name, text, &f);
    ASSERT_TRUE(f.has_model()) << name;
    EXPECT_FALSE(f.records().empty()) << name;
    EXPECT_FALSE(f.model().has_train_mean_output()) << name;
    // What version 1 wrote twice is the model's: nothing is lost by dropping the copies.
    const proto::FitModel& m = f.model();
    EXPECT_EQ(old.fields().at("response_unit").string_value(), m.response_unit()) << name;
    EXPECT_EQ(old.fields().at("drive_unit").string_value(), m.drive_unit()) << name;
    EXPECT_EQ(old.fields().at("polarity").number_value(), m.polarity()) << name;
    const auto& params = old.fields().at("params").struct_value().fields();
    ASSERT_EQ(params.size(), static_cast<size_t>(m.params_size())) << name;
    for (const proto::FitParam& p : m.params())
      EXPECT_EQ(params.at(p.name()).number_value(), p.value()) << name << " " << p.name();
    const auto& weights = old.fields().at("weights").list_value().values();
    ASSERT_EQ(weights.size(), m.weights_size()) << name;
    for (int i = 0; i < m.weights_size(); ++i)
      EXPECT_EQ(weights[i].number_value(), m.weights(i)) << name << " weight " << i;
    // Written as version 2: the model once, the rest as it was; read back to the same message.
    const std::string v2 = WriteFitFile(f);
    const Struct root = ParseJsonObject(name, v2);
    EXPECT_EQ(root.fields().at("format_version").number_value(), 2) << name;
    EXPECT_EQ(root.fields().at("model").struct_value().fields().at("format_version").number_value(),
              2)
        << name;
    for (const char* key : kCopies) EXPECT_FALSE(root.fields().contains(key)) << name << " " << key;
    EXPECT_EQ(root.fields().size() + std::size(kCopies), old.fields().size()) << name;
    proto::FitFile back;
    ReadFitFile(name, v2, &back);
    proto::FitFile expected = f;
    expected.set_format_version(2);
    expected.mutable_model()->set_format_version(2);
    EXPECT_EQ(back.SerializeAsString(), expected.SerializeAsString()) << name;
    EXPECT_EQ(WriteFitFile(back), v2) << name;
    proto::FitModel model;
    ReadFitModel(name, text, &model);
    EXPECT_EQ(model.family(), f.model().family()) << name;
  }
  proto::FitFile f;
  ReadFitFile("auto.json", ReadTextFile(Data("auto.json")), &f);
  EXPECT_TRUE(f.has_selection());
  EXPECT_FALSE(f.selection().ranking().empty());
  EXPECT_FALSE(f.has_resolution());
  ReadFitFile("preisach-auto.json", ReadTextFile(Data("preisach-auto.json")), &f);
  EXPECT_TRUE(f.has_resolution());
  EXPECT_TRUE(f.has_regularisation());
  EXPECT_FALSE(f.has_selection());
  ReadFitFile("line.json", ReadTextFile(Data("line.json")), &f);
  EXPECT_EQ(f.search().algorithm(), "line");
  EXPECT_TRUE(f.search().has_grid());
  EXPECT_FALSE(f.search().has_particles());
  ReadFitFile("spectrum.json", ReadTextFile(Data("spectrum.json")), &f);
  EXPECT_TRUE(f.has_spectrum_regularisation());
  EXPECT_TRUE(f.search().has_solved_parameters());
}

/// `text` with the value that starts after the first `key` following `after` (up to its comma or
/// line end) replaced by null.
std::string Nulled(std::string text, const std::string& after, const std::string& key) {
  const size_t at = text.find(key, text.find(after));
  EXPECT_NE(at, std::string::npos) << key;
  if (at == std::string::npos) return text;
  const size_t from = at + key.size(), to = text.find_first_of(",\n", from);
  return text.replace(from, to - from, "null");
}

TEST(FitModelCodec, NullIsNotFiniteAndWrittenBackAsNull) {
  std::string text = Nulled(ReadTextFile(Data("auto.json")), "\"records\"", "\"nrmse_pct\": ");
  // in a list, where protobuf's parser would drop it: it stays in its place
  text = Nulled(text, "\"fold_rmse\"", "[\n     ");
  proto::FitFile f;
  ReadFitFile("nulls", text, &f);
  for (int pass = 0; pass < 2; ++pass) {  // version 1 as read, then its version 2 read back
    EXPECT_TRUE(std::isnan(f.records(0).nrmse_pct()));
    const auto& folds = f.selection().ranking(0).fold_rmse();
    ASSERT_GE(folds.size(), 2);
    EXPECT_TRUE(std::isnan(folds[0]));
    EXPECT_TRUE(std::isfinite(folds[1]));
    const std::string v2 = WriteFitFile(f);
    EXPECT_NE(v2.find("\"nrmse_pct\": null"), std::string::npos);
    ReadFitFile("nulls", v2, &f);
    EXPECT_EQ(WriteFitFile(f), v2);
  }
  f.mutable_records(0)->set_rmse(INFINITY);  // written as null too (protobuf: "Infinity")
  EXPECT_NE(WriteFitFile(f).find("\"rmse\": null"), std::string::npos);
}

TEST(FitModelCodec, ABadFieldIsNamedByItsPath) {
  const std::string text = ReadTextFile(Data("auto.json"));
  EXPECT_NE(ErrorOf(Replaced(text, "\"max_abs\"", "\"rmse\"", "\"rmsee\"")).find("x/fit.json: "),
            std::string::npos);
  const std::string unknown = ErrorOf(Replaced(text, "\"records\"", "\"rmse\"", "\"rmsee\""));
  EXPECT_NE(unknown.find("x/fit.json: records[0].rmsee: Cannot find field"), std::string::npos)
      << unknown;
  const std::string typed =
      ErrorOf(Replaced(text, "\"search\"", "\"polishes\": 1", "\"polishes\": \"two\""));
  EXPECT_NE(typed.find("x/fit.json: search.polishes: invalid value \"two\""), std::string::npos)
      << typed;
  const std::string model = ErrorOf(Replaced(text, "\"model\"", "\"weights\"", "\"weigths\""));
  EXPECT_NE(model.find("x/fit.json: model.weigths: Cannot find field"), std::string::npos) << model;
  EXPECT_NE(ErrorOf(Replaced(text, "\"format_version\"", "1", "3"))
                .find("format_version 3: this piezoid reads fit.json format_version 1 or 2"),
            std::string::npos);
  const std::string mixed =
      ErrorOf(Replaced(text, "\"model\"", "\"format_version\": 1", "\"format_version\": 2"));
  EXPECT_NE(mixed.find("x/fit.json: model.format_version 2: not the file's format_version 1"),
            std::string::npos)
      << mixed;
  EXPECT_NE(ErrorOf("[1]").find("x/fit.json: not a JSON object"), std::string::npos);
}

TEST(FitModelCodec, ModelOnlyFilesOfTheFuzzCorpusRead) {
  const fs::path f =
      fs::path(PIEZOID_DATA_DIR) / ".." / "fuzz" / "corpus-fit-model" / "asymmetric-pi.json";
  proto::FitModel m;
  ReadFitModel(f.string(), ReadTextFile(f), &m);
  EXPECT_EQ(m.family(), "asymmetric-pi");
  EXPECT_NE(ErrorOf("{\"format_version\": 1}").find("(read)"), std::string::npos);
  proto::FitModel none;
  try {
    ReadFitModel("x/fit.json", "{\"format_version\": 1}", &none);
    FAIL() << "read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("no \"model\" object"), std::string::npos) << e.what();
  }
}

TEST(SynthTruthCodec, AnOldTruthJsonReadsAndIsWrittenBackToTheSameBytes) {
  const std::string text = ReadTextFile(Data("truth.json"));
  proto::SynthTruth t;
  ReadSynthTruth("truth.json", text, &t);
  EXPECT_TRUE(t.plant().has_rate_lag_v());
  EXPECT_TRUE(t.plant().has_driver_tau_s());
  EXPECT_FALSE(t.records().empty());
  EXPECT_EQ(WriteSynthTruth(t), text);
  try {
    ReadSynthTruth("x/truth.json", Replaced(text, "\"sensor\"", "\"fs_hz\"", "\"fs\""), &t);
    FAIL() << "read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("x/truth.json: sensor.fs: Cannot find field"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace pz::io
