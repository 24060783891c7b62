// Record sets of any drive (io/records.h, issue 14): the manifest format with windows, units and
// offsets; the old bench formats read as record sets; a single CSV split into windows; and bad
// records (NaN, unsorted time, mismatched units, too short, unknown roles) rejected with errors
// that name the file, the line and the column, or the record.
#include "io/records.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "tests/testing/expect_error.h"

namespace pz::io {
namespace {

namespace fs = std::filesystem;
using model::CaseRole;
using pz::testing::InputErrorOf;

class RecordsDir : public ::testing::Test {
 protected:
  void SetUp() override {
    char tmpl[] = "/tmp/pz_records_XXXXXX";
    ASSERT_NE(mkdtemp(tmpl), nullptr);
    dir_ = tmpl;
  }
  void TearDown() override { fs::remove_all(dir_); }
  void Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name) << text;
  }
  /// A 1 kHz record: 0.1 s of rest at 0 V, then a sine of 50 V at 5 Hz that starts at 1 rad,
  /// response in `unit` (0.1 µm/V, offset −1.5 µm, expressed in that unit).
  std::string RecordText(const std::string& header = "t_s,voltage_V,displacement_um",
                         double scale = 1, int n = 1000) {
    std::ostringstream s;
    s << header << "\n";
    for (int k = 0; k < n; ++k) {
      const double t = k * 1e-3;
      const double u = t < 0.1 ? 0 : 50 * std::sin(2 * std::numbers::pi * 5 * (t - 0.1) + 1);
      s << t << "," << u << "," << (0.1 * u - 1.5) * scale << "\n";
    }
    return s.str();
  }
  fs::path dir_;
};

TEST_F(RecordsDir, ManifestWithWindowsUnitsAndOffsets) {
  Write("a.csv", RecordText());
  Write("b.csv", RecordText("time_ms,drive_mV,position_nm", 1000));  // converted per column
  // b.csv's times are in ms: rewrite them.
  {
    std::ostringstream s;
    s << "time_ms,drive_mV,position_nm\n";
    for (int k = 0; k < 1000; ++k) {
      const double t = k * 1e-3;
      const double u = t < 0.1 ? 0 : 50 * std::sin(2 * std::numbers::pi * 5 * (t - 0.1) + 1);
      s << t * 1e3 << "," << u * 1e3 << "," << (0.1 * u - 1.5) * 1e3 << "\n";
    }
    Write("b.csv", s.str());
  }
  Write("manifest.csv",
        "record,file,role,t_start_s,t_end_s,offset,time_column,drive_column,response_column\n"
        "first,a.csv,train,0.2,0.6,rest,,,\n"
        "second,a.csv,validate,0.6,,-1.5,,,\n"
        "third,b.csv,test,,,fit,time_ms,drive_mV,position_nm\n");
  const RecordSet set = LoadRecordSet(dir_);
  ASSERT_EQ(set.records.size(), 3u);
  EXPECT_EQ(set.format, "manifest");
  EXPECT_EQ(set.response_unit, "um");
  const Record& a = set.records[0];
  EXPECT_EQ(a.role, CaseRole::kTrain);
  EXPECT_EQ(a.rest_samples, 100u);
  EXPECT_NEAR(a.t[a.first_scored], 0.2, 1e-12);
  EXPECT_NEAR(a.t[a.end_scored - 1], 0.6, 1e-12);
  EXPECT_EQ(a.offset_mode, OffsetMode::kRest);
  EXPECT_NEAR(a.offset, -1.5, 1e-12);  // mean over the rest
  EXPECT_EQ(set.records[1].offset_mode, OffsetMode::kFixed);
  EXPECT_EQ(set.records[1].end_scored, 1000u);
  const Record& c = set.records[2];
  EXPECT_NEAR(c.dt, 1e-3, 1e-15);
  for (size_t k = 0; k < c.size(); k += 97) {
    EXPECT_NEAR(c.u[k], a.u[k], 1e-9);
    EXPECT_NEAR(c.y[k], a.y[k], 1e-9);
  }
}

TEST_F(RecordsDir, SingleCsvSplitsIntoWindows) {
  Write("r.csv", RecordText());
  RecordSet set = LoadRecordSet(dir_ / "r.csv");
  ASSERT_EQ(set.records.size(), 1u);
  SplitIntoWindows(set, {ParseWindow("0.2:0.6", CaseRole::kTrain, "--train-window"),
                         ParseWindow("0.6:0.999", CaseRole::kValidate, "--validate-window")});
  ASSERT_EQ(set.records.size(), 2u);
  EXPECT_EQ(set.records[0].name, "train");
  EXPECT_EQ(set.records[1].role, CaseRole::kValidate);
  EXPECT_EQ(set.records[1].scored(), 400u);
  PZ_EXPECT_HAS(InputErrorOf([] { ParseWindow("7-10", CaseRole::kTrain, "--train-window"); }),
                "--train-window '7-10': expected START:END");
  RecordSet again = LoadRecordSet(dir_ / "r.csv");
  PZ_EXPECT_HAS(InputErrorOf([&] {
                  SplitIntoWindows(again, {{CaseRole::kTrain, 0.5, 2.0}});
                }),
                "train window [0.5, 2] s is outside the record (0 … 0.999 s)");
}

// The settling window (io::SkipSettling): a record is scored from settle_s after its rest, or from
// its own window's start when that is later; nothing moves at 0; too long a settle is named.
TEST_F(RecordsDir, TheSettlingWindowStartsAfterTheRest) {
  Write("a.csv", RecordText());  // rest 0 … 0.099 s, excitation from 0.1 s
  Write("manifest.csv",
        "record,file,role,t_start_s,t_end_s,offset,time_column,drive_column,response_column\n"
        "whole,a.csv,train,,,fit,,,\n"
        "late,a.csv,validate,0.5,,fit,,,\n");
  RecordSet set = LoadRecordSet(dir_);
  ASSERT_EQ(set.records[0].rest_samples, 100u);
  const size_t whole = set.records[0].first_scored, late = set.records[1].first_scored;
  SkipSettling(set, 0, 20, "--settle-s 0");
  EXPECT_EQ(set.records[0].first_scored, whole);
  SkipSettling(set, 0.25, 20, "--settle-s 0.25");
  EXPECT_NEAR(set.records[0].t[set.records[0].first_scored], 0.35,
              1e-12);                            // 0.1 s rest end + 0.25 s
  EXPECT_EQ(set.records[1].first_scored, late);  // its window starts later
  PZ_EXPECT_HAS(InputErrorOf([&] { SkipSettling(set, 0.89, 20, "--settle-s 0.89"); }),
                "--settle-s 0.89: record whole would keep 10 scored samples");
  PZ_EXPECT_HAS(InputErrorOf([&] { SkipSettling(set, -1, 20, "--settle-s -1"); }),
                "must be finite and ≥ 0");
}

// A recorder's export: no header (refused with the fix), then columns in another order with an
// empty one (found by their units).
TEST_F(RecordsDir, ColumnsAreFoundByTheirUnitsAndAMissingHeaderIsNamed) {
  std::string text = RecordText("t_s,voltage_V,displacement_um");
  std::istringstream in(text);
  std::string line, headerless, reordered = "unused,t_ms,displacement_nm,voltage_V\n";
  std::getline(in, line);
  while (std::getline(in, line)) {
    const size_t a = line.find(','), b = line.rfind(',');
    const double t = std::stod(line.substr(0, a)), u = std::stod(line.substr(a + 1, b - a - 1)),
                 y = std::stod(line.substr(b + 1));
    headerless += "," + line.substr(0, a) + "," + line.substr(b + 1) + "," +
                  line.substr(a + 1, b - a - 1) + "\n";
    reordered += "," + std::to_string(t * 1e3) + "," + std::to_string(y * 1e3) + "," +
                 std::to_string(u) + "\n";
  }
  Write("export.csv", headerless);
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_ / "export.csv"); }),
                "export.csv:1: no header line (the first line is data: ',0,-1.5,0'): add a header");
  Write("named.csv", reordered);
  const RecordSet set = LoadRecordSet(dir_ / "named.csv");
  ASSERT_EQ(set.records.size(), 1u);
  const Record& r = set.records[0];
  EXPECT_NEAR(r.dt, 1e-3, 1e-9);
  EXPECT_EQ(set.response_unit, "um");
  EXPECT_EQ(r.rest_samples, 100u);
  const size_t k = 500;
  EXPECT_NEAR(r.y[k], 0.1 * r.u[k] - 1.5, 1e-5);
  EXPECT_NEAR(r.u[k], 50 * std::sin(2 * std::numbers::pi * 5 * 0.4 + 1), 1e-4);
}

TEST_F(RecordsDir, RecorderJitterIsAcceptedButGapsAreNot) {
  std::string text = RecordText();
  Write(
      "ok.csv",
      "t_s,voltage_V,displacement_um\n0,0,1\n0.000200010001,0,1\n0.0004,0,1\n0.00059999,1,1\n" +
          [] {
            std::string s;
            for (int k = 4; k < 40; ++k) s += std::to_string(k * 2e-4) + ",1,1\n";
            return s;
          }());
  EXPECT_NO_THROW(LoadRecordSet(dir_ / "ok.csv"));
  Write(
      "gap.csv", "t_s,voltage_V,displacement_um\n0,0,1\n0.001,0,1\n0.003,1,1\n0.004,1,1\n" + [] {
        std::string s;
        for (int k = 5; k < 40; ++k) s += std::to_string(k * 1e-3) + ",1,1\n";
        return s;
      }());
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_ / "gap.csv"); }),
                "gap.csv:4: column 't_s' (1): step 0.002");
}

TEST_F(RecordsDir, BadRecordsAreNamed) {
  // NaN in the response.
  Write("nan.csv", "t_s,voltage_V,displacement_um\n0,0,1\n0.001,1,nan\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_ / "nan.csv"); }),
                "nan.csv:3: column 'displacement_um' (3)");
  // Unsorted time.
  std::string rows = "t_s,voltage_V,displacement_um\n";
  for (int k = 0; k < 30; ++k) rows += std::to_string(k == 10 ? 0.0085 : k * 1e-3) + ",1,1\n";
  Write("unsorted.csv", rows);
  PZ_EXPECT_HAS(
      InputErrorOf([&] { LoadRecordSet(dir_ / "unsorted.csv"); }),
      "unsorted.csv:12: column 't_s' (1): time 0.008500 is not after the previous 0.009000");
  // Too short.
  Write("short.csv", "t_s,voltage_V,displacement_um\n0,0,1\n0.001,1,2\n0.002,2,3\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_ / "short.csv"); }),
                "has 3 samples; at least 20 are needed (too short)");
  // A finite number that its unit's conversion takes beyond the doubles (issue 37, the reader's
  // fuzzer): named with its line and column, not read as inf.
  rows = "t_s,voltage_kV,displacement_um\n";
  for (int k = 0; k < 30; ++k)
    rows += std::to_string(k * 1e-3) + "," + (k == 5 ? "1e306" : "1") + ",1\n";
  Write("huge.csv", rows);
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_ / "huge.csv"); }),
                "huge.csv:7: column 'voltage_kV' (2): 1e306 is beyond the range of a number in V");
  Write("big.csv", RecordText("t_s,voltage_V,displacement_m"));
  Write("manifest.csv",
        "record,file,role,offset,response_column\none,big.csv,train,1e303,displacement_m\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_); }),
                "offset '1e303' is beyond the range of a number in um");
  // A unit that is not declared anywhere.
  Write("nounit.csv", "time,drive,response\n0,0,1\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_ / "nounit.csv"); }),
                "the unit of the time column 'time' is not declared");
}

TEST_F(RecordsDir, MismatchedUnitsAreNamed) {
  Write("a.csv", RecordText());
  Write("b.csv", RecordText("t_s,voltage_V,angle_deg"));
  Write("manifest.csv",
        "record,file,role,response_column\none,a.csv,train,\ntwo,b.csv,test,angle_deg\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_); }),
                "mismatched units: record 'two' has its response in deg but record 'one' in um");
  Write("manifest.csv", "record,file,role,response_unit\none,a.csv,train,nm\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_); }),
                "a.csv:1: mismatched units: column 'displacement_um' says um but manifest line 2 "
                "declares nm");
}

TEST_F(RecordsDir, BadManifestsAreNamed) {
  Write("a.csv", RecordText());
  Write("manifest.csv", "record,file,role\none,a.csv,training\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_); }),
                "manifest.csv:2: column 'role' (3): unknown role 'training'");
  Write("manifest.csv", "record,file,role\none,a.csv,train\none,a.csv,test\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_); }),
                "manifest.csv:3: column 'record' (1): duplicate record 'one'");
  Write("manifest.csv", "record,file,role\none,missing.csv,train\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_); }), "record file 'missing.csv' not found");
  Write("manifest.csv", "record,file,role,t_start_s,t_end_s\none,a.csv,train,0.5,0.51\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_); }),
                "record 'one' window [0.5, 0.51] s holds 11 samples; at least 20");
  Write("manifest.csv", "record,file,role,offset\none,a.csv,train,zero\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_); }),
                "offset 'zero' is not fit, rest or a finite number");
  Write("manifest.csv", "record,file,role,gain\none,a.csv,train,1\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_); }), "unknown column 'gain'");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_ / "nowhere"); }), "no such file or folder");
  Write("manifest.csv", "record,file,role,repeat\none,a.csv,train,run\ntwo,a.csv,test,\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_); }),
                "manifest.csv:2: repeat group 'run' has one record ('one')");
  Write("manifest.csv", "record,file,role,repeat\none,a.csv,train,a run\n");
  PZ_EXPECT_HAS(InputErrorOf([&] { LoadRecordSet(dir_); }), "repeat group 'a run' must be");
}

TEST(RecordSets, OldBenchFormatsAreReadAsRecordSets) {
  const RecordSet stack = LoadRecordSet(fs::path(PIEZOID_DATA_DIR) / "piezo-stack-bench");
  EXPECT_EQ(stack.format, "stack-bench");
  ASSERT_EQ(stack.records.size(), 16u);
  EXPECT_EQ(stack.records[0].u[0], 400);
  EXPECT_EQ(stack.WithRole(CaseRole::kTest).size(), 8u);
  const RecordSet fin = LoadRecordSet(fs::path(PIEZOID_DATA_DIR) / "bimorph-fin" / "nominal");
  EXPECT_EQ(fin.format, "bimorph-fin-bench");
  EXPECT_EQ(fin.response_unit, "deg");
  EXPECT_EQ(fin.records.size(), 9u);
}

TEST_F(RecordsDir, WrittenSetsReadBackTheSame) {
  Write("a.csv", RecordText());
  Write("manifest.csv",
        "record,file,role,t_start_s,t_end_s,repeat\none,a.csv,train,0.2,0.6,\n"
        "two,a.csv,test,0.6,,sine\nthree,a.csv,test,0.6,,sine\n");
  const RecordSet set = LoadRecordSet(dir_);
  EXPECT_EQ(set.records[0].repeat, "");
  EXPECT_EQ(set.records[1].repeat, "sine");
  WriteRecordSet(set, dir_ / "copy");
  const RecordSet back = LoadRecordSet(dir_ / "copy");
  ASSERT_EQ(back.records.size(), 3u);
  for (size_t i = 0; i < 3; ++i) {
    EXPECT_EQ(back.records[i].repeat, set.records[i].repeat);
    EXPECT_EQ(back.records[i].y, set.records[i].y);
    EXPECT_EQ(back.records[i].first_scored, set.records[i].first_scored);
    EXPECT_EQ(back.records[i].end_scored, set.records[i].end_scored);
  }
}

}  // namespace
}  // namespace pz::io
