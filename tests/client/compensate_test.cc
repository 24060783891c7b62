// `piezoid fit` → fit.json → `piezoid compensate` (issue 23): on a synthetic plant with a known
// inverse (a Prandtl–Ishlinskii operator written here, with measurement noise), the drive the
// compensator computes from the fitted model, played on the true plant, tracks the reference within
// the noise; a reference beyond the drive's reach is clipped and reported (how much, where); a
// reference in other units is refused naming both; a fit.json of another version is refused with
// the version needed, a bad field is named; --check-model reports another model's error; --replay
// of the training record is close to the noise, and so is the replay of a record whose sensor zero
// is another (each record's offset is taken as the fit takes it), beside the noiseless replay of
// the model's own response (≈ 0) and the drive error the noise alone implies.
#include <gtest/gtest.h>

#include <CLI/CLI.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <optional>
#include <random>
#include <regex>
#include <sstream>

#include "client/commands.h"
#include "io/csv.h"
#include "model/format.h"
#include "reports/fit_file.h"
#include "tests/testing/cli.h"
#include "tests/testing/expect_error.h"

namespace pz::client {
namespace {

namespace fs = std::filesystem;

constexpr double kNoise = 0.02;  // [um], the plant's measurement noise

int RunCli(const std::vector<std::string>& args) {
  return pz::testing::RunCommands({RegisterFit, RegisterCompensate}, args);
}

std::string Captured(const std::vector<std::string>& args) {
  return pz::testing::CapturedCommands({RegisterFit, RegisterCompensate}, args);
}

/// The true plant: 0.25 u + Σ w_i play_{r_i}[u] from rest at u[0] (three plays).
std::vector<double> Plant(const std::vector<double>& u) {
  const double r[3] = {3, 9, 18}, w[3] = {0.08, 0.06, 0.05};
  double z[3] = {u[0], u[0], u[0]};
  std::vector<double> y(u.size());
  for (size_t k = 0; k < u.size(); ++k) {
    double acc = 0.25 * u[k];
    for (int i = 0; i < 3; ++i) {
      z[i] = std::max(u[k] - r[i], std::min(u[k] + r[i], z[i]));
      acc += w[i] * z[i];
    }
    y[k] = acc;
  }
  return y;
}

class Compensate : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = fs::path(::testing::TempDir()) / "compensate_cli";
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    std::vector<double> u;
    for (size_t k = 0; k < 6000; ++k) {
      const double t = static_cast<double>(k) * 1e-3;
      u.push_back(50 + 45 * std::sin(2 * std::numbers::pi * t) * (0.6 + 0.4 * std::cos(0.8 * t)));
    }
    const std::vector<double> y = Plant(u);
    std::mt19937_64 rng(7);
    std::normal_distribution<double> noise(0, kNoise);
    std::ofstream rec(dir_ / "rec.csv");
    rec << "t_s,voltage_V,displacement_um\n";
    for (size_t k = 0; k < u.size(); ++k)
      rec << io::FormatNumber(static_cast<double>(k) * 1e-3) << "," << io::FormatNumber(u[k]) << ","
          << io::FormatNumber(y[k] + noise(rng)) << "\n";
    rec.close();
    Captured({"fit", "--records", (dir_ / "rec.csv").string(), "--family", "prandtl-ishlinskii",
              "--pi-operators", "24", "--out", (dir_ / "fit").string(), "--no-figures", "--quiet"});
    Captured({"fit", "--records", (dir_ / "rec.csv").string(), "--family", "backlash-like", "--out",
              (dir_ / "other").string(), "--no-figures", "--quiet"});
  }
  static void WriteReference(const fs::path& p, double amplitude,
                             const std::string& column = "displacement_um") {
    std::ofstream ref(p);
    ref << "t_s," << column << "\n";
    for (size_t k = 0; k < 2000; ++k) {
      const double t = static_cast<double>(k) * 1e-3;
      ref << io::FormatNumber(t) << ","
          << io::FormatNumber(25 + amplitude * std::sin(2 * std::numbers::pi * 1.5 * t)) << "\n";
    }
  }
  static std::vector<double> Column(const fs::path& p, int col) {
    const io::CsvTable t = io::ReadCsvFile(p);
    std::vector<double> v;
    for (size_t i = 0; i < t.rows.size(); ++i) v.push_back(t.Number(i, col));
    return v;
  }
  static fs::path dir_;
};
fs::path Compensate::dir_;

TEST_F(Compensate, TheDriveMakesTheTruePlantTrackWithinTheNoise) {
  WriteReference(dir_ / "ref.csv", 12);
  const std::string out =
      Captured({"compensate", "--model", (dir_ / "fit" / "fit.json").string(), "--reference",
                (dir_ / "ref.csv").string(), "--out", (dir_ / "drive.csv").string(),
                "--check-model", (dir_ / "other" / "fit.json").string()});
  PZ_EXPECT_HAS(out, "clipping: none");
  PZ_EXPECT_HAS(out, "exposure to model error: backlash-like");
  const std::vector<double> ref = Column(dir_ / "ref.csv", 1), u = Column(dir_ / "drive.csv", 1);
  const std::vector<double> y = Plant(u);
  double sse = 0;
  for (size_t k = 1; k < u.size(); ++k) sse += (y[k] - ref[k]) * (y[k] - ref[k]);
  const double rmse = std::sqrt(sse / static_cast<double>(u.size() - 1));
  // Without compensation (the drive scaled by the static gain) the loop's width shows.
  EXPECT_LT(rmse, 2 * kNoise) << out;
}

/// RMSE of (a − mean a) against (b − mean b) from sample 1 on.
double CentredRmse(const std::vector<double>& a, const std::vector<double>& b) {
  double ma = 0, mb = 0;
  for (size_t k = 1; k < a.size(); ++k) ma += a[k] / static_cast<double>(a.size() - 1);
  for (size_t k = 1; k < b.size(); ++k) mb += b[k] / static_cast<double>(b.size() - 1);
  double sse = 0;
  for (size_t k = 1; k < a.size(); ++k) sse += (a[k] - ma - b[k] + mb) * (a[k] - ma - b[k] + mb);
  return std::sqrt(sse / static_cast<double>(a.size() - 1));
}

TEST_F(Compensate, AZeroMeanReferenceIsTakenRelative) {
  // The usual form of a reference: zero-mean, ±12 um. The model's output spans about 2 … 42 um, so
  // by default (auto) the reference is taken about the training records' mean response (fit.json's
  // model.train_mean_output); the true plant on that drive follows it within the noise; the
  // prediction column is in the reference's frame.
  WriteReference(dir_ / "zero.csv", 12);
  {
    std::ifstream in(dir_ / "zero.csv");
    std::stringstream all;
    all << in.rdbuf();
    std::string text = all.str();
    std::ofstream out(dir_ / "zero.csv");
    std::istringstream lines(text);
    std::string line;
    std::getline(lines, line);
    out << line << "\n";
    while (std::getline(lines, line)) {  // less the 25 um of WriteReference
      const size_t c = line.find(',');
      out << line.substr(0, c) << "," << io::FormatNumber(std::stod(line.substr(c + 1)) - 25)
          << "\n";
    }
  }
  const std::string fit = (dir_ / "fit" / "fit.json").string(), ref = (dir_ / "zero.csv").string();
  const std::string out = Captured({"compensate", "--model", fit, "--reference", ref, "--out",
                                    (dir_ / "zero_drive.csv").string()});
  std::optional<double> train_mean;
  reports::LoadFit(fit, &train_mean);
  ASSERT_TRUE(train_mean.has_value());
  PZ_EXPECT_HAS(out, "reference relative to the training records' mean response, " +
                         FormatG(*train_mean, 4) + " um");
  PZ_EXPECT_HAS(out, "clipping: none");
  const std::vector<double> r = Column(dir_ / "zero.csv", 1);
  const std::vector<double> u = Column(dir_ / "zero_drive.csv", 1);
  const std::vector<double> predicted = Column(dir_ / "zero_drive.csv", 2);
  EXPECT_LT(CentredRmse(Plant(u), r), 2 * kNoise) << out;
  double mean = 0;  // the prediction about the reference's zero, not the model's absolute output
  for (double y : predicted) mean += y / static_cast<double>(predicted.size());
  EXPECT_LT(std::abs(mean), 2.0) << out;
  // A fit.json without the training mean (version 1, a model-only file): the model's major loop's
  // mean instead, and said so.
  std::string json = io::ReadTextFile(fit);
  const size_t at = json.find("  \"train_mean_output\": ");
  ASSERT_NE(at, std::string::npos);
  json.erase(at, json.find('\n', at) + 1 - at);
  std::ofstream(dir_ / "no_mean.json") << json;
  const std::string loop =
      Captured({"compensate", "--model", (dir_ / "no_mean.json").string(), "--reference", ref,
                "--out", (dir_ / "loop_drive.csv").string(), "--reference-zero", "mean"});
  PZ_EXPECT_HAS(loop, "reference relative to the mean of the model's major loop");
  PZ_EXPECT_HAS(loop, "(the fit.json does not carry the training records' mean)");
  // About the rest output at 50 V: the drive starts there and tracks all the same.
  const std::string rest = Captured({"compensate", "--model", fit, "--reference", ref, "--out",
                                     (dir_ / "rest_drive.csv").string(), "--reference-zero", "rest",
                                     "--rest-drive", "50"});
  PZ_EXPECT_HAS(rest, "reference relative to the model's rest output");
  PZ_EXPECT_HAS(rest, "clipping: none");
  const std::vector<double> ur = Column(dir_ / "rest_drive.csv", 1);
  EXPECT_NEAR(ur[0], 50, 1e-9);
  EXPECT_LT(CentredRmse(Plant(ur), r), 2 * kNoise) << rest;
  // Taken as the absolute output (the former behaviour, by choice): clipped, and said so.
  const std::string absolute =
      Captured({"compensate", "--model", fit, "--reference", ref, "--out",
                (dir_ / "abs_drive.csv").string(), "--reference-zero", "absolute"});
  PZ_EXPECT_HAS(absolute, "where the reference is beyond what the drive limits reach");
  PZ_EXPECT_HAS(testing::InputErrorOf([&] {
                  RunCli({"compensate", "--model", fit, "--reference", ref, "--out",
                          (dir_ / "x.csv").string(), "--reference-zero", "middle"});
                }),
                "reference-zero");
}

TEST_F(Compensate, AnUnreachableReferenceIsClippedAndReported) {
  WriteReference(dir_ / "big.csv", 60);
  const std::string out =
      Captured({"compensate", "--model", (dir_ / "fit" / "fit.json").string(), "--reference",
                (dir_ / "big.csv").string(), "--out", (dir_ / "big_drive.csv").string()});
  PZ_EXPECT_HAS(
      out, "event(s) where the reference is beyond what the drive limits reach; largest shortfall");
  PZ_EXPECT_HAS(out, " s: ");  // where
  const std::vector<double> u = Column(dir_ / "big_drive.csv", 1);
  const auto [lo, hi] = std::minmax_element(u.begin(), u.end());
  const records::ModelSpec m = reports::LoadFit((dir_ / "fit" / "fit.json").string());
  EXPECT_EQ(*hi, m.drive_max);
  EXPECT_EQ(*lo, m.drive_min);
}

TEST_F(Compensate, BadInputIsNamed) {
  WriteReference(dir_ / "deg.csv", 5, "angle_deg");
  PZ_EXPECT_HAS(
      testing::InputErrorOf([&] {
        RunCli({"compensate", "--model", (dir_ / "fit" / "fit.json").string(), "--reference",
                (dir_ / "deg.csv").string(), "--out", (dir_ / "x.csv").string()});
      }),
      "is in 'deg', the model's response is in 'um'");
  std::string json = io::ReadTextFile(dir_ / "fit" / "fit.json");
  const size_t at = json.find("\"format_version\": 2");
  ASSERT_NE(at, std::string::npos);
  std::string v3 = json;
  v3.replace(at, 19, "\"format_version\": 3");
  std::ofstream(dir_ / "v3.json") << v3;
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { reports::LoadFit((dir_ / "v3.json").string()); }),
                "format_version 3: this piezoid reads fit.json format_version 1 or 2");
  std::string renamed = json;
  const size_t w = renamed.find("\"weights\"", renamed.find("\"model\""));  // the model section's
  ASSERT_NE(w, std::string::npos);
  renamed.replace(w, 9, "\"weigths\"");
  std::ofstream(dir_ / "bad.json") << renamed;
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { reports::LoadFit((dir_ / "bad.json").string()); }),
                "weigths");
  std::string family = json;
  const size_t fam = family.find("\"family\": \"");
  ASSERT_NE(fam, std::string::npos);
  family.insert(fam + 11, "no-such-");
  std::ofstream(dir_ / "family.json") << family;
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { reports::LoadFit((dir_ / "family.json").string()); }),
                "model.family 'no-such-");
  std::ofstream(dir_ / "old.json") << "{\"model\": \"prandtl-ishlinskii\", \"params\": {}}\n";
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { reports::LoadFit((dir_ / "old.json").string()); }),
                "no format_version");
}

/// --initial-state reaches fit.json's model section and LoadFit reads it back; without the flag it
/// is auto (the default); a fit.json without the field (proto3: empty; fitted before it, centred)
/// reads as centred; bad values name the flag / field.
TEST_F(Compensate, TheInitialStateIsSavedAndLoaded) {
  EXPECT_EQ(reports::LoadFit((dir_ / "fit" / "fit.json").string()).initial_state,
            model::InitialState::kAuto);
  PZ_EXPECT_HAS(io::ReadTextFile(dir_ / "fit" / "fit.json"), "\"initial_state\": \"auto\"");
  PZ_EXPECT_HAS(io::ReadTextFile(dir_ / "fit" / "report.md"),
                "in the **auto** state (descended at a rest at the bottom");
  // backlash-like's auto is centred (records/families.cc; measured: docs/records.md).
  EXPECT_EQ(reports::LoadFit((dir_ / "other" / "fit.json").string()).initial_state,
            model::InitialState::kCentred);
  Captured({"fit", "--records", (dir_ / "rec.csv").string(), "--family", "prandtl-ishlinskii",
            "--pi-operators", "6", "--initial-state", "ascended", "--out", (dir_ / "asc").string(),
            "--no-figures", "--quiet"});
  const fs::path fit = dir_ / "asc" / "fit.json";
  EXPECT_EQ(reports::LoadFit(fit.string()).initial_state, model::InitialState::kAscended);
  const std::string report = io::ReadTextFile(dir_ / "asc" / "report.md");
  EXPECT_NE(report.find("in the **ascended** state"), std::string::npos) << report;
  std::string json = io::ReadTextFile(fit);
  const std::string field = "\"initial_state\": \"ascended\"";
  const size_t at = json.find(field);
  ASSERT_NE(at, std::string::npos) << json;
  std::string old = json;
  old.replace(at, field.size(), "\"initial_state\": \"\"");
  std::ofstream(dir_ / "no_state.json") << old;
  EXPECT_EQ(reports::LoadFit((dir_ / "no_state.json").string()).initial_state,
            model::InitialState::kCentred);
  std::string bad = json;
  bad.replace(at, field.size(), "\"initial_state\": \"upward\"");
  std::ofstream(dir_ / "bad_state.json") << bad;
  PZ_EXPECT_HAS(
      testing::InputErrorOf([&] { reports::LoadFit((dir_ / "bad_state.json").string()); }),
      "model.initial_state 'upward' is unknown (allowed: centred, descended, ascended, auto)");
  PZ_EXPECT_HAS(testing::InputErrorOf([&] {
                  RunCli({"fit", "--records", (dir_ / "rec.csv").string(), "--family",
                          "prandtl-ishlinskii", "--initial-state", "down", "--out",
                          (dir_ / "x").string(), "--no-figures", "--quiet"});
                }),
                "--initial-state 'down' is unknown (allowed: centred, descended, ascended, auto)");
  PZ_EXPECT_HAS(testing::InputErrorOf([&] {
                  RunCli({"fit", "--records", (dir_ / "rec.csv").string(), "--family", "duhem",
                          "--initial-state", "descended", "--out", (dir_ / "x").string(),
                          "--no-figures", "--quiet"});
                }),
                "--initial-state descended: family duhem starts centred");
}

TEST_F(Compensate, ReplayOfTheTrainingRecordIsNearTheNoise) {
  const std::string out = Captured({"compensate", "--model", (dir_ / "fit" / "fit.json").string(),
                                    "--replay", (dir_ / "rec.csv").string()});
  // "… through the local gain X um RMS …": the replay error in response units.
  const size_t at = out.find("through the local gain ");
  ASSERT_NE(at, std::string::npos) << out;
  const double rms = std::stod(out.substr(at + 23));
  EXPECT_LT(rms, 2 * kNoise) << out;
  EXPECT_GT(rms, 0.5 * kNoise) << out;  // the noise is in the measured response it inverts
}

/// The number after `label` in `out` (the first occurrence at or after `from`).
double NumberAfter(const std::string& out, const std::string& label, size_t from = 0) {
  const size_t at = out.find(label, from);
  if (at == std::string::npos) return NAN;
  return std::stod(out.substr(at + label.size()));
}

/// A record whose sensor reads 3 um higher (another zero, as each record of a set has): the replay
/// takes its offset as the fit does, so its drive error is the noise's, not 3 um through the gain
/// (≈ 8 V here: the error `compensate --replay` showed on every synth-stack set, whose records each
/// have their own offset).
TEST_F(Compensate, ReplayTakesEachRecordsOwnOffset) {
  const fs::path set = dir_ / "offsets";
  fs::create_directories(set);
  fs::copy_file(dir_ / "rec.csv", set / "rec.csv", fs::copy_options::overwrite_existing);
  const std::vector<double> t = Column(dir_ / "rec.csv", 0), u = Column(dir_ / "rec.csv", 1),
                            y = Plant(u);
  {
    // The same drive measured again: its own noise, the sensor's zero 3 um up.
    std::mt19937_64 rng(8);
    std::normal_distribution<double> noise(0, kNoise);
    std::ofstream shifted(set / "shifted.csv");
    shifted << "t_s,voltage_V,displacement_um\n";
    for (size_t k = 0; k < u.size(); ++k)
      shifted << io::FormatNumber(t[k]) << "," << io::FormatNumber(u[k]) << ","
              << io::FormatNumber(y[k] + 3.0 + noise(rng)) << "\n";
  }
  std::ofstream(set / "manifest.csv")
      << "record,file,role\nrec,rec.csv,train\nshifted,shifted.csv,validate\n";
  const std::string out = Captured(
      {"compensate", "--model", (dir_ / "fit" / "fit.json").string(), "--replay", set.string()});
  for (const std::string name : {"  rec (", "  shifted ("}) {
    const size_t at = out.find(name);
    ASSERT_NE(at, std::string::npos) << out;
    const double rms = NumberAfter(out, "through the local gain ", at);
    EXPECT_LT(rms, 2 * kNoise) << name << out;
    EXPECT_GT(rms, 0.5 * kNoise) << name << out;
    // The inverse on the model's own response gives the applied drive back; with noise of the
    // floor's sigma, the drive error the noise implies, which the measured one is near.
    EXPECT_LT(NumberAfter(out, "noiseless ", at), 1e-6) << name << out;
    const double ratio = NumberAfter(out, "measured ", at);
    EXPECT_GT(ratio, 0.5) << name << out;
    EXPECT_LT(ratio, 2.0) << name << out;
  }
  const size_t shifted = out.find("  shifted (");
  EXPECT_NEAR(NumberAfter(out, "record offset ", shifted) -
                  NumberAfter(out, "record offset ", out.find("  rec (")),
              3.0, 0.01)
      << out;
}

// `piezoid fit` polishes with forward differences by default (a Jacobian of p + 1 evaluations, the
// residuals at the point reused, against 2p central) and central ones once it has converged (after
// the line search of one parameter, forward throughout)
// (tests/opt/fit_test.cc for the evaluations): the same search, a fit as good; fit.json and
// report.md say which; another value is refused.
TEST_F(Compensate, FitPolishesWithForwardDifferencesByDefault) {
  Captured({"fit", "--records", (dir_ / "rec.csv").string(), "--family", "backlash-like",
            "--lm-differences", "central", "--out", (dir_ / "other-central").string(),
            "--no-figures", "--quiet"});
  const std::string fwd = io::ReadTextFile(dir_ / "other" / "fit.json");
  const std::string cen = io::ReadTextFile(dir_ / "other-central" / "fit.json");
  PZ_EXPECT_HAS(fwd, "\"lm_differences\": \"forward-central\"");
  PZ_EXPECT_HAS(cen, "\"lm_differences\": \"central\"");
  PZ_EXPECT_HAS(io::ReadTextFile(dir_ / "other" / "report.md"), "(forward-central differences)");
  auto number = [](const std::string& json, const std::string& key) {
    std::smatch m;
    EXPECT_TRUE(std::regex_search(json, m, std::regex("\"" + key + "\": ([-0-9.e+]+)"))) << key;
    return m.empty() ? -1.0 : std::stod(m[1].str());
  };
  EXPECT_EQ(number(fwd, "search_evaluations"), number(cen, "search_evaluations"));
  const double mse_fwd = number(fwd, "train_mse"), mse_cen = number(cen, "train_mse");
  EXPECT_LE(mse_fwd, 1.01 * mse_cen) << mse_fwd << " forward, " << mse_cen << " central";
  std::string refused;
  try {
    RunCli({"fit", "--records", (dir_ / "rec.csv").string(), "--family", "backlash-like",
            "--lm-differences", "sideways", "--out", (dir_ / "bad").string(), "--no-figures",
            "--quiet"});
  } catch (const std::exception& e) {
    refused = e.what();
  }
  PZ_EXPECT_HAS(refused, "--lm-differences: sideways");
  EXPECT_FALSE(fs::exists(dir_ / "bad"));
  // One searched parameter (a linear family's delay): the line search has located it to its
  // tolerance, and `auto` polishes with forward differences throughout.
  Captured({"fit", "--records", (dir_ / "rec.csv").string(), "--family", "prandtl-ishlinskii",
            "--effects", "delay", "--out", (dir_ / "line").string(), "--no-figures", "--quiet"});
  const std::string line = io::ReadTextFile(dir_ / "line" / "fit.json");
  PZ_EXPECT_HAS(line, "\"algorithm\": \"line\"");
  PZ_EXPECT_HAS(line, "\"lm_differences\": \"forward\"");
  PZ_EXPECT_HAS(io::ReadTextFile(dir_ / "line" / "report.md"), "(forward differences)");
}

}  // namespace
}  // namespace pz::client
