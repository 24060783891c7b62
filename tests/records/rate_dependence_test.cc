// Rate dependence (model/effect_library.h `rate-dependence`, issue 22): on a real-like stack
// (synth/reallike.h, an independent plant) whose loops widen with the drive rate up to a bound,
// trained on sines at 0.5, 2 and 8 Hz, the preisach family with the effect predicts withheld sines
// at other frequencies and a chirp within 1.25 × their true noise floor, where the family alone
// does not, and the records diagnosis names rate dependence; on the same records of a plant with an
// amplifier low-pass instead, it names the low-pass. Records at one rate are refused for the
// effect, naming what is missing; the extrapolation guard flags a withheld record faster than
// training for a model with the effect.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "diagnose/diagnose.h"
#include "records/excitation.h"
#include "records/extrapolation.h"
#include "records/fit.h"
#include "synth/reallike.h"
#include "tests/records/quick_fit.h"
#include "tests/testing/expect_error.h"

namespace pz::records {
namespace {

/// Training sines at 0.5, 2 and 8 Hz (6 s each); withheld sines at 1 and 4 Hz and a chirp over
/// 0.5–8 Hz; no creep, no sensor lag (the test is about the rate).
synth::RealLikeOptions Rates(uint64_t seed) {
  synth::RealLikeOptions o;
  o.train_s = 6;
  o.withheld_s = 6;
  o.sensor.oversample = 2;
  o.sensor.lag_samples = 0;
  o.stack.everett_grid = 120;
  o.stack.creep_per_decade = 0;
  o.second_sine = o.ramp = o.reversals = false;
  o.train_frequencies_hz = {0.5, 2, 8};
  o.withheld_frequencies_hz = {1, 4};
  o.chirp = true;
  o.seed = seed;
  return o;
}

/// The set, each record scored from 1.5 s after its rest (`--settle-s 1.5`, io::SkipSettling: the
/// jump from the rest to the sine's phase is a step the recorder cannot sample, and a step's rate
/// is no drive rate).
synth::RealLikeSet Generate(const synth::RealLikeOptions& o) {
  synth::RealLikeSet s = GenerateRealLikeSet(o);
  io::SkipSettling(s.set, 1.5, 20, "settle");
  return s;
}

synth::RealLikeOptions RatePlant(uint64_t seed) {
  synth::RealLikeOptions o = Rates(seed);
  o.stack.rate_lag_v = 4;       // the bound of the lag [V]
  o.stack.rate_time_s = 0.005;  // knee at 800 V/s: 0.5 Hz below it, 8 Hz well above
  return o;
}

/// Each withheld record's RMSE / its true noise RMS, by name (the quick Preisach fit).
std::map<std::string, double> Ratios(const synth::RealLikeSet& s, std::vector<EffectKind> effects,
                                     FitResult* out = nullptr) {
  return testing::FloorRatios(s, testing::QuickPreisach(std::move(effects)), out);
}

diagnose::RecordDiagnoseOptions QuickDiagnosis() {
  diagnose::RecordDiagnoseOptions d;
  d.family = "preisach";
  d.propose = false;
  d.fit = testing::QuickPreisach({});
  return d;
}

std::string Named(const diagnose::RecordDiagnosis& d) {
  return d.named >= 0 ? EffectName(d.candidates[static_cast<size_t>(d.named)].kind) : "nothing";
}

TEST(RateDependenceTest, ThePlantsRecordsCoverRates) {
  const synth::RealLikeSet s = Generate(RatePlant(1));
  ASSERT_EQ(s.set.records.size(), 6u);
  EXPECT_EQ(s.set.records[0].name, "train-0.5hz");
  EXPECT_EQ(s.set.records[5].name, "chirp");
  const ExcitationReport rep = AnalyseExcitation(s.set);
  EXPECT_GT(rep.training.rate_span(), 8)
      << rep.training.rate_peak_lo << " … " << rep.training.rate_peak_hi;
  EXPECT_TRUE(
      RateCoverageError(s.set, std::vector<EffectKind>{EffectKind::Named("rate-dependence")})
          .empty());
}

TEST(RateDependenceTest, BringsRateDependentLoopsToTheFloorWhereTheFamilyAloneDoesNot) {
  const synth::RealLikeSet s = Generate(RatePlant(1));
  FitResult fit;
  const auto with = Ratios(s, {EffectKind::Named("rate-dependence")}, &fit);
  const auto without = Ratios(s, {});
  for (const char* name : {"sine-1hz", "sine-4hz", "chirp"}) {
    RecordProperty(std::string(name) + "_with", std::to_string(with.at(name)));
    RecordProperty(std::string(name) + "_without", std::to_string(without.at(name)));
    EXPECT_LE(with.at(name), 1.25) << name << " (family alone: " << without.at(name) << ")";
    EXPECT_GT(without.at(name), 1.25) << name;
  }
  // The bound and the knee found: r_m near 4 V, tau_r near 5 ms (the family's parameters first).
  const size_t nf = fit.params.size() - 2;
  RecordProperty("r_m", std::to_string(fit.params[nf]));
  RecordProperty("tau_r_s", std::to_string(fit.params[nf + 1]));
  EXPECT_NEAR(fit.params[nf], 4, 1.5);
  EXPECT_NEAR(fit.params[nf + 1], 0.005, 0.002);
  // Withheld records within the training's rates are not flagged; a faster one would be.
  for (const ExtrapolationCheck& c : CheckExtrapolation(s.set, fit)) {
    EXPECT_GT(c.rate_ratio, 0) << c.record;
    EXPECT_LE(c.rate_ratio, 1.5) << c.Describe("V", "um");
  }
}

TEST(RateDependenceTest, TheDiagnosisNamesRateDependence) {
  const diagnose::RecordDiagnosis d = DiagnoseRecords(Generate(RatePlant(2)).set, QuickDiagnosis());
  ASSERT_TRUE(d.significant) << d.verdict;
  EXPECT_EQ(d.verdict_kind, "effect") << d.verdict;
  EXPECT_EQ(Named(d), "rate-dependence") << d.verdict;
}

TEST(RateDependenceTest, OnAnAmplifierLowpassTheDiagnosisNamesTheLowpass) {
  synth::RealLikeOptions o = Rates(2);
  o.stack.driver_tau_s = 0.01;
  const diagnose::RecordDiagnosis d = DiagnoseRecords(Generate(o).set, QuickDiagnosis());
  ASSERT_TRUE(d.significant) << d.verdict;
  EXPECT_EQ(d.verdict_kind, "effect") << d.verdict;
  EXPECT_EQ(Named(d), "driver-lowpass") << d.verdict;
}

TEST(RateDependenceTest, RecordsAtOneRateAreRefusedAndFlagged) {
  // One sine at one amplitude and frequency for training: its half cycles all peak at one rate.
  synth::RealLikeOptions o = RatePlant(3);
  o.train_frequencies_hz.clear();
  o.chirp = false;
  o.frequency_hz = 1;
  o.withheld_frequencies_hz = {4};
  const synth::RealLikeSet s = Generate(o);
  const ExcitationReport rep = AnalyseExcitation(s.set);
  EXPECT_LT(rep.training.rate_span(), kMinRateSpan);
  bool said = false;
  for (const std::string& line : rep.training_lines)
    said = said || line.find("one rate only") != std::string::npos;
  EXPECT_TRUE(said);
  // The 4 Hz record needs rates beyond training.
  bool rate_need = false;
  for (const WithheldExcitation& w : rep.withheld)
    for (const ExcitationNeed& n : w.needs)
      rate_need = rate_need || n.kind == ExcitationNeed::Kind::kRate;
  EXPECT_TRUE(rate_need);
  const std::string e = testing::InputErrorOf(
      [&] { FitRecords(s.set, testing::QuickPreisach({EffectKind::Named("rate-dependence")})); });
  PZ_EXPECT_HAS(e, "rate-dependence");
  PZ_EXPECT_HAS(e, "cover rates");
  PZ_EXPECT_HAS(e, "several rates");
  // The diagnosis leaves it out of its default candidates.
  diagnose::RecordDiagnoseOptions d = QuickDiagnosis();
  d.fit.search.pso.particles = 6;
  d.fit.search.pso.iterations = 4;
  d.fit.lm.max_iterations = 5;
  const diagnose::RecordDiagnosis dg = DiagnoseRecords(s.set, d);
  EXPECT_FALSE(dg.candidates.empty());
  for (const auto& c : dg.candidates) EXPECT_NE(c.kind, EffectKind::Named("rate-dependence"));
}

TEST(RateDependenceTest, AWithheldRecordFasterThanTrainingIsFlagged) {
  synth::RealLikeOptions o = RatePlant(4);
  o.train_frequencies_hz = {0.5, 2};
  o.withheld_frequencies_hz = {8};
  o.chirp = false;
  const synth::RealLikeSet s = Generate(o);
  const FitResult fit =
      FitRecords(s.set, testing::QuickPreisach({EffectKind::Named("rate-dependence")}));
  const std::vector<ExtrapolationCheck> checks = CheckExtrapolation(s.set, fit);
  ASSERT_EQ(checks.size(), 1u);
  EXPECT_TRUE(checks[0].flagged) << checks[0].Describe("V", "um");
  EXPECT_GT(checks[0].rate_ratio, 3);
  PZ_EXPECT_HAS(checks[0].Describe("V", "um"), "rate-dependent lag is extrapolated");
  // Without the effect the rates do not enter the guard.
  const FitResult plain = FitRecords(s.set, testing::QuickPreisach({}));
  EXPECT_EQ(CheckExtrapolation(s.set, plain)[0].rate_ratio, 0);
}

}  // namespace
}  // namespace pz::records
