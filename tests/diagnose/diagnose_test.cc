// The diagnosis on record sets (diagnose/diagnose.h, issue 14), on records made by the project's
// own plants with a known withheld effect: a stack (not the bimorph grid) whose creep is named by
// the same rules; a clean stack with no gap; a low-pass bench where driver-lowpass and delay
// explain the single-frequency records equally — the verdict says the data cannot separate them and
// proposes a measurement, and that measurement, simulated from the truth and added to the records,
// separates them. The noise floor comes from the rest, the periods, or the residual, and says
// which.
#include "diagnose/diagnose.h"

#include <gtest/gtest.h>

#include <cmath>
#include <iostream>

#include "tests/testing/expect_error.h"

namespace pz::records {
namespace {

using model::CaseRole;

constexpr double kNoise = 0.02;

FitOptions Quick() {
  FitOptions o;
  o.search.repetitions = 1;
  o.search.pso.particles = 20;
  o.search.pso.iterations = 60;
  o.search.pso.stall_iterations = 20;
  o.lm.max_iterations = 30;
  return o;
}

/// A record of truth = family + effects, cut into a training and a withheld window.
void AddRecord(io::RecordSet& set, const std::string& family, std::vector<EffectKind> effects,
               std::vector<double> params, const DriveShape& d, uint64_t seed,
               const std::string& name, double split_fraction = 0.6) {
  const DataScale s = SyntheticStackScale();
  auto fam = std::shared_ptr<const Family>(MakeFamily(family, s));
  RecordModel truth(fam, std::move(effects), s);
  io::Record r =
      SynthesizeRecord(truth, params, {}, d, {-1.2, kNoise, 0.005, seed}, name, CaseRole::kTrain);
  const double t0 = r.t[r.rest_samples] + 0.2, t2 = r.t.back();
  const double t1 = t0 + split_fraction * (t2 - t0);
  io::Record train = r, withheld = r;
  train.name = name + "-train";
  io::SetWindow(train, t0, t1, 20, "train");
  withheld.name = name + "-withheld";
  withheld.role = CaseRole::kValidate;
  io::SetWindow(withheld, t1, t2, 20, "withheld");
  set.records.push_back(train);
  set.records.push_back(withheld);
}

DriveShape Sine(double f = 1, double phase = 2.2) {
  DriveShape d;
  d.amplitude = 100;
  d.frequency_hz = f;
  d.phase_rad = phase;
  d.rest_s = 0.5;
  d.duration_s = 6;
  d.fs_hz = 500;
  return d;
}

const std::vector<double> kStack = {0.3, 0.018, 0.006, 0.12, 40};

TEST(RecordDiagnosis, NamesCreepOnAStack) {
  io::RecordSet set;
  set.source = "synthetic stack with creep";
  std::vector<double> p = kStack;
  p.push_back(0.12);  // creep k_c
  p.push_back(1.5);   // creep tau_c [s]
  DriveShape d = Sine();
  d.waveform = Waveform::kMultisine;
  d.frequency_end_hz = 6;
  AddRecord(set, "stack-bouc-wen", {EffectKind::Named("creep")}, p, d, 3, "multisine");
  RecordDiagnoseOptions o;
  o.family = "stack-bouc-wen";
  o.fit = Quick();
  const RecordDiagnosis r = DiagnoseRecords(set, o);
  EXPECT_TRUE(r.significant) << r.verdict;
  EXPECT_EQ(r.noise.used, "rest");
  EXPECT_NEAR(r.noise.sigma, std::sqrt(kNoise * kNoise + 0.005 * 0.005 / 12), 0.004);
  ASSERT_GE(r.named, 0) << r.verdict;
  EXPECT_EQ(r.candidates[static_cast<size_t>(r.named)].kind, EffectKind::Named("creep"))
      << r.verdict;
  EXPECT_EQ(r.verdict_kind, "effect") << r.verdict;
  EXPECT_GT(r.confidence, 0.9) << r.verdict;
  for (const auto& c : r.candidates)
    EXPECT_NE(c.kind, EffectKind::Named("driver-lowpass"));  // the stack family has its filter
}

TEST(RecordDiagnosis, NoGapOnACleanStack) {
  io::RecordSet set;
  set.source = "synthetic clean stack";
  AddRecord(set, "stack-bouc-wen", {}, kStack, Sine(), 4, "sine");
  RecordDiagnoseOptions o;
  o.family = "stack-bouc-wen";
  o.fit = Quick();
  o.candidates = {EffectKind::Named("creep"), EffectKind::Named("delay")};
  const RecordDiagnosis r = DiagnoseRecords(set, o);
  EXPECT_FALSE(r.significant) << r.verdict;
  EXPECT_EQ(r.verdict_kind, "none");
  EXPECT_EQ(r.named, -1);
}

TEST(RecordDiagnosis, LowpassAndDelayCannotBeSeparatedUntilTheProposedMeasurement) {
  // backlash-like + driver low-pass τ = 10 ms, driven like the fin bench: a sine from phase zero.
  const std::vector<double> truth = {0.02, 0.1, 0.05, 0.01};
  io::RecordSet set;
  set.source = "synthetic low-pass bench";
  AddRecord(set, "backlash-like", {EffectKind::Named("driver-lowpass")}, truth, Sine(1, 0), 5,
            "sine");
  RecordDiagnoseOptions o;
  o.family = "backlash-like";
  o.fit = Quick();
  o.candidates = {EffectKind::Named("driver-lowpass"), EffectKind::Named("delay")};
  const RecordDiagnosis r = DiagnoseRecords(set, o);
  ASSERT_TRUE(r.significant) << r.verdict;
  std::cout << "before: " << r.verdict << "\n";
  ASSERT_EQ(r.verdict_kind, "inseparable") << r.verdict;
  PZ_EXPECT_HAS(r.verdict, "cannot separate");
  EXPECT_LT(r.confidence, 0.98) << r.verdict;
  ASSERT_TRUE(r.next.has_value());
  EXPECT_GT(r.next->ratio_to_noise, 3) << r.next->description;

  // Measure what was proposed (simulated from the truth) and diagnose again.
  io::RecordSet more = set;
  DriveShape next = r.next->shape;
  next.rest_s = 0.5;
  next.duration_s = std::max(next.duration_s, 4.0);
  AddRecord(more, "backlash-like", {EffectKind::Named("driver-lowpass")}, truth, next, 6,
            "proposed", 0.5);
  const RecordDiagnosis again = DiagnoseRecords(more, o);
  std::cout << "after: " << again.verdict << "\n";
  ASSERT_GE(again.named, 0) << again.verdict;
  EXPECT_EQ(again.candidates[static_cast<size_t>(again.named)].kind,
            EffectKind::Named("driver-lowpass"))
      << again.verdict;
  EXPECT_EQ(again.verdict_kind, "effect") << again.verdict;
  EXPECT_GT(again.confidence, 0.95) << again.verdict;
}

TEST(RecordDiagnosis, NoiseFloorFromPeriodsWithoutRest) {
  io::RecordSet set;
  set.source = "periodic";
  DriveShape d = Sine(2, 0);
  d.rest_s = 0;
  AddRecord(set, "backlash-like", {}, {0.02, 0.1, 0.05}, d, 8, "periodic");
  const NoiseFloor nf = EstimateNoiseFloor(set);
  EXPECT_EQ(nf.used, "periods");
  EXPECT_NEAR(nf.sigma, std::sqrt(kNoise * kNoise + 0.005 * 0.005 / 12), 0.004);
}

TEST(RecordDiagnosis, NeedsAWithheldRecord) {
  io::RecordSet set;
  set.source = "only-train";
  AddRecord(set, "backlash-like", {}, {0.02, 0.1, 0.05}, Sine(), 9, "a");
  set.records.pop_back();
  RecordDiagnoseOptions o;
  o.fit = Quick();
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { DiagnoseRecords(set, o); }),
                "no withheld record or window");
}

}  // namespace
}  // namespace pz::records
