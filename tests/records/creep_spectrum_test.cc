// Creep over decades (model/effect_library.h `creep-spectrum`, issue 22): on a real-like stack
// (synth/reallike.h, an independent plant) whose creep is logarithmic from 0.05 s to the
// training window's length, the preisach family with the creep spectrum predicts the withheld
// records near their true noise floor, where the single-relaxation `creep` does not; the spectrum's
// weights stay non-negative; trained on the major loop alone, the varying-amplitude and reversal
// records come within 1.25x the floor with the roughness penalty on the spectrum's weights (chosen
// by validation on the training record) and without it (the weights solved exactly), the Preisach
// weights under the roughness over the triangle that the validation keeps; the major loop
// identifies the creep and the lag (with an oracle's Preisach weights every withheld record is at
// the floor); a record too short for the spectrum is refused, naming what is missing (and left out
// of a diagnosis's default candidates).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <string>

#include "diagnose/diagnose.h"
#include "records/fit.h"
#include "records/nnls.h"
#include "records/registry.h"
#include "synth/reallike.h"
#include "tests/records/quick_fit.h"
#include "tests/testing/expect_error.h"

namespace pz::records {
namespace {

/// The library entry of that name (fails the test if missing).
const EffectInfo& Find(const std::vector<EffectInfo>& lib, const std::string& name) {
  const auto it =
      std::find_if(lib.begin(), lib.end(), [&](const EffectInfo& e) { return e.name == name; });
  if (it == lib.end()) throw std::logic_error("no records effect " + name);
  return *it;
}

/// A small set: 12 s of training, 8 s withheld records, log creep of 3 % per decade from 0.05 to
/// 12 s, no sensor lag (the test is about the creep). Trained on a sine whose amplitude swings
/// between 10 % and 100 % of the major loop's (the minor loops are taught, not extrapolated: the
/// gap left is the creep's).
synth::RealLikeOptions Small(uint64_t seed) {
  synth::RealLikeOptions o;
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
std::map<std::string, double> Ratios(const synth::RealLikeSet& s, std::vector<EffectKind> effects,
                                     FitResult* out = nullptr) {
  return testing::FloorRatios(s, testing::QuickPreisach(std::move(effects)), out);
}

TEST(CreepSpectrumTest, BringsLogCreepToTheFloorWhereOneRelaxationDoesNot) {
  const synth::RealLikeSet s = GenerateRealLikeSet(Small(3));
  FitResult spectrum_fit;
  const auto spectrum = Ratios(s, {EffectKind::Named("creep-spectrum")}, &spectrum_fit);
  const auto single = Ratios(s, {EffectKind::Named("creep")});
  // What the family reaches on the same plant without creep (same drives and noise): the reversal
  // record's depths are partly beyond what 12 s of training teach (an excitation gap, not creep).
  synth::RealLikeOptions o = Small(3);
  o.stack.creep_per_decade = 0;
  const auto no_creep = Ratios(synth::GenerateRealLikeSet(o), {});
  // Relaxations 0.05 s … 12 s, two per decade: 0.05, 0.124, …, 12 s.
  ASSERT_EQ(spectrum_fit.params.size(), 6u);
  for (double w : spectrum_fit.params) EXPECT_GE(w, 0);
  for (const char* name : {"played", "ramp", "reversals"}) {
    RecordProperty(std::string(name) + "_creep_spectrum", std::to_string(spectrum.at(name)));
    RecordProperty(std::string(name) + "_creep", std::to_string(single.at(name)));
    RecordProperty(std::string(name) + "_plant_without_creep", std::to_string(no_creep.at(name)));
    // The creep is explained: what is left is the family's own error on a plant without creep.
    EXPECT_LE(spectrum.at(name), std::max(1.25, 1.1 * no_creep.at(name)))
        << name << " (one relaxation: " << single.at(name) << ", no creep: " << no_creep.at(name)
        << ")";
    // One relaxation cannot follow a creep spread over decades.
    EXPECT_GT(single.at(name), 1.25) << name;
    EXPECT_GT(single.at(name), 1.3 * spectrum.at(name)) << name;
  }
  EXPECT_LE(spectrum.at("played"), 1.25);
  EXPECT_LE(spectrum.at("ramp"), 1.25);
}

TEST(CreepSpectrumTest, AMajorLoopFitExtrapolatesToTheMinorLoopsWithinTheTarget) {
  // Trained on the major loop only (a 40 s constant-amplitude sine: what a user has), with the
  // sensor's lag: the set of `piezoid synth-stack --seed 4` (docs/real-recording.md).
  synth::RealLikeOptions o;
  o.seed = 4;
  synth::RealLikeSet s = GenerateRealLikeSet(o);
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
    for (size_t i = 0; i < s.set.records.size(); ++i)
      out[s.set.records[i].name] = r.metrics[i].rmse / s.truth[i].noise_rms_um;
    return out;
  };
  const FitResult penalised = FitRecords(s.set, f);
  f.spectrum_roughness = false;
  const FitResult ragged = FitRecords(s.set, f);
  const auto with = ratios(penalised), without = ratios(ragged);
  ASSERT_TRUE(penalised.spectrum_regularisation.used);
  EXPECT_EQ(penalised.spectrum_regularisation.cv_rmse.size(),
            penalised.spectrum_regularisation.relatives.size());
  EXPECT_GT(penalised.spectrum_regularisation.lambda, 0);
  const auto [first, count] = penalised.model->EffectParams(EffectKind::Named("creep-spectrum"));
  ASSERT_GT(count, 3u);
  for (size_t i = first; i < first + count; ++i) EXPECT_GE(penalised.params[i], 0);
  for (const char* name : {"major", "major-2", "ramp", "reversals"}) {
    RecordProperty(std::string(name) + "_penalised", std::to_string(with.at(name)));
    RecordProperty(std::string(name) + "_unpenalised", std::to_string(without.at(name)));
    std::cout << name << ": " << with.at(name) << " x the floor (unpenalised " << without.at(name)
              << ")\n";
  }
  // The training excitation still fits at the floor.
  EXPECT_LE(with.at("major"), 1.1);
  EXPECT_LE(with.at("major-2"), 1.1);
  // The varying-amplitude and reversal records: within the 1.25x of the floor (1.17x /
  // 1.14x): the Preisach weights' penalty kept is the roughness over the triangle, which fills in
  // the interior the major loop does not identify from its branches (with the roughness along the
  // centre, the only one before: 1.47x / 1.64x). The spectrum is solved with the Preisach weights
  // (records/spectrum_solve.h), so the unpenalised fit is the exact optimum, not the ragged
  // spectrum a search of the weights used to stop at (fast relaxations at their bound standing in
  // for the loop's shape and the lag: 2.7x the floor on the reversals, seed 4): it extrapolates as
  // well, and the spectrum's penalty (chosen by the blocks, which cannot tell the two apart) costs
  // the withheld records nothing.
  EXPECT_EQ(penalised.regularisation.penalty_name, "roughness over the triangle");
  for (const char* name : {"ramp", "reversals"}) {
    EXPECT_LE(with.at(name), 1.25) << name;
    EXPECT_LE(without.at(name), 1.25) << name;
    EXPECT_LE(with.at(name), 1.05 * without.at(name)) << name;
  }
  std::cout << penalised.spectrum_regularisation.Describe() << "\n";
}

/// Each record's RMSE / its true noise RMS for a model with given parameters and family weights.
std::map<std::string, double> RatiosOf(const synth::RealLikeSet& s, const RecordModel& model,
                                       const std::vector<double>& p,
                                       const std::vector<double>& weights) {
  std::map<std::string, double> out;
  for (size_t i = 0; i < s.set.records.size(); ++i)
    out[s.set.records[i].name] =
        Evaluate(model, p, weights, s.set.records[i]).rmse / s.truth[i].noise_rms_um;
  return out;
}

TEST(CreepSpectrumTest, AMajorLoopIdentifiesTheCreepTheLagAndWithTheTrianglePenaltyTheMinorLoops) {
  // The decomposition of the major-loop gap on `synth-stack --seed 1` (docs/real-recording.md,
  // "What the major loop's gap is made of"). The same plant without creep and lag (the same drives
  // and noise) gives the Preisach weights alone: fitted on every record (an oracle) the grid
  // reaches the floor; fitted on the major loop, the minor-loop records depend on how the penalty
  // fills in the interior of the triangle, which the loop's branches do not identify.
  // With those oracle weights fixed, the creep spectrum and the delay fitted on the full plant's
  // major loop bring every withheld record to the floor: the major loop identifies creep and lag;
  // what it does not identify is the interior of the Preisach triangle (the minor loops).
  synth::RealLikeOptions o;
  o.seed = 1;
  synth::RealLikeSet full = GenerateRealLikeSet(o);
  o.stack.creep_per_decade = 0;
  o.sensor.lag_samples = 0;
  synth::RealLikeSet plain = GenerateRealLikeSet(o);
  io::SkipSettling(full.set, 1.5, 100, "test");
  io::SkipSettling(plain.set, 1.5, 100, "test");
  const auto train = full.set.WithRole(model::CaseRole::kTrain);
  const DataScale scale = MeasureScale(train);  // the same drives: the same grid for both plants
  const std::shared_ptr<const Family> family = MakeFamily("preisach", scale);
  const RecordModel alone(family, {}, scale);
  // The Preisach weights from the major loop of the plant without creep and lag.
  const RecordFitness major(alone, plain.set.WithRole(model::CaseRole::kTrain));
  const auto from_major = RatiosOf(plain, alone, {}, major.Run({}).weights);
  // From every record of it: the oracle.
  std::vector<const io::Record*> every;
  for (const io::Record& r : plain.set.records) every.push_back(&r);
  const std::vector<double> oracle = RecordFitness(alone, every).Run({}).weights;
  const auto grid = RatiosOf(plain, alone, {}, oracle);
  // The oracle weights fixed; the creep spectrum's weights (non-negative least squares: the output
  // is linear in them, the record's offset centred out) and the delay (on a grid of 0.25 ms)
  // fitted on the full plant's major loop.
  const RecordModel model(family, {EffectKind::Named("creep-spectrum"), EffectKind::Named("delay")},
                          scale);
  const auto [first, count] = model.EffectParams(EffectKind::Named("creep-spectrum"));
  const size_t delay = model.EffectParams(EffectKind::Named("delay")).first;
  const io::Record& tr = *train.front();
  const size_t n = tr.scored();
  double best = std::numeric_limits<double>::infinity();
  std::vector<double> fitted;
  for (int step = 0; step <= 50; ++step) {
    std::vector<double> p(model.params().size(), 0.0);
    p[delay] = 0.00025 * step;
    std::vector<double> y0(tr.end_scored), yi(tr.end_scored);
    model.Simulate(tr, p, oracle, tr.end_scored, y0);
    Eigen::MatrixXd A(n, count);
    Eigen::VectorXd b(n);
    for (size_t i = 0; i < count; ++i) {
      std::vector<double> q = p;
      q[first + i] = 1;
      model.Simulate(tr, q, oracle, tr.end_scored, yi);
      for (size_t k = 0; k < n; ++k) A(k, i) = yi[tr.first_scored + k] - y0[tr.first_scored + k];
    }
    for (size_t k = 0; k < n; ++k) b(k) = tr.y[tr.first_scored + k] - y0[tr.first_scored + k];
    for (Eigen::Index j = 0; j < A.cols(); ++j) A.col(j).array() -= A.col(j).mean();
    b.array() -= b.mean();
    const Eigen::VectorXd w = NonNegativeLeastSquares(A.transpose() * A, A.transpose() * b);
    const double sse = (A * w - b).squaredNorm();
    if (sse < best) {
      best = sse;
      fitted = p;
      for (size_t i = 0; i < count; ++i) fitted[first + i] = w(static_cast<Eigen::Index>(i));
    }
  }
  const auto fixed = RatiosOf(full, model, fitted, oracle);
  double total = 0;
  for (size_t i = 0; i < count; ++i) total += fitted[first + i];
  for (const char* name : {"major", "major-2", "ramp", "reversals"}) {
    RecordProperty(std::string(name) + "_preisach_from_major", std::to_string(from_major.at(name)));
    RecordProperty(std::string(name) + "_oracle_grid", std::to_string(grid.at(name)));
    RecordProperty(std::string(name) + "_oracle_preisach_creep_lag_from_major",
                   std::to_string(fixed.at(name)));
    std::cout << name << ": Preisach from the major loop " << from_major.at(name)
              << ", oracle grid " << grid.at(name)
              << ", oracle Preisach with creep and lag from the major loop " << fixed.at(name)
              << " x the floor\n";
  }
  std::cout << "delay " << fitted[delay] << " s, creep weights sum " << total << "\n";
  for (const char* name : {"major", "major-2", "ramp", "reversals"}) {
    EXPECT_LE(grid.at(name), 1.05) << name;
    EXPECT_LE(fixed.at(name), 1.05) << name;
  }
  EXPECT_NEAR(fitted[delay], 1.35 / 200, 0.0005);  // truth: 1.35 samples at 200 Hz
  EXPECT_NEAR(total, 0.05, 0.01);                  // truth: 1.5 % per decade over 0.05 … 50 s
  // The minor loops from the major loop's own Preisach weights, creep and lag aside: the interior
  // of the triangle comes from the penalty the validation keeps — the roughness over the triangle
  // here (1.14x / 1.17x the floor); the roughness along the centre, the only one before, left
  // 1.76x / 1.84x.
  EXPECT_EQ(major.validation().penalty_name, "roughness over the triangle");
  for (const char* name : {"major", "major-2", "ramp", "reversals"})
    EXPECT_LE(from_major.at(name), 1.25) << name;
}

TEST(CreepSpectrumTest, ARecordTooShortForTheSpectrumIsRefused) {
  synth::RealLikeOptions o = Small(1);
  o.train_drive.clear();
  o.train_s = 0.4;
  o.withheld_s = 1;
  o.ramp = o.reversals = false;
  o.second_sine = true;  // a withheld record for the diagnosis
  const synth::RealLikeSet s = GenerateRealLikeSet(o);
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
  diagnose::RecordDiagnoseOptions d;
  d.family = "prandtl-ishlinskii";
  d.propose = false;
  d.fit.uncertainty = false;
  d.fit.search.repetitions = 1;
  d.fit.search.pso.particles = 6;
  d.fit.search.pso.iterations = 4;
  d.fit.lm.max_iterations = 5;
  const diagnose::RecordDiagnosis dg = DiagnoseRecords(s.set, d);
  EXPECT_FALSE(dg.candidates.empty());
  for (const auto& c : dg.candidates) EXPECT_NE(c.kind, EffectKind::Named("creep-spectrum"));
  d.candidates = {EffectKind::Named("creep-spectrum")};
  PZ_EXPECT_HAS(testing::InputErrorOf([&] { diagnose::DiagnoseRecords(s.set, d); }),
                "at least 0.5 s");
}

}  // namespace
}  // namespace pz::records
