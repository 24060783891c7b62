// The engine's criteria (records/criterion.h): over a window, the costs of a records family are
// model/criteria.h's on the family's simulation, bit for bit (the committee machine's figures rest
// on it); a genome of the wrong size is an error, a diverging parameter set a named penalty; the
// window, the options and the names are checked.
#include "records/criterion.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>

#include "model/criteria.h"
#include "model/stack_models.h"
#include "records/registry.h"
#include "tests/testing/expect_error.h"

namespace pz::records {
namespace {

using pz::testing::InputErrorOf;

constexpr double kFs = 5000;

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// A sine from rest at 400 V, 1000 samples, the Bouc–Wen stack's response plus noise.
io::Record StackRecord(double f, double amp, unsigned seed) {
  io::Record r;
  r.name = "r" + std::to_string(seed);
  r.dt = 1 / kFs;
  r.offset_mode = io::OffsetMode::kFixed;
  r.rest_samples = 1;
  for (int k = 0; k < 1000; ++k) {
    r.t.push_back(k / kFs);
    r.u.push_back(400 + amp * std::sin(2 * std::numbers::pi * f * k / kFs));
  }
  r.end_scored = r.t.size();
  r.y.resize(r.u.size());
  model::SimulateStackBoucWen({0.3, 0.004, 0.002, 0.05, 400}, r.u, r.dt, r.y);
  std::mt19937 rng(seed);
  for (double& y : r.y) y += 0.02 * (rng() / 4294967296.0 - 0.5);
  return r;
}

TEST(CriterionFitness, WindowedCostsAreTheCriteriaOfTheFamilysSimulationBitForBit) {
  const io::Record a = StackRecord(40, 400, 1), b = StackRecord(60, 300, 2);
  const std::vector<const io::Record*> records{&a, &b};
  const DataScale scale = MeasureScale(records);
  const double t0 = 0.05, t1 = 0.5;  // t1 after the records' end: clipped to their last sample
  struct Case {
    std::string family;
    model::StackFamily stack;
    std::vector<double> p;
  };
  for (const Case& c :
       {Case{"stack-bouc-wen", model::StackFamily::kBoucWen, {0.3, 0.004, 0.002, 0.05, 400}},
        Case{"stack-bouc-wen", model::StackFamily::kBoucWen, {1.5, 0.02, -0.01, 0.03, 5000}},
        Case{"backlash-like", model::StackFamily::kBacklashLike, {0.012, 0.052, 0.015}}}) {
    FamilyOptions fo;
    fo.substeps = 3;
    const RecordModel model(MakeFamily(c.family, scale, fo), {}, scale);
    for (Criterion k : {Criterion::kIae, Criterion::kSse, Criterion::kRmse, Criterion::kMax}) {
      SCOPED_TRACE(c.family + " " + CriterionName(k));
      const CriterionFitness fitness(model, records, {k, t0, t1});
      double want = 0;
      for (const io::Record* r : records) {
        std::vector<double> y(r->u.size());
        model::SimulateStack(c.stack, c.p, r->u, r->dt, y, model::StackSimOptions{3});
        const double end = std::min(t1, static_cast<double>(r->t.size() - 1) * r->dt);
        switch (k) {
          case Criterion::kIae:
            want += model::Iae(r->y, y, r->dt, t0, end);
            break;
          case Criterion::kSse:
            want += model::Sse(r->y, y, r->dt, t0, end);
            break;
          case Criterion::kRmse:
            want += model::Rmse(r->y, y, r->dt, t0, end);
            break;
          case Criterion::kMax:
            want = std::max(want, model::MaxAbsError(r->y, y, r->dt, t0, end));
            break;
          default:
            break;
        }
      }
      EXPECT_TRUE(SameBits(fitness.Cost(c.p), want)) << fitness.Cost(c.p) << " vs " << want;
      opt::Genome g;
      g.reals = c.p;
      const opt::FitnessResult res = fitness.Evaluate(g);
      EXPECT_EQ(res.status, opt::FitnessStatus::kOk);
      EXPECT_TRUE(SameBits(res.cost, want));
    }
  }
}

TEST(CriterionFitness, TheDirectPathIsTheRecordModelsOutput) {
  // A record with a leading rest (50 samples at 400 V), a fitted offset and a falling response
  // (polarity −1): the windowed cost is the criterion of RecordFitness::Run's output, bit for bit.
  io::Record a = StackRecord(40, 400, 3);
  for (size_t k = 0; k < a.u.size(); ++k)
    a.u[k] =
        k < 50
            ? 400
            : 400 + 400 * std::sin(2 * std::numbers::pi * 40 * static_cast<double>(k - 50) / kFs);
  model::SimulateBacklashLike({0.01, 0.05, 0.01}, a.u, a.y);
  for (size_t k = 0; k < a.y.size(); ++k)
    a.y[k] = 7 - a.y[k] + 0.01 * std::sin(0.37 * static_cast<double>(k));
  a.rest_samples = 50;
  a.offset_mode = io::OffsetMode::kFit;
  a.first_scored = 100;
  const std::vector<const io::Record*> records{&a};
  const DataScale scale = MeasureScale(records);
  ASSERT_EQ(scale.polarity, -1);
  const RecordModel model(MakeFamily("backlash-like", scale), {}, scale);
  const std::vector<double> p{0.012, 0.052, 0.015};
  const std::vector<double> yhat = RecordFitness(model, records).Run(p).yhat[0];
  for (Criterion k : {Criterion::kIae, Criterion::kMax}) {
    const CriterionFitness f(model, records, {k, 0.03, 0.15});
    const double end = WindowEnd(a, 0.15);
    const double want = k == Criterion::kIae ? model::Iae(a.y, yhat, a.dt, 0.03, end)
                                             : model::MaxAbsError(a.y, yhat, a.dt, 0.03, end);
    EXPECT_TRUE(SameBits(f.Cost(p), want)) << f.Cost(p) << " vs " << want;
  }
}

TEST(CriterionFitness, ErrorsPenaltiesAndChecks) {
  const io::Record a = StackRecord(40, 400, 1);
  const std::vector<const io::Record*> records{&a};
  const DataScale scale = MeasureScale(records);
  const RecordModel model(MakeFamily("stack-bouc-wen", scale), {}, scale);
  const CriterionFitness iae(model, records, {Criterion::kIae, 0.05, 0.2, 1e6});
  opt::Genome g;
  g.reals = {1, 2, 3};
  const auto bad = iae.Evaluate(g);
  EXPECT_EQ(bad.status, opt::FitnessStatus::kError);
  EXPECT_EQ(bad.cost, 1e6);
  PZ_EXPECT_HAS(bad.reason, "genome has 3 reals, stack-bouc-wen has 5 parameters");
  g.reals = {3, 1e-5, -10, 0.05, 1000};  // β + γ ≪ 0: h overflows
  const auto div = iae.Evaluate(g);
  EXPECT_EQ(div.status, opt::FitnessStatus::kPenalized);
  EXPECT_EQ(div.cost, 1e6);
  g.reals = {0.3, 0.004, 0.002, 0.05, -400};  // fc < 0: invalid, named
  const auto inv = iae.Evaluate(g);
  EXPECT_EQ(inv.status, opt::FitnessStatus::kPenalized);
  PZ_EXPECT_HAS(inv.reason, "invalid parameters: ");
  // Without a window: the engine's MSE (records/fit.h), bit for bit.
  const CriterionFitness mse(model, records, {});
  const std::vector<double> p{0.3, 0.004, 0.002, 0.05, 400};
  EXPECT_TRUE(SameBits(mse.Cost(p), RecordFitness(model, records).Run(p).mse));
  PZ_EXPECT_HAS(InputErrorOf([&] {
                  CriterionFitness(model, records, {Criterion::kIae, 0.5, 0.6});
                }),
                "before the window start t0_s = 0.5 s");
  PZ_EXPECT_HAS(InputErrorOf([&] {
                  CriterionFitness(model, records, {Criterion::kIae, 0.1, 0.1});
                }),
                "must be finite and > t0_s");
  PZ_EXPECT_HAS(InputErrorOf([&] {
                  CriterionFitness(model, records, {Criterion::kSse, 0, 1, -1});
                }),
                "error_cost = -1");
  PZ_EXPECT_HAS(InputErrorOf([&] {
                  CriterionFitness(model, {}, {Criterion::kIae, 0, 1});
                }),
                "no training records");
  EXPECT_EQ(ParseCriterion("rmse"), Criterion::kRmse);
  PZ_EXPECT_HAS(InputErrorOf([] { ParseCriterion("mae"); }),
                "criterion 'mae': expected mse, iae, sse, rmse or max");
  // Window errors of one output: the samples with t0 ≤ k dt ≤ t1, and the three figures.
  std::vector<double> yhat(a.y);
  yhat[500] += 1;
  const WindowErrors w = ScoreWindow(a, yhat, 0.05, 0.2);
  EXPECT_EQ(w.samples, 750u);  // 0.05 … 0.1998 s (t1 clipped to the last sample)
  EXPECT_DOUBLE_EQ(w.sse, 1);
  EXPECT_DOUBLE_EQ(w.max_abs, 1);
  EXPECT_NEAR(w.iae, a.dt, 1e-15);
}

}  // namespace
}  // namespace pz::records
