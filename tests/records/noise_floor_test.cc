// The noise floor of a bench case (records/noise_floor.h): rounding, scatter of the last two
// cycles, saturation plateaus, on series whose answers are known in closed form. The floor of
// record sets (EstimateNoiseFloor) is tested on synthetic records in diagnose_test.cc and
// reallike_test.cc; here, its sources on small sets made for each: a rest that rings and settles,
// a hold inside a record, a repeat group, and the warning when the sources disagree.
#include "records/noise_floor.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "synth/reallike_ring.h"
#include "tests/testing/expect_error.h"
#include "tests/testing/series.h"

namespace pz::records {
namespace {

using pz::testing::Quantise;
using pz::testing::Sine;
constexpr double kQ = pz::testing::kEncoderQuantum;

TEST(NoiseFloorTest, PeriodicQuantisedRecordHasTheQuantisationFloor) {
  const CaseNoise n = EstimateCaseNoise(Quantise(Sine(600, 0.5, 2.0), kQ), 3);
  EXPECT_DOUBLE_EQ(n.quantum_deg, kQ);
  EXPECT_NEAR(n.scatter_rms_deg, 0.0, 1e-12);  // identical cycles
  EXPECT_NEAR(n.floor_rms_deg, kQ / std::sqrt(12.0), 1e-12);
}

TEST(NoiseFloorTest, FloorAddsRoundingAndScatter) {
  std::vector<double> y = Sine(300, 1.0, 2.0);
  for (size_t k = 200; k < 300; ++k) y[k] += (k % 2 ? 0.005 : -0.005);
  EXPECT_NEAR(EstimateCaseNoise(y, 3, 0.0).floor_rms_deg, 0.005, 1e-3);  // continuous: the scatter
  const CaseNoise n = EstimateCaseNoise(y, 3, kQ);
  EXPECT_NEAR(n.floor_rms_deg, std::hypot(kQ / std::sqrt(12.0), n.scatter_rms_deg), 1e-12);
}

TEST(NoiseFloorTest, ScatterSeesJitterButNotASlowTrend) {
  // Continuous data: alternating ±s jitter on the last cycle only, plus a slow drift.
  std::vector<double> y = Sine(300, 1.0, 2.0);
  for (size_t k = 0; k < y.size(); ++k) y[k] += 0.05 * k / 100.0;  // drift between cycles
  const CaseNoise clean = EstimateCaseNoise(y, 3, 0.0);
  EXPECT_LT(clean.scatter_rms_deg, 1e-4);  // the drift drops out
  for (size_t k = 200; k < 300; ++k) y[k] += (k % 2 ? 0.01 : -0.01);
  const CaseNoise jit = EstimateCaseNoise(y, 3, 0.0);
  EXPECT_NEAR(jit.scatter_rms_deg, 0.01, 2e-3);  // d has ±0.01 steps: var(Δd)/4 = 0.01²
}

TEST(NoiseFloorTest, PeriodDifferenceIsTheScatterOfAnyTwoPeriods) {
  // A periodic signal with a slow drift, ±0.01 jitter on the period starting at 120 (period 50):
  // 49 terms of (±0.02)² from the jitter alone, whatever comes before the periods compared.
  std::vector<double> y = Sine(250, 2.0, 1.5);
  for (size_t k = 0; k < y.size(); ++k) y[k] += 0.03 * k / 100.0;
  EXPECT_LT(PeriodDifferenceSquares(y, 70, 50), 1e-12);
  for (size_t k = 120; k < 170; ++k) y[k] += (k % 2 ? 0.01 : -0.01);
  EXPECT_NEAR(PeriodDifferenceSquares(y, 70, 50), 49 * 0.02 * 0.02, 1e-9);
  // The bench's scatter is the last two cycles of it.
  EXPECT_DOUBLE_EQ(EstimateCaseNoise(std::span<const double>(y).first(200), 4, 0.0).scatter_rms_deg,
                   std::sqrt(PeriodDifferenceSquares(y, 100, 50) / 49 / 4.0));
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { PeriodDifferenceSquares(y, 200, 50); }),
                "the series has 250");
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { PeriodDifferenceSquares(y, 0, 1); }),
                "periods of 1 samples");
}

TEST(NoiseFloorTest, SaturatedSamplesContributeTheirRoundingOnly) {
  CaseNoise n;
  n.quantum_deg = kQ;
  n.floor_rms_deg = 0.01;
  const std::vector<double> model = {1.0, 1.0, 1.0, 0.5, 0.2};  // first three clipped at b1 = 1
  const std::vector<double> meas = {1.0 - kQ, 1.0, 1.0 - 3 * kQ, 0.5,
                                    0.21};  // one level below; three below
  const double f = SaturationAwareFloor(n, meas, model, 1.0, -1.0);
  EXPECT_NEAR(f, std::sqrt((kQ * kQ + 0 + 3 * 0.01 * 0.01) / 5), 1e-12);
  PZ_EXPECT_HAS(pz::testing::InputErrorOf(
                    [&] { SaturationAwareFloor(n, meas, std::vector<double>{1.0}, 1.0, -1.0); }),
                "measured has 5");
}

// ---- a record set ------------------------------------------------------------------------------

constexpr double kFs = 10000;

/// A record of n samples at 10 kHz: a rest of `rest` samples at drive 0 whose response rings
/// (740 Hz, 0.4 µm decaying in 40 ms) and creeps after the step to it, then a 20 Hz sine; white
/// noise σ from `seed`, `scatter` added to the sine part only (a drive the plant does not repeat
/// exactly), `shift` added to the whole response.
io::Record Ringing(const std::string& name, size_t n, size_t rest, double sigma, uint64_t seed,
                   double scatter = 0, double shift = 0) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> g(0, 1);
  io::Record r;
  r.name = name;
  r.file = name + ".csv";
  for (size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / kFs;
    const bool at_rest = k < rest;
    const double ts = static_cast<double>(k - std::min(k, rest)) / kFs;
    r.t.push_back(t);
    r.u.push_back(at_rest ? 0 : 50 * std::sin(2 * std::numbers::pi * 20 * ts));
    double y = 0.4 * std::exp(-t / 0.04) * std::sin(2 * std::numbers::pi * 740 * t) +
               0.2 * std::exp(-t / 0.1) + 0.005 * std::log10(1 + t / 0.01);
    if (!at_rest) y += 2 * r.u.back() / 50 + scatter * std::sin(2 * std::numbers::pi * 4 * ts);
    r.y.push_back(y + shift + sigma * g(rng));
  }
  r.dt = 1 / kFs;
  r.rest_samples = rest;
  r.first_scored = rest;
  r.end_scored = n;
  return r;
}

TEST(NoiseFloorSetTest, TheRestsRingingIsLeftOut) {
  const double sigma = 0.0012;
  io::RecordSet set;
  set.records.push_back(Ringing("a", 12000, 8000, sigma, 1));
  const NoiseFloor nf = EstimateNoiseFloor(set);
  ASSERT_EQ(nf.used, "rest") << nf.Summary("um");
  // The whole rest about its line would read the ringing (≈ 0.07 here); its settled part reads the
  // sensor: within 20 % (the blocks' own lines take a little of the noise; 8000 samples).
  EXPECT_NEAR(nf.sigma / sigma, 1, 0.2) << nf.Summary("um");
  PZ_EXPECT_HAS(nf.estimates.front().detail, "still ringing or settling left out");
  const SettledHold h =
      FindSettledHold(std::span<const double>(set.records[0].y).first(8000), true);
  EXPECT_GT(h.from, 800u);   // 5 decay times of the ringing: 0.2 s
  EXPECT_LT(h.from, 4000u);  // the creep's fast part is gone by 0.4 s
}

TEST(NoiseFloorSetTest, AHoldInsideARecordIsARest) {
  // No leading rest; the drive holds for 0.2 s in the middle of a sine (a ramp's pause).
  std::mt19937_64 rng(2);
  std::normal_distribution<double> g(0, 0.002);
  io::Record r;
  r.name = r.file = "hold";
  for (size_t k = 0; k < 6000; ++k) {
    r.t.push_back(static_cast<double>(k) / kFs);
    r.u.push_back(k >= 2000 && k < 4000 ? r.u[1999]
                                        : 50 * std::sin(2 * std::numbers::pi * 20 * r.t.back()));
    r.y.push_back(2 * r.u.back() / 50 + g(rng));
  }
  r.dt = 1 / kFs;
  r.end_scored = r.size();
  io::RecordSet set;
  set.records.push_back(r);
  const NoiseFloor nf = EstimateNoiseFloor(set);
  ASSERT_EQ(nf.used, "rest") << nf.Summary("um");
  EXPECT_GT(nf.estimates.front().samples, 1900u);
  EXPECT_NEAR(nf.sigma / 0.002, 1, 0.1) << nf.Summary("um");
}

TEST(NoiseFloorSetTest, ARepeatGroupIsTheFloorAndTheSensorsNoiseIsWarnedAbout) {
  // Three recordings of one drive whose responses differ by a slow 4 Hz scatter of ±0.03 (what
  // the plant does not repeat) and by their zero; the sensor's noise is 0.0012.
  io::RecordSet set;
  const double scatter[3] = {0.03, -0.01, -0.02};
  for (int i = 0; i < 3; ++i) {
    set.records.push_back(
        Ringing("run" + std::to_string(i), 9000, 4000, 0.0012, 10 + i, scatter[i], 0.5 * i));
    set.records.back().repeat = "sine-20hz";
  }
  // Each record's own file: the rest estimate sees three rests.
  const NoiseFloor nf = EstimateNoiseFloor(set);
  ASSERT_EQ(nf.used, "repeats") << nf.Summary("um");
  // Scatter about the group's mean of s_i sin(…): mean s = 0, Σ s_i² / 2 × ½ (a sine's mean
  // square), plus the sensor's noise.
  const double want =
      std::sqrt((0.03 * 0.03 + 0.01 * 0.01 + 0.02 * 0.02) / 2 / 2 + 0.0012 * 0.0012);
  EXPECT_NEAR(nf.sigma / want, 1, 0.05) << nf.Summary("um");
  PZ_EXPECT_HAS(nf.warning, "disagree");
  PZ_EXPECT_HAS(nf.warning, "repeats estimate is used");
  PZ_EXPECT_HAS(nf.Summary("um"), "rest 0.00");
  // A repeat is aligned on the drive: the third recorded 7 samples later.
  io::RecordSet late = set;
  io::Record& r = late.records[2];
  r.u.insert(r.u.begin(), 7, 0.0);
  r.y.insert(r.y.begin(), 7, r.y.front());
  r.u.resize(9000);
  r.y.resize(9000);
  EXPECT_NEAR(EstimateNoiseFloor(late).sigma / want, 1, 0.05);
  // A group of one, a drive that is not the same: named.
  io::RecordSet one = set;
  one.records[1].repeat = one.records[2].repeat = "";
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { EstimateNoiseFloor(one); }),
                "repeat group 'sine-20hz' has one record");
  io::RecordSet other = set;
  for (double& u : other.records[1].u) u *= 0.5;
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { EstimateNoiseFloor(other); }), "not a repeat");
}

// The check on the second real-like generator (synth/reallike_ring.h; never tuned on): a 10 kHz
// stage whose rests ring (740 Hz) and settle after the step to them, chatter drives recorded three
// times. The floor is the repeats' (what the stage repeats to), the rest's settled part reads the
// sensor's white noise, and the two are said to disagree.
TEST(NoiseFloorSetTest, TheRingingStagesFloorIsItsRepeatability) {
  synth::RingingOptions o = synth::RingingDefaults();
  o.rest_s = 0.4;
  o.loops_s = 0.3;
  o.chatter_s = 0.3;
  o.train_loops_hz = {20};
  o.withheld_loops_hz = {};
  for (uint64_t seed : {1u, 2u}) {
    o.seed = seed;
    const synth::RingingSet s = GenerateRingingSet(o);
    const NoiseFloor nf = EstimateNoiseFloor(s.set);
    ASSERT_EQ(nf.used, "repeats") << nf.Summary("um");
    // The wander is slow (0.1 s over 0.3 s records): a few independent values per record, so the
    // realised scatter and the truth's RMS differ by sampling; within 35 %.
    EXPECT_NEAR(nf.sigma / s.realised_floor_um, 1, 0.35) << nf.Summary("um");
    double rest = 0;
    for (const NoiseEstimate& e : nf.estimates)
      if (e.method == "rest") rest = e.sigma;
    // The rest's settled part: the white noise and a little wander (blocks of 20 ms).
    EXPECT_GT(rest, 0.8 * s.sensor_floor_um) << nf.Summary("um");
    EXPECT_LT(rest, 4 * s.sensor_floor_um) << nf.Summary("um");
    PZ_EXPECT_HAS(nf.warning, "disagree");
  }
}

}  // namespace
}  // namespace pz::records
