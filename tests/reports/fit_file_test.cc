// fit.json's codec (io/fit_model.h: the JSON <-> proto::FitModel; reports/fit_file.h: the one
// conversion to records::ModelSpec) over every fit.json of the fuzzer's seed corpus
// (fuzz/corpus-fit-model: fit.json model sections `piezoid fit` wrote, one per family and effect,
// and the regressions the fuzzer found): each loads to a model or a named InputError, and a model
// it loads is written back to the same values (what `piezoid fit` writes for that model).
#include "reports/fit_file.h"

#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "io/csv.h"
#include "io/proto_json.h"

namespace pz::reports {
namespace {

namespace fs = std::filesystem;

std::vector<fs::path> Corpus() {
  std::vector<fs::path> files;
  for (const auto& e :
       fs::directory_iterator(fs::path(PIEZOID_DATA_DIR) / ".." / "fuzz" / "corpus-fit-model"))
    if (e.path().extension() == ".json") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

TEST(FitFile, EveryCorpusFileLoadsAndWritesBackTheSameBytes) {
  const std::vector<fs::path> files = Corpus();
  ASSERT_GE(files.size(), 20u);
  int loaded = 0;
  for (const fs::path& f : files) {
    const std::string text = io::ReadTextFile(f);
    records::ModelSpec m;
    try {
      m = LoadFitText(f.string(), text);
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(f.string()), std::string::npos) << e.what();
      continue;
    }
    ++loaded;
    google::protobuf::Struct stored;
    // The corpus was written with the shortest digits that give each double back: compared as
    // values, printed alike. It is of fit.json's version 1 (still read; its model section is the
    // same): written back as the current version.
    ASSERT_TRUE(google::protobuf::util::JsonStringToMessage(text, &stored).ok()) << f;
    google::protobuf::Struct model = stored.fields().at("model").struct_value();
    EXPECT_EQ(model.fields().at("format_version").number_value(), 1) << f;
    (*model.mutable_fields())["format_version"].set_number_value(io::kFitFormatVersion);
    EXPECT_EQ(FitModelJson(m), io::PrintJson(model, "fit.json")) << f;
    EXPECT_TRUE(LooksLikeFitJson(f.string())) << f;
  }
  EXPECT_GE(loaded, 20) << "of " << files.size();
}

TEST(FitFile, AFieldOfAnotherTypeIsNamed) {
  const fs::path f = fs::path(PIEZOID_DATA_DIR) / ".." / "fuzz" / "corpus-fit-model" / "duhem.json";
  std::string text = io::ReadTextFile(f);
  const std::string field = "\"substeps\": 2";
  const size_t at = text.find(field);
  ASSERT_NE(at, std::string::npos);
  text.replace(at, field.size(), "\"substeps\": \"two\"");
  try {
    (void)LoadFitText("x/fit.json", text);
    FAIL() << "loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("x/fit.json: model.substeps: invalid value \"two\""),
              std::string::npos)
        << e.what();
  }
}

// A drive range a fit never writes (the fuzzer's: -4.3e17 V on a fin whose data spans 32 V, which
// took the fin's sub-steps 9 s for 24 samples) is refused by name; an amplifier's wider range
// loads.
TEST(FitFile, ADriveRangeFarBeyondTheDataIsRefusedByName) {
  const fs::path f =
      fs::path(PIEZOID_DATA_DIR) / ".." / "fuzz" / "corpus-fit-model" / "bimorph-fin.json";
  const std::string text = io::ReadTextFile(f);
  const records::ModelSpec m = LoadFitText("x/fit.json", text);
  const std::string field = "\"drive_min\": ";
  const size_t at = text.find(field);
  ASSERT_NE(at, std::string::npos);
  const size_t end = text.find_first_of(",\n", at + field.size());
  auto with_min = [&](double v) {
    std::string t = text;
    t.replace(at, end - at, field + io::FormatNumber(v));
    return t;
  };
  const double centre = 0.5 * (m.scale.u_min + m.scale.u_max);
  EXPECT_NO_THROW((void)LoadFitText("x/fit.json", with_min(centre - 3 * m.scale.u_half)));
  try {
    (void)LoadFitText("x/fit.json", with_min(-4.3e17));
    FAIL() << "loaded";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("x/fit.json: model.drive_min / drive_max = [-4.3e+17"),
              std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("1000 half-ranges"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace pz::reports
