// The real-like stack generator (synth/reallike.h, issue 22 item 5), checked without the
// product's families: its Preisach loops have return-point memory and wipe out minor loops; its
// creep is logarithmic; its sensor lag is the stated number of samples; the product's noise floor
// (records/noise_floor.h EstimateNoiseFloor) finds the true floor of its records; the set it writes
// reads back through io/records.h with its rest and quantum; bad input is named.
#include "synth/reallike.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "diagnose/diagnose.h"
#include "records/fit.h"
#include "tests/testing/expect_error.h"

namespace pz::records {
namespace {

/// A straight path from a to b in `n` steps (b included, a not).
void Ramp(std::vector<double>& u, double to, int n = 200) {
  const double from = u.empty() ? 0 : u.back();
  for (int k = 1; k <= n; ++k) u.push_back(from + (to - from) * k / n);
}

synth::RealLikeOptions Short(uint64_t seed) {
  synth::RealLikeOptions o;
  o.train_s = 12;
  o.withheld_s = 8;
  o.sensor.oversample = 4;
  o.seed = seed;
  return o;
}

TEST(RealLikeTest, PreisachLoopsHaveReturnPointMemory) {
  const synth::RealLikePlant plant(synth::RealLikeStack{});
  // 0 → 120 → 30 → 100, a minor loop 100 → 50 → 100, then on to 110.
  std::vector<double> u{0};
  Ramp(u, 120);
  Ramp(u, 30);
  Ramp(u, 100);
  const size_t at_a = u.size() - 1;
  Ramp(u, 50);
  const size_t at_b = u.size() - 1;
  Ramp(u, 100);
  const size_t back_at_a = u.size() - 1;
  Ramp(u, 110);
  const std::vector<double> y = plant.Static(u);
  // Return-point memory: back at the reversal point, the output is the one it left.
  EXPECT_EQ(y[back_at_a], y[at_a]);
  // Wiping-out: the path on from there is the one that never made the minor loop.
  std::vector<double> v{0};
  Ramp(v, 120);
  Ramp(v, 30);
  Ramp(v, 100);
  Ramp(v, 110);
  const std::vector<double> w = plant.Static(v);
  for (int k = 1; k <= 200; ++k)
    EXPECT_EQ(y[back_at_a + static_cast<size_t>(k)], w[at_a + static_cast<size_t>(k)]) << k;
  // The minor loop is a loop (its branches differ), and the memory is real: at 100 V, the branch
  // from below (30 V) is not the branch from above (120 V).
  EXPECT_GT(std::abs(y[at_b + 100] - y[at_a + 100]),
            0.05);  // at 75 V: rising vs falling branch of the minor loop
  std::vector<double> up{0};
  Ramp(up, 100);
  std::vector<double> down{0};
  Ramp(down, 120);
  Ramp(down, 100);
  EXPECT_GT(plant.Static(down).back() - plant.Static(up).back(), 0.5);
  // The major loop's width is a stack's (10–20 % of the stroke) and the stroke is the stated one.
  const synth::RealLikeSet s = GenerateRealLikeSet(Short(1));
  EXPECT_GT(s.major_loop_width, 0.08);
  EXPECT_LT(s.major_loop_width, 0.25);
}

TEST(RealLikeTest, RecordsKeepReturnPointMemoryWithoutCreep) {
  synth::RealLikeStack st;
  st.creep_per_decade = 0;
  const synth::RealLikePlant plant(st);
  synth::RealLikeSensor se;
  se.lag_samples = 0;
  se.oversample = 1;
  se.noise_white_um = se.noise_colored_um = se.quantum_um = se.drive_quantum_v =
      se.offset_range_um = 0;
  // A played drive: up to 140, down to 20, up to 90, minor loop to 60 and back to 90, on to 140.
  synth::RealLikeDrive d;
  d.kind = synth::RealLikeDrive::Kind::kSamples;
  d.samples_fs_hz = se.fs_hz;
  d.rest_s = 0.5;
  d.rest_level = 0;
  for (double to : {140.0, 20.0, 90.0, 60.0, 90.0, 140.0}) Ramp(d.samples, to, 100);
  d.duration_s = static_cast<double>(d.samples.size()) / se.fs_hz;
  std::vector<double> clean;
  const io::Record r = synth::SynthesizeRealLikeRecord(plant, se, d, "memory",
                                                       model::CaseRole::kTrain, 1, nullptr, &clean);
  const size_t start = r.rest_samples;  // record sample start + i is d.samples[i]
  const size_t first_90 = start + 299, second_90 = start + 499;
  ASSERT_NEAR(r.u[first_90], 90, 1e-9);
  ASSERT_NEAR(r.u[second_90], 90, 1e-9);
  EXPECT_NEAR(clean[second_90], clean[first_90], 1e-9);
  EXPECT_EQ(r.y, clean);  // no noise, no offset: the readings are the plant
}

TEST(RealLikeTest, CreepIsLogarithmicAndTheLagIsTheStatedSamples) {
  const synth::RealLikePlant plant(synth::RealLikeStack{});
  synth::RealLikeSensor se;
  se.lag_samples = 0;
  se.noise_white_um = se.noise_colored_um = se.quantum_um = se.drive_quantum_v =
      se.offset_range_um = 0;
  // A step from 0 to 100 V held 40 s: the increments per decade of time are alike (log creep).
  const auto step = [](double t) { return t < 0.5 ? 0.0 : 100.0; };
  const size_t n = static_cast<size_t>(40.5 * se.fs_hz) + 1;
  const std::vector<double> y = plant.Respond(step, n, se);
  const auto at = [&](double t) {
    return y[static_cast<size_t>(std::lround((0.5 + t) * se.fs_hz))];
  };
  const double d1 = at(1) - at(0.1), d2 = at(10) - at(1), jump = at(0.01) - y[0];
  EXPECT_GT(d1, 0);
  EXPECT_NEAR(d2 / d1, 1.0, 0.3);
  EXPECT_NEAR(d2 / jump, synth::RealLikeStack{}.creep_per_decade, 0.005);
  // Lag: two whole samples later, exactly; half a sample: between its neighbours (away from the
  // turns).
  const auto sine = [](double t) { return 75 + 60 * std::sin(2 * 3.14159265358979 * t); };
  const std::vector<double> y0 = plant.Respond(sine, 400, se);
  se.lag_samples = 2;
  const std::vector<double> y2 = plant.Respond(sine, 400, se);
  se.lag_samples = 0.5;
  const std::vector<double> yh = plant.Respond(sine, 400, se);
  for (size_t k = 3; k < 400; ++k) {
    EXPECT_EQ(y2[k], y0[k - 2]) << k;
    if (k % 100 >= 48 && k % 100 <= 52)
      continue;  // the sine's turns (samples 50, 150, …): a lagged peak
    EXPECT_GE(yh[k], std::min(y0[k], y0[k - 1]) - 1e-12) << k;
    EXPECT_LE(yh[k], std::max(y0[k], y0[k - 1]) + 1e-12) << k;
  }
}

TEST(RealLikeTest, TheProductsNoiseFloorFindsTheTruth) {
  for (uint64_t seed : {1u, 2u, 3u}) {
    const synth::RealLikeSet s = GenerateRealLikeSet(Short(seed));
    ASSERT_EQ(s.set.records.size(), 4u);
    EXPECT_NEAR(s.realised_floor_um / s.nominal_floor_um, 1, 0.1);
    const NoiseFloor nf = EstimateNoiseFloor(s.set);
    EXPECT_EQ(nf.used, "rest");
    EXPECT_NEAR(nf.sigma / s.realised_floor_um, 1, 0.15)
        << "seed " << seed << ": " << nf.sigma << " vs " << s.realised_floor_um;
    bool periods = false;
    for (const NoiseEstimate& e : nf.estimates) {
      if (e.method != "periods") continue;
      periods = true;
      EXPECT_NEAR(e.sigma / s.realised_floor_um, 1, 0.15) << "seed " << seed;
    }
    EXPECT_TRUE(periods);
  }
}

// A cross-check of two independent codes: a Preisach density that depends only on the hysteron's
// width (no centre dependence, no asymmetry, no curvature, creep or lag) is a Prandtl–Ishlinskii
// operator, so the product's prandtl-ishlinskii family, fitted on the major loop alone, must
// predict the withheld minor loops (the ramp, the reversals) near the true floor — although the
// excitation report, which knows no family, flags them. Scored from 1.5 s into each excitation: the
// two start differently (the plant rests at the bottom of its range, below every hysteron: from
// there it rises as from negative saturation; the family started centred on the rest drive does
// not, while the default state, auto, is descended there), and the first large reversal wipes the
// difference out (before it, centred, ramp and reversals differ by 1.4 and 0.6 µm RMS over the
// first 0.5 s).
/// A plant whose density depends on the width alone (a PI operator), no creep, lag or coloured
/// noise.
synth::RealLikeSet WidthOnlySet() {
  synth::RealLikeOptions o = Short(4);
  o.stack.density_center_spread = 1e3;
  o.stack.asymmetry = o.stack.quadratic = o.stack.creep_per_decade = 0;
  o.sensor.lag_samples = 0;
  o.sensor.noise_colored_um = 0;
  return synth::GenerateRealLikeSet(o);
}

TEST(RealLikeTest, AWidthOnlyDensityIsWhatThePrandtlIshlinskiiFamilyPredicts) {
  synth::RealLikeSet s = WidthOnlySet();
  for (io::Record& r : s.set.records)
    io::SetWindow(r, r.t[r.rest_samples] + 1.5, r.t.back(), 20, r.name);
  FitOptions f;
  f.family = "prandtl-ishlinskii";
  f.family_options.pi_operators = 40;
  const FitResult r = FitRecords(s.set, f);
  for (const RecordMetrics& m : r.metrics) {
    EXPECT_LT(m.rmse / s.realised_floor_um, 1.25)
        << m.name << ": " << m.rmse << " vs floor " << s.realised_floor_um;
  }
}

/// The same plant scored from the end of the rest (issue 22's initial-state defect): the plant
/// rests at the bottom of its range (below every hysteron); the family started in the descended
/// state — the state after the drive came down to the rest — matches the first 0.5 s of every
/// excitation as well as the rest of it, within 1.25 × the floor; started centred on the rest drive
/// it does not (its first 0.5 s are several times the floor: the test can fail).
TEST(RealLikeTest, TheDescendedStateMatchesTheFirstHalfSecondOfAStackRestingAtTheBottom) {
  synth::RealLikeSet s = WidthOnlySet();
  for (io::Record& r : s.set.records) io::SetWindow(r, r.t[r.rest_samples], r.t.back(), 20, r.name);
  double worst_centred = 0;
  for (model::InitialState state :
       {model::InitialState::kDescended, model::InitialState::kCentred}) {
    FitOptions f;
    f.family = "prandtl-ishlinskii";
    f.family_options.pi_operators = 40;
    f.family_options.initial_state = state;
    const FitResult r = FitRecords(s.set, f);
    for (size_t i = 0; i < s.set.records.size(); ++i) {
      const io::Record& rec = s.set.records[i];
      const double t0 = rec.t[rec.rest_samples];
      double early = 0, late = 0;
      size_t ne = 0, nl = 0;
      for (size_t k = rec.first_scored; k < rec.end_scored; ++k) {
        const double e = rec.y[k] - r.yhat[i][k], t = rec.t[k] - t0;
        if (t < 0.5) early += e * e, ++ne;
        if (t >= 1.5) late += e * e, ++nl;
      }
      ASSERT_GT(ne, 50u);
      early = std::sqrt(early / static_cast<double>(ne));
      late = std::sqrt(late / static_cast<double>(nl));
      const std::string what = rec.name + " " + model::InitialStateName(state);
      if (state == model::InitialState::kDescended) {
        EXPECT_LT(early / s.realised_floor_um, 1.25)
            << what << ": first 0.5 s " << early << ", floor " << s.realised_floor_um;
        EXPECT_LT(late / s.realised_floor_um, 1.25) << what << ": after 1.5 s " << late;
        EXPECT_LT(r.metrics[i].rmse / s.realised_floor_um, 1.25) << what;
      } else {
        worst_centred = std::max(worst_centred, early / s.realised_floor_um);
      }
    }
  }
  EXPECT_GT(worst_centred, 3)
      << "centred plays should miss the first 0.5 s of a stack resting at the bottom";
}

TEST(RealLikeTest, DeterministicAndReadBackInTheRecordFormat) {
  const synth::RealLikeSet a = GenerateRealLikeSet(Short(7)), b = GenerateRealLikeSet(Short(7)),
                           c = GenerateRealLikeSet(Short(8));
  for (size_t i = 0; i < a.set.records.size(); ++i) {
    EXPECT_EQ(a.set.records[i].y, b.set.records[i].y);
    EXPECT_EQ(a.set.records[i].u, b.set.records[i].u);
    EXPECT_NE(a.set.records[i].y, c.set.records[i].y);
  }
  const std::filesystem::path dir = std::filesystem::path(::testing::TempDir()) / "reallike_set";
  std::filesystem::remove_all(dir);
  io::WriteRecordSet(a.set, dir);
  const io::RecordSet back = io::LoadRecordSet(dir);
  ASSERT_EQ(back.records.size(), a.set.records.size());
  for (size_t i = 0; i < back.records.size(); ++i) {
    const io::Record &r = back.records[i], &o = a.set.records[i];
    EXPECT_EQ(r.name, o.name);
    EXPECT_EQ(r.role, o.role);
    EXPECT_EQ(r.rest_samples, o.rest_samples);
    EXPECT_EQ(r.first_scored, o.first_scored);
    EXPECT_EQ(r.end_scored, o.end_scored);
    EXPECT_NEAR(r.quantum, 0.02, 1e-9);
    for (size_t k = 0; k < r.size(); k += 97) EXPECT_NEAR(r.y[k], o.y[k], 1e-9);
  }
  std::filesystem::remove_all(dir);
}

TEST(RealLikeTest, BadInputIsNamed) {
  synth::RealLikeStack st;
  st.u_hi = st.u_lo;
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { synth::RealLikePlant p(st); }), "stack.u_hi");
  synth::RealLikeOptions o = Short(1);
  o.sensor.lag_samples = -1;
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { synth::GenerateRealLikeSet(o); }),
                "sensor.lag_samples");
  o = Short(1);
  o.frequency_hz = 60;
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { synth::GenerateRealLikeSet(o); }), "frequency_hz");
  synth::RealLikeDrive d;
  d.kind = synth::RealLikeDrive::Kind::kSamples;
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { synth::DriveFunction(d); }), "needs samples");
}

}  // namespace
}  // namespace pz::records
