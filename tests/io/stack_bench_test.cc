// The stack bench as a record set (io/records.h, the one reader): the bundled
// data/piezo-stack-bench loads as its README describes it, and malformed manifests and record files
// (written by the test into a temporary folder) are rejected with a message naming the file, the
// line and the column.
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

const fs::path kBench = fs::path(PIEZOID_DATA_DIR) / "piezo-stack-bench";

RecordReadOptions Checked() {
  RecordReadOptions o;
  o.check_stated_drive = true;
  return o;
}

TEST(PiezoStackBench, HasSixteenRecordsAtEightFrequencies) {
  const RecordSet set = LoadRecordSet(kBench, Checked());  // the drives are the stated sines
  EXPECT_EQ(set.format, "stack-bench");
  ASSERT_EQ(set.records.size(), 16u);
  const double f[] = {10, 40, 75, 125, 175, 225, 275, 340};
  for (int i = 0; i < 16; ++i) {
    const Record& r = set.records[i];
    EXPECT_EQ(r.name, "record" + std::to_string(i + 1));
    EXPECT_EQ(r.frequency_hz, f[i / 2]);
    EXPECT_EQ(r.role, i % 2 == 0 ? CaseRole::kTrain : CaseRole::kTest);
    EXPECT_EQ(r.t.size(), 12500u);
    EXPECT_EQ(r.y.size(), r.t.size());
    EXPECT_NEAR(r.dt, 2e-4, 1e-15);
    EXPECT_NEAR(r.sample_rate_hz(), 5000, 1e-6);
    EXPECT_EQ(r.u[0], 400);
    EXPECT_EQ(r.rest_samples, 1u);  // a sine from the offset
    EXPECT_EQ(r.offset_mode, OffsetMode::kFixed);
    EXPECT_EQ(r.offset, 0);
    EXPECT_EQ(r.scored(), 12500u);
  }
  EXPECT_EQ(set.WithRole(CaseRole::kTrain).size(), 8u);
  EXPECT_EQ(set.WithRole(CaseRole::kTest).size(), 8u);
  EXPECT_EQ(set.Find("record3")->Label(), "train record 'record3' (f040_train.csv, 0–2.4998 s)");
  EXPECT_EQ(set.Find("record17"), nullptr);
}

class BadRecords : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("pz_stack_records_test_" + std::to_string(::getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  void Write(const std::string& name, const std::string& text) {
    std::ofstream(dir_ / name, std::ios::binary) << text;
  }
  // A valid 10 Hz record at fs = 1 kHz, offset 400 V, A = 100 V, n samples.
  static std::string Record(int n = 20) {
    std::ostringstream os;
    os.precision(17);
    os << "t_s,voltage_V,displacement_um\n";
    for (int k = 0; k < n; ++k) {
      const double t = k * 1e-3;
      os << t << "," << 400 + 100 * std::sin(2 * std::numbers::pi * 10 * t) << "," << 20 + 0.1 * k
         << "\n";
    }
    return os.str();
  }
  static std::string Manifest(const std::string& rows) {
    return "record,frequency_Hz,offset_V,amplitude_V,file,role\n" + rows;
  }
  std::string SetError() {
    return InputErrorOf([&] { (void)LoadRecordSet(dir_, Checked()); });
  }

  fs::path dir_;
};

TEST_F(BadRecords, ValidSmallSetLoads) {
  Write("a.csv", Record());
  Write("records.csv", Manifest("1,10,400,100,a.csv,train\n2,10,400,100,a.csv,test\n"));
  const RecordSet set = LoadRecordSet(dir_, Checked());
  ASSERT_EQ(set.records.size(), 2u);
  EXPECT_NEAR(set.records[0].dt, 1e-3, 1e-15);
  EXPECT_EQ(set.records[1].role, CaseRole::kTest);
  EXPECT_EQ(set.records[1].frequency_hz, 10);
}

TEST_F(BadRecords, ManifestErrorsNameLineAndColumn) {
  Write("a.csv", Record());
  Write("records.csv", "record,frequency_Hz,offset_V,file,role\n1,10,400,a.csv,train\n");
  PZ_EXPECT_HAS(SetError(), "missing column 'amplitude_V'");
  Write("records.csv", Manifest("1,10,400,100,a.csv,train\n1,10,400,100,a.csv,test\n"));
  PZ_EXPECT_HAS(SetError(),
                "records.csv:3: column 'record' (1): duplicate record 1 (first on line 2)");
  Write("records.csv", Manifest("1,-5,400,100,a.csv,train\n"));
  PZ_EXPECT_HAS(SetError(),
                "records.csv:2: column 'frequency_Hz' (2): frequency -5 Hz must be > 0");
  Write("records.csv", Manifest("1,10,400,-1,a.csv,train\n"));
  PZ_EXPECT_HAS(SetError(), "column 'amplitude_V' (4): amplitude -1 V must be >= 0");
  Write("records.csv", Manifest("1,10,400,100,a.csv,validate\n"));
  PZ_EXPECT_HAS(SetError(), "column 'role' (6): unknown role 'validate' (expected train or test)");
  Write("records.csv", Manifest("1,10,400,100,missing.csv,train\n"));
  PZ_EXPECT_HAS(SetError(), "column 'file' (5): record file 'missing.csv' not found");
  Write("records.csv", Manifest("0,10,400,100,a.csv,train\n"));
  PZ_EXPECT_HAS(SetError(), "record number 0 must be a positive integer");
  Write("records.csv", Manifest("1,ten,400,100,a.csv,train\n"));
  PZ_EXPECT_HAS(SetError(), "records.csv:2: column 'frequency_Hz' (2)");
  Write("records.csv", Manifest(""));
  PZ_EXPECT_HAS(SetError(), "no data rows");
  fs::remove(dir_ / "records.csv");
  PZ_EXPECT_HAS(SetError(), "records.csv");
}

TEST_F(BadRecords, RecordFileErrorsNameLineAndColumn) {
  Write("records.csv", Manifest("1,10,400,100,a.csv,train\n"));
  std::string rec = Record();
  Write("a.csv", "t_s,voltage_V\n0,400\n0.001,400.6\n");
  PZ_EXPECT_HAS(SetError(), "missing column 'displacement_um'");
  Write("a.csv", "t_s,voltage_V,displacement_um\n0,400,20\n");
  PZ_EXPECT_HAS(SetError(), "1 data rows; a record needs at least 2 samples (record 1 of");
  // Non-number on line 4 (third data row), column 3.
  std::string bad = rec;
  {
    std::istringstream in(rec);
    std::string line, out;
    for (int i = 1; std::getline(in, line); ++i) {
      if (i == 4) line = line.substr(0, line.rfind(',')) + ",abc";
      out += line + "\n";
    }
    bad = out;
  }
  Write("a.csv", bad);
  PZ_EXPECT_HAS(SetError(), "a.csv:4: column 'displacement_um' (3)");
  Write("a.csv", "t_s,voltage_V,displacement_um\n0.5,400,20\n0.501,400,20\n");
  PZ_EXPECT_HAS(SetError(), "a.csv:2: column 't_s' (1): the first sample time is 0.5 s");
  Write("a.csv",
        "t_s,voltage_V,displacement_um\n0,400,20\n0.001,406.279,20\n0.0025,"
        "400.6,20\n");
  PZ_EXPECT_HAS(SetError(), "a.csv:4: column 't_s' (1): step 0.0015 s from the previous sample");
  Write("a.csv", "t_s,voltage_V,displacement_um\n0,400,20\n0.001,406.279,20\n0.001,400.6,20\n");
  PZ_EXPECT_HAS(SetError(), "a.csv:4: column 't_s' (1): time 0.001 s is not after");
  Write("a.csv", "t_s,voltage_V,displacement_um\n0,400,20\n0.001,410,20\n");
  PZ_EXPECT_HAS(SetError(),
                "a.csv:3: column 'voltage_V' (2): 410 V is not offset + A sin(2 pi f t)");
  Write("a.csv", "t_s,voltage_V,displacement_um\n0,400,nan\n0.001,406.279,20\n");
  PZ_EXPECT_HAS(SetError(), "a.csv:2: column 'displacement_um' (3)");
  // The voltage check is on request (`piezoid committee`); else the drive is the measured samples.
  Write("a.csv", "t_s,voltage_V,displacement_um\n0,400,20\n0.001,410,20\n");
  RecordReadOptions lax;
  lax.min_scored = 2;
  EXPECT_EQ(LoadRecordSet(dir_, lax).records.size(), 1u);
}

}  // namespace
}  // namespace pz::io
