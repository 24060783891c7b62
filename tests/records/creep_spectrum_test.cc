// Creep over decades (model/effect_library.h `creep-spectrum`, issue 22): on a real-like stack
// (records/reallike.h, an independent plant) whose creep is logarithmic from 0.05 s to the
// training window's length, the preisach family with the creep spectrum predicts the withheld
// records near their true noise floor, where the single-relaxation `creep` does not; the spectrum's
// weights stay non-negative; trained on the major loop alone, the varying-amplitude and reversal
// records stay within 2x the floor with the roughness penalty on the weights (chosen by validation
// on the training record) and without it (the weights solved exactly); a record too short for the spectrum is
// refused, naming what is missing (and left out of a diagnosis's default candidates).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <map>
#include <numbers>
#include <string>

#include "records/diagnose.h"
#include "records/fit.h"
#include "records/reallike.h"
#include "tests/records/quick_fit.h"
#include "tests/testing/expect_error.h"

namespace pz::records {
namespace {

/// The library entry of that name (fails the test if missing).
const EffectInfo& Find(const std::vector<EffectInfo>& lib, const std::string& name) {
  const auto it = std::find_if(lib.begin(), lib.end(), [&](const EffectInfo& e) { return e.name == name; });
  if (it == lib.end()) throw std::logic_error("no records effect " + name);
  return *it;
}

/// A small set: 12 s of training, 8 s withheld records, log creep of 3 % per decade from 0.05 to
/// 12 s, no sensor lag (the test is about the creep). Trained on a sine whose amplitude swings
/// between 10 % and 100 % of the major loop's (the minor loops are taught, not extrapolated: the
/// gap left is the creep's).
RealLikeOptions Small(uint64_t seed) {
  RealLikeOptions o;
  o.train_s = 12;
  o.withheld_s = 8;
  o.sensor.oversample = 2;
  o.sensor.lag_samples = 0;
  o.stack.everett_grid = 120;
  o.stack.creep_per_decade = 0.03;
  o.stack.creep_tau_max_s = 12;
  o.second_sine = false;
  o.seed = seed;
  const double fs = o.sensor.fs_hz, rest_s = 1;
  for (size_t k = 0; k < static_cast<size_t>((rest_s + o.train_s) * fs); ++k) {
    const double t = static_cast<double>(k) / fs - rest_s;
    const double a = 70 * (0.55 + 0.45 * std::cos(2 * std::numbers::pi * t / 6));
    o.train_drive.push_back(t < 0 ? 0.0 : 75 - a * std::cos(2 * std::numbers::pi * 0.8 * t));
  }
  return o;
}

/// Each withheld record's RMSE / its true noise RMS, by name (the quick Preisach fit).
std::map<std::string, double> Ratios(const RealLikeSet& s, std::vector<EffectKind> effects, FitResult* out = nullptr) {
  return testing::FloorRatios(s, testing::QuickPreisach(std::move(effects)), out);
}

TEST(CreepSpectrumTest, BringsLogCreepToTheFloorWhereOneRelaxationDoesNot) {
  const RealLikeSet s = GenerateRealLikeSet(Small(3));
  FitResult spectrum_fit;
  const auto spectrum = Ratios(s, {EffectKind::Named("creep-spectrum")}, &spectrum_fit);
  const auto single = Ratios(s, {EffectKind::Named("creep")});
  // What the family reaches on the same plant without creep (same drives and noise): the reversal
  // record's depths are partly beyond what 12 s of training teach (an excitation gap, not creep).
  RealLikeOptions o = Small(3);
  o.stack.creep_per_decade = 0;
  const auto no_creep = Ratios(GenerateRealLikeSet(o), {});
  // Relaxations 0.05 s … 12 s, two per decade: 0.05, 0.124, …, 12 s.
  ASSERT_EQ(spectrum_fit.params.size(), 6u);
  for (double w : spectrum_fit.params) EXPECT_GE(w, 0);
  for (const char* name : {"played", "ramp", "reversals"}) {
    RecordProperty(std::string(name) + "_creep_spectrum", std::to_string(spectrum.at(name)));
    RecordProperty(std::string(name) + "_creep", std::to_string(single.at(name)));
    RecordProperty(std::string(name) + "_plant_without_creep", std::to_string(no_creep.at(name)));
    // The creep is explained: what is left is the family's own error on a plant without creep.
    EXPECT_LE(spectrum.at(name), std::max(1.25, 1.1 * no_creep.at(name)))
        << name << " (one relaxation: " << single.at(name) << ", no creep: " << no_creep.at(name) << ")";
    // One relaxation cannot follow a creep spread over decades.
    EXPECT_GT(single.at(name), 1.25) << name;
    EXPECT_GT(single.at(name), 1.3 * spectrum.at(name)) << name;
  }
  EXPECT_LE(spectrum.at("played"), 1.25);
  EXPECT_LE(spectrum.at("ramp"), 1.25);
}


TEST(CreepSpectrumTest, AMajorLoopSpectrumExtrapolatesWithinTwiceTheFloor) {
  // Trained on the major loop only (a 40 s constant-amplitude sine: what a user has), with the
  // sensor's lag: the set of `piezoid synth-stack --seed 4` (docs/real-recording.md).
  RealLikeOptions o;
  o.seed = 4;
  RealLikeSet s = GenerateRealLikeSet(o);
  io::SkipSettling(s.set, 1.5, 100, "test");
  FitOptions f;
  f.family = "preisach";
  f.effects = {EffectKind::Named("creep-spectrum"), EffectKind::Named("delay")};
  f.uncertainty = false;
  f.search.repetitions = 1;
  f.search.pso.particles = 10;
  f.search.pso.iterations = 15;
  auto ratios = [&](const FitResult& r) {
    std::map<std::string, double> out;
    for (size_t i = 0; i < s.set.records.size(); ++i) out[s.set.records[i].name] = r.metrics[i].rmse / s.truth[i].noise_rms_um;
    return out;
  };
  const FitResult penalised = FitRecords(s.set, f);
  f.spectrum_roughness = false;
  const FitResult ragged = FitRecords(s.set, f);
  const auto with = ratios(penalised), without = ratios(ragged);
  ASSERT_TRUE(penalised.spectrum_regularisation.used);
  EXPECT_EQ(penalised.spectrum_regularisation.cv_rmse.size(), penalised.spectrum_regularisation.relatives.size());
  EXPECT_GT(penalised.spectrum_regularisation.lambda, 0);
  const auto [first, count] = penalised.model->EffectParams(EffectKind::Named("creep-spectrum"));
  ASSERT_GT(count, 3u);
  for (size_t i = first; i < first + count; ++i) EXPECT_GE(penalised.params[i], 0);
  for (const char* name : {"major", "major-2", "ramp", "reversals"}) {
    RecordProperty(std::string(name) + "_penalised", std::to_string(with.at(name)));
    RecordProperty(std::string(name) + "_unpenalised", std::to_string(without.at(name)));
    std::cout << name << ": " << with.at(name) << " x the floor (unpenalised " << without.at(name) << ")\n";
  }
  // The training excitation still fits at the floor.
  EXPECT_LE(with.at("major"), 1.1);
  EXPECT_LE(with.at("major-2"), 1.1);
  // The varying-amplitude and reversal records: within 2x the floor. The spectrum is solved with
  // the Preisach weights (records/spectrum_solve.h), so the unpenalised fit is the exact optimum,
  // not the ragged spectrum a search of the weights used to stop at (fast relaxations at their bound
  // standing in for the loop's shape and the lag: 2.7x the floor on the reversals, seed 4): it
  // extrapolates as well, and the penalty (chosen by the blocks, which cannot tell the two apart)
  // costs the withheld records nothing.
  for (const char* name : {"ramp", "reversals"}) {
    EXPECT_LE(with.at(name), 2.0) << name;
    EXPECT_LE(without.at(name), 2.0) << name;
    EXPECT_LE(with.at(name), 1.05 * without.at(name)) << name;
  }
  std::cout << penalised.spectrum_regularisation.Describe() << "\n";
}

TEST(CreepSpectrumTest, ARecordTooShortForTheSpectrumIsRefused) {
  RealLikeOptions o = Small(1);
  o.train_drive.clear();
  o.train_s = 0.4;
  o.withheld_s = 1;
  o.ramp = o.reversals = false;
  o.second_sine = true;  // a withheld record for the diagnosis
  const RealLikeSet s = GenerateRealLikeSet(o);
  FitOptions f;
  f.family = "prandtl-ishlinskii";
  f.effects = {EffectKind::Named("creep-spectrum")};
  const std::string e = testing::InputErrorOf([&] { FitRecords(s.set, f); });
  PZ_EXPECT_HAS(e, "creep-spectrum");
  PZ_EXPECT_HAS(e, "at least 0.5 s");
  PZ_EXPECT_HAS(e, "longest training window");
  // The library says so without throwing (a model without the effect is built as before).
  const auto lib = EffectLibrary(MeasureScale(s.set.WithRole(model::CaseRole::kTrain)));
  PZ_EXPECT_HAS(Find(lib, "creep-spectrum").unsupported, "at least 0.5 s");
  EXPECT_TRUE(Find(lib, "creep-spectrum").params.empty());
  EXPECT_TRUE(Find(lib, "creep").unsupported.empty());
  // The diagnosis's default candidates leave out what the records cannot support; named, it is
  // the same error.
  RecordDiagnoseOptions d;
  d.family = "prandtl-ishlinskii";
  d.propose = false;
  d.fit.uncertainty = false;
  d.fit.search.repetitions = 1;
  d.fit.search.pso.particles = 6;
  d.fit.search.pso.iterations = 4;
  d.fit.lm.max_iterations = 5;
  const RecordDiagnosis dg = DiagnoseRecords(s.set, d);
  EXPECT_FALSE(dg.candidates.empty());
  for (const auto& c : dg.candidates) EXPECT_NE(c.kind, EffectKind::Named("creep-spectrum"));
  d.candidates = {EffectKind::Named("creep-spectrum")};
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { DiagnoseRecords(s.set, d); }), "at least 0.5 s");
}

}  // namespace
}  // namespace pz::records
