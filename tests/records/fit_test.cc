// Identification of every plant family on records shaped like a real recording (records/fit.h,
// issue 14): a rest segment, a drive that starts at an arbitrary phase, a response offset, noise
// and quantisation — and on a multisine record. The records are made by the project's own plants
// (synth/synthetic.h) with known parameters; each family must explain the withheld window down
// to the noise (RMSE < 1.5 × the noise floor) and the result must not depend on the thread count.
#include "records/fit.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>

#include "model/bimorph.h"
#include "records/nnls.h"
#include "records/registry.h"
#include "synth/synthetic.h"
#include "tests/testing/expect_error.h"

namespace pz::records {
namespace {

using model::CaseRole;

struct Case {
  std::string family;
  std::vector<double> truth;
  double amplitude = 100, bias = 0, frequency = 1;
  double gain_hint = 0.1;
};

DataScale TruthScale(const Case& c) {
  DataScale s;
  s.u_min = c.bias - c.amplitude;
  s.u_max = c.bias + c.amplitude;
  s.u_half = c.amplitude;
  s.y_half = c.amplitude * c.gain_hint;
  s.gain = c.gain_hint;
  s.f_dom = c.frequency;
  s.fs = 1000;
  s.duration = 3;
  return s;
}

constexpr double kNoise = 0.02, kQuantum = 0.01;
const double kFloor = std::sqrt(kNoise * kNoise + kQuantum * kQuantum / 12);

/// One record of the truth cut into a training window and a withheld window.
io::RecordSet MakeSet(const Case& c, synth::Waveform w, uint64_t seed) {
  const DataScale scale = TruthScale(c);
  auto fam = std::shared_ptr<const Family>(MakeFamily(c.family, scale));
  RecordModel truth(fam, {}, scale);
  synth::DriveShape d;
  d.waveform = w;
  d.amplitude = c.amplitude;
  d.bias = c.bias;
  d.frequency_hz = c.frequency;
  d.frequency_end_hz = 8 * c.frequency;
  d.phase_rad = 1.9;  // starts abruptly mid-cycle
  d.rest_s = 0.4;
  d.duration_s = 5.6;
  d.fs_hz = 1000;
  d.seed = seed;
  synth::Measurement m{-1.7, kNoise, kQuantum, seed};
  std::vector<double> weights;
  std::vector<double> params = c.truth;
  if (fam->linear()) {
    weights = c.truth;
    params.clear();
  }
  io::Record r = synth::SynthesizeRecord(truth, params, weights, d, m, "rec", CaseRole::kTrain);
  io::RecordSet set;
  set.source = "synthetic";
  set.format = "synthetic";
  io::Record train = r, validate = r;
  io::SetWindow(train, 0.6, 3.6, 20, "train");
  validate.name = "withheld";
  validate.role = CaseRole::kValidate;
  io::SetWindow(validate, 3.6, 6.0, 20, "withheld");
  set.records = {train, validate};
  return set;
}

FitOptions QuickOptions(const std::string& family) {
  FitOptions o;
  o.family = family;
  o.search.repetitions = 1;
  o.search.pso.particles = 24;
  o.search.pso.iterations = 80;
  o.search.pso.stall_iterations = 25;
  o.lm.max_iterations = 40;
  if (family == "bimorph-fin" ||
      family == "bw-oscillator") {  // more parameters, resonances: a wider search
    o.search.repetitions = 3;
    o.search.pso.particles = 30;
    o.search.pso.iterations = 150;
  }
  return o;
}

std::vector<Case> Cases() {
  std::vector<double> pi = {0.05};
  for (int i = 0; i < 12; ++i) pi.push_back(i % 3 == 0 ? 0.0 : 0.01 + 0.002 * i);
  return {
      {"stack-bouc-wen", {0.3, 0.018, 0.006, 0.12, 40}},
      {"backlash-like", {0.02, 0.1, 0.05}},
      {"duhem", {0.02, 0.1, -2e-6, 0.05, 2.0}},
      {"prandtl-ishlinskii", pi},
      {"bw-oscillator", {0.1, 30, 0.3, 0.4, 0.15, -0.05}},
      {"bimorph-fin",
       {95, 0.1, 2.5e-3, 6e-3, 4e-3, 0.1, 0.15, 12, 12, 2.0, 0.07, 0.02},
       375,
       0,
       0.5,
       0.5},
  };
}

class FamilyFit : public ::testing::TestWithParam<std::tuple<int, synth::Waveform>> {};

TEST_P(FamilyFit, ExplainsTheWithheldWindowDownToTheNoise) {
  const Case c = Cases()[static_cast<size_t>(std::get<0>(GetParam()))];
  const synth::Waveform w = std::get<1>(GetParam());
  const io::RecordSet set = MakeSet(c, w, 11);
  const FitResult r = FitRecords(set, QuickOptions(c.family));
  ASSERT_EQ(r.metrics.size(), 2u);
  EXPECT_LT(r.metrics[0].rmse, 1.5 * kFloor)
      << c.family << " " << synth::WaveformName(w) << " train";
  EXPECT_LT(r.metrics[1].rmse, 1.5 * kFloor)
      << c.family << " " << synth::WaveformName(w) << " withheld";
  EXPECT_NEAR(r.metrics[1].offset, -1.7, 0.2);
  EXPECT_LT(r.metrics[1].nrmse_pct, 1.0);
}

INSTANTIATE_TEST_SUITE_P(Families, FamilyFit,
                         ::testing::Combine(::testing::Range(0, 6),
                                            ::testing::Values(synth::Waveform::kSine,
                                                              synth::Waveform::kMultisine)),
                         [](const auto& info) {
                           std::string n =
                               Cases()[static_cast<size_t>(std::get<0>(info.param))].family + "_" +
                               synth::WaveformName(std::get<1>(info.param));
                           for (char& ch : n)
                             if (ch == '-') ch = '_';
                           return n;
                         });

// A quasi-static drive (0.5 Hz, far below the fin's first mode at 81 Hz) cannot tell the beam's
// lengths from the gains; a sweep through the first mode identifies the geometry as far as one
// mode can: the first natural frequency of the identified lengths is the truth's. (The two
// lengths separately need a second mode in the record: one frequency fixes one combination.)
TEST(RecordFit, TheFinGeometryIsIdentifiedFromASweepThroughItsFirstMode) {
  Case c = Cases()[5];
  ASSERT_EQ(c.family, "bimorph-fin");
  c.truth[0] = 5;     // μ [1/s] and δ [s]: a lightly damped first mode (ζ ≈ 3 %), visible in
  c.truth[1] = 1e-4;  // the response (the grid's δ = 0.1 s overdamps it: ζ ≈ 25)
  DataScale scale = TruthScale(c);
  scale.f_dom = 60;
  scale.fs = 2000;
  auto fam = std::shared_ptr<const Family>(MakeFamily(c.family, scale));
  ASSERT_EQ(fam->params().size(), 12u);
  EXPECT_EQ(fam->params()[10].name, "active_length");
  EXPECT_EQ(fam->params()[11].name, "tip_length");
  RecordModel truth(fam, {}, scale);
  synth::DriveShape d;
  d.waveform = synth::Waveform::kSweep;
  d.amplitude = c.amplitude;
  d.bias = c.bias;
  d.frequency_hz = 20;
  d.frequency_end_hz = 160;
  d.phase_rad = 0.7;
  d.rest_s = 0.1;
  d.duration_s = 2.1;
  d.fs_hz = 2000;
  d.seed = 5;
  io::Record r =
      synth::SynthesizeRecord(truth, c.truth, {}, d, synth::Measurement{-1.7, kNoise, kQuantum, 5},
                              "sweep", CaseRole::kTrain);
  io::RecordSet set;
  set.source = "synthetic";
  set.records = {r};
  FitOptions o = QuickOptions(c.family);
  const FitResult f = FitRecords(set, o);
  EXPECT_LT(f.metrics[0].rmse, 1.5 * kFloor);
  auto first_mode_hz = [](double lp, double le) {
    model::BeamGeometry g;
    g.active_length_m = lp;
    g.tip_length_m = le;
    return model::BimorphPlant(g).modal().omega[0] / (2 * std::numbers::pi);
  };
  const double f1 = first_mode_hz(c.truth[10], c.truth[11]);
  EXPECT_NEAR(f1, 80.9, 0.1);
  EXPECT_NEAR(first_mode_hz(f.params[10], f.params[11]), f1, 0.01 * f1);
  const double nominal = first_mode_hz(0.085, 0.017);  // the search started around this one
  EXPECT_GT(std::abs(nominal - f1), 0.2 * f1);
}

TEST(RecordFit, SameResultOnOneAndTwoThreads) {
  const Case c = Cases()[1];
  const io::RecordSet set = MakeSet(c, synth::Waveform::kSine, 3);
  FitOptions o = QuickOptions(c.family);
  o.threads = 1;
  const FitResult a = FitRecords(set, o);
  o.threads = 2;
  const FitResult b = FitRecords(set, o);
  EXPECT_EQ(a.params, b.params);
  EXPECT_EQ(a.train_mse, b.train_mse);
}

TEST(RecordFit, EvaluationsSideBySideAreTheSameBitForBit) {
  // The bw-oscillator runs up to four parameter sets at once (Family::lanes,
  // model::SimulateBwMany): each result is Evaluate's, bit for bit, for points in the box, a point
  // outside (m <= 0 after the scaling: NaN alone) and one that diverges — alone and with effects:
  // drive effects give each genome its own drive (Family::SimulateMany), output effects act on each
  // lane's output; a family without lanes and a pair of odd sizes take Evaluate one by one. (The
  // thread pool's groups: tests/opt/ga_test.cc.)
  const Case c = Cases()[4];
  const io::RecordSet set = MakeSet(c, synth::Waveform::kSine, 5);
  const auto train = set.WithRole(CaseRole::kTrain);
  const DataScale scale = MeasureScale(train);
  std::vector<std::vector<double>> family(6);
  family[0] = c.truth;
  family[1] = {0.12, 25, 0.5, 0.2, 0.3, 0.01};
  family[2] = {0.1, 30, 0.3, 0.4, 0.15, -0.05};
  family[3] = {-0.1, 30, 0.3, 0.4, 0.15, -0.05};  // K < 0: m < 0, invalid
  family[4] = {0.1, 30, 0.3, 0.4, -50, -50};      // β·γ + β·δ ≪ 0: z grows without bound
  family[5] = {0.1, 40, 0.2, 0.3, 0.2, 0.1};
  for (const char* effects :
       {"", "delay", "creep", "creep-spectrum,delay", "quadratic-drive,drift"}) {
    SCOPED_TRACE(effects);
    std::vector<EffectKind> kinds;
    for (std::string_view e = effects; !e.empty();) {
      const size_t comma = std::min(e.find(','), e.size());
      kinds.push_back(ParseEffect(e.substr(0, comma)));
      e.remove_prefix(std::min(comma + 1, e.size()));
    }
    const RecordModel model(MakeFamily(c.family, scale), kinds, scale);
    const RecordFitness fitness(model, train);
    ASSERT_EQ(fitness.lanes(), 4);
    // Each genome's effects at its own point of their box (so each lane has its own drive).
    std::vector<opt::Genome> g(family.size());
    for (size_t a = 0; a < g.size(); ++a) {
      g[a].reals = family[a];
      for (size_t i = model.family_param_count(); i < model.params().size(); ++i) {
        const ParamInfo& q = model.params()[i];
        const double f = 0.15 + 0.13 * static_cast<double>(a);
        g[a].reals.push_back(q.log_scale ? q.lower * std::pow(q.upper / q.lower, f)
                                         : q.lower + f * (q.upper - q.lower));
      }
    }
    auto check = [&](std::vector<const opt::Genome*> group) {
      std::vector<opt::FitnessResult> out(group.size());
      fitness.EvaluateMany(group, out);
      for (size_t l = 0; l < group.size(); ++l) {
        const opt::FitnessResult want = fitness.Evaluate(*group[l]);
        EXPECT_EQ(out[l].status, want.status)
            << group.size() << " lanes, genome " << group[l] - g.data();
        EXPECT_EQ(std::bit_cast<uint64_t>(out[l].cost), std::bit_cast<uint64_t>(want.cost))
            << group.size() << " lanes, genome " << group[l] - g.data();
      }
    };
    for (size_t a = 0; a < g.size(); ++a) {
      for (size_t b = 0; b < g.size(); ++b) check({&g[a], &g[b]});
      // Groups of three (a pair and one alone) and four (two vector chains), with and without the
      // invalid and the diverging genome.
      check({&g[a], &g[(a + 1) % 6], &g[(a + 2) % 6]});
      check({&g[a], &g[(a + 1) % 6], &g[(a + 2) % 6], &g[(a + 5) % 6]});
    }
    EXPECT_EQ(fitness.Evaluate(g[4]).status, opt::FitnessStatus::kPenalized);
    EXPECT_NE(fitness.Evaluate(g[1]).cost, fitness.Evaluate(g[2]).cost);
  }
  const RecordModel plain(MakeFamily("backlash-like", scale), {}, scale);
  EXPECT_EQ(RecordFitness(plain, train).lanes(), 1);
}

TEST(RecordFit, ALinearFamilysOutputFromItsSolveIsSimulatesBitForBit) {
  // RecordFitness::Run keeps the regressors of the weights' solve for the output (no second
  // regressor pass); with a delay or a creep of the drive, the output is what RecordModel::Simulate
  // gives for the solved weights, bit for bit.
  const Case c = Cases()[3];
  const io::RecordSet set = MakeSet(c, synth::Waveform::kSine, 7);
  const auto train = set.WithRole(CaseRole::kTrain);
  const DataScale scale = MeasureScale(train);
  for (const char* effects : {"delay", "creep"}) {
    SCOPED_TRACE(effects);
    const RecordModel model(MakeFamily("preisach", scale), {ParseEffect(effects)}, scale);
    const RecordFitness fitness(model, train);
    std::vector<double> p;
    for (const ParamInfo& q : model.params()) p.push_back(q.lower + 0.3 * (q.upper - q.lower));
    const RecordFitness::Output out = fitness.Run(p);
    ASSERT_EQ(out.yhat.size(), train.size());
    for (size_t i = 0; i < train.size(); ++i) {
      std::vector<double> y(train[i]->end_scored);
      model.Simulate(*train[i], p, out.weights, train[i]->end_scored, y);
      const int pol = model.scale().polarity;
      for (size_t k = 0; k < y.size(); ++k)
        ASSERT_EQ(std::bit_cast<uint64_t>(pol * y[k] + out.offsets[i]),
                  std::bit_cast<uint64_t>(out.yhat[i][k]))
            << k;
    }
  }
}

TEST(RecordFit, TheSizedSearchBudgetFollowsTheSearchedParametersAndFlagsWin) {
  const SearchBudget one = SizedSearchBudget(1), five = SizedSearchBudget(5),
                     twelve = SizedSearchBudget(12);
  EXPECT_EQ(one.particles, 10);
  EXPECT_EQ(one.iterations, 30);
  EXPECT_EQ(one.stall, 10);
  EXPECT_EQ(one.repetitions, 2);
  EXPECT_EQ(five.particles, 30);
  EXPECT_EQ(five.iterations, 150);
  EXPECT_EQ(five.stall, 40);
  EXPECT_EQ(five.repetitions, 3);
  EXPECT_EQ(twelve.particles, 30);
  EXPECT_EQ(twelve.converged_spread, 1e-3);
  PZ_EXPECT_HAS(one.Describe(),
                "PSO 10 particles × ≤ 30 iterations, stall 10, converged at a spread of 0.001, 2 "
                "repetitions");
  // prandtl-ishlinskii + delay searches the delay alone (its weights are solved).
  const Case c = Cases()[3];
  const io::RecordSet set = MakeSet(c, synth::Waveform::kSine, 3);
  FitOptions o = QuickOptions("prandtl-ishlinskii");
  o.effects = {ParseEffect("delay")};
  o.uncertainty = false;
  o.sizing.enabled = true;
  const FitResult sized = FitRecords(set, o);
  EXPECT_TRUE(sized.budget_sized);
  EXPECT_EQ(sized.searched_parameters, 1u);
  EXPECT_FALSE(sized.spectrum_solved);
  // One searched parameter: the line search (a grid of 17, two brackets refined), not a swarm.
  EXPECT_EQ(sized.algorithm, opt::SearchAlgorithm::kLine);
  EXPECT_EQ(sized.line.grid, 17);
  EXPECT_EQ(sized.line.brackets, 2);
  EXPECT_LE(sized.search.evaluations, 17 + 2 * 60);
  // The same optimum as the swarm's (to the polish's precision): the delay's cost is one basin.
  o.sizing.keep_particles = o.sizing.keep_repetitions = true;  // --particles 24 --repetitions 1
  const FitResult kept = FitRecords(set, o);
  EXPECT_EQ(kept.algorithm, opt::SearchAlgorithm::kPso);
  EXPECT_LE(sized.train_mse, kept.train_mse * (1 + 1e-6));
  EXPECT_NEAR(sized.params[0], kept.params[0], 1e-3 * sized.model->params()[0].upper);
  EXPECT_EQ(kept.budget.particles, 24);
  EXPECT_EQ(kept.budget.repetitions, 1);
  EXPECT_EQ(kept.budget.iterations, 30);
  // The line search's budget given where the search is not the line search: refused, saying why.
  o.sizing.line_given = true;
  PZ_EXPECT_HAS(pz::testing::InputErrorOf([&] { FitRecords(set, o); }),
                "--line-grid / --line-brackets / --line-tolerance: the line search's budget");
  o.sizing.line_given = false;
  o.sizing.enabled = false;
  const FitResult given = FitRecords(set, o);
  EXPECT_FALSE(given.budget_sized);
  EXPECT_EQ(given.budget.iterations, 80);
  EXPECT_EQ(given.budget.converged_spread, 0);
}

TEST(RecordFit, DifferentialEvolutionFitsAndTheUncertaintyTableCoversTheTruth) {
  // backlash-like on a noisy sine: the one fit of opt/fit.h with the DE search; every parameter is
  // well constrained and its σ covers the truth (|estimate − truth| < 4 σ), the same on two
  // threads.
  const Case c = Cases()[1];
  const io::RecordSet set = MakeSet(c, synth::Waveform::kSine, 7);
  FitOptions o = QuickOptions(c.family);
  o.search.algorithm = opt::SearchAlgorithm::kDe;
  o.search.de.population = 20;
  o.search.de.generations = 60;
  o.threads = 1;
  const FitResult r = FitRecords(set, o);
  EXPECT_LT(r.metrics[1].rmse, 1.5 * kFloor);
  ASSERT_EQ(r.uncertainty.params.size(), 3u);
  EXPECT_NEAR(r.uncertainty.residual_sigma, kFloor, 0.2 * kFloor);
  for (size_t i = 0; i < 3; ++i) {
    const opt::ParamEstimate& p = r.uncertainty.params[i];
    SCOPED_TRACE(p.name);
    EXPECT_EQ(p.name, r.model->params()[i].name);
    EXPECT_EQ(p.value, r.params[i]);
    EXPECT_EQ(p.identifiability, opt::Identifiability::kWell);
    EXPECT_GT(p.std_error, 0);
    EXPECT_LT(std::abs(p.value - c.truth[i]), 4 * p.std_error);
  }
  EXPECT_EQ(r.uncertainty.singular_values.size(), 3u);
  o.threads = 2;
  const FitResult b = FitRecords(set, o);
  EXPECT_EQ(b.params, r.params);
  EXPECT_EQ(b.uncertainty.params[0].std_error, r.uncertainty.params[0].std_error);
  o.uncertainty = false;
  EXPECT_TRUE(FitRecords(set, o).uncertainty.params.empty());
}

TEST(RecordFit, NegativeGainIsHandledByPolarity) {
  Case c = Cases()[1];
  io::RecordSet set = MakeSet(c, synth::Waveform::kSine, 5);
  for (auto& r : set.records)
    for (double& v : r.y) v = -v;
  const FitResult r = FitRecords(set, QuickOptions(c.family));
  EXPECT_EQ(r.model->scale().polarity, -1);
  EXPECT_LT(r.metrics[1].rmse, 1.5 * kFloor);
}

TEST(RecordFit, TheLargestErrorIsReportedWithItsTime) {
  // A spike planted in the withheld window: the metrics say how large and where, so that a report
  // can tell a one-sample glitch (a jump at the start, a lagging sensor) from a blow-up.
  Case c = Cases()[1];
  io::RecordSet set = MakeSet(c, synth::Waveform::kSine, 5);
  const FitResult r = FitRecords(set, QuickOptions(c.family));
  io::Record spiked = set.records[1];
  const size_t k = spiked.first_scored + (spiked.end_scored - spiked.first_scored) / 3;
  spiked.y[k] += 50 * kFloor;
  std::vector<double> yhat;
  const RecordMetrics m = Evaluate(*r.model, r.params, r.weights, spiked, &yhat);
  EXPECT_EQ(m.max_at_s, spiked.t[k]);
  EXPECT_DOUBLE_EQ(m.max_abs, std::abs(spiked.y[k] - yhat[k]));
  EXPECT_GT(m.max_abs, 40 * kFloor);
}

TEST(RecordFit, NonNegativeLeastSquaresMatchesAnActiveSetByHand) {
  // min ‖A w − b‖², w ≥ 0 with the unconstrained optimum (1, −1): the answer is (x, 0).
  Eigen::MatrixXd A(3, 2);
  A << 1, 0, 0, 1, 1, 1;
  Eigen::VectorXd b(3);
  b << 1, -1, 0;
  const Eigen::VectorXd w = NonNegativeLeastSquares(A.transpose() * A, A.transpose() * b);
  EXPECT_NEAR(w(0), 0.5, 1e-12);
  EXPECT_EQ(w(1), 0);
}

TEST(RecordFit, AWindowThatEndsInsideTheRestGivesEveryFamilyItsRestOutput) {
  // Issue 37: a withheld record whose scored window lies inside its rest is simulated from the
  // rest's last sample of the window, one sample; the bimorph fin's sampled drive needs two and
  // gave NaN (its fits then diverged on every vector, or reported RMSE nan).
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.family);
    const io::RecordSet set = MakeSet(c, synth::Waveform::kSine, 3);
    io::Record r = set.records[0];
    ASSERT_GT(r.rest_samples, 100u);
    io::SetWindow(r, r.t[10], r.t[60], 20, "inside the rest");
    const DataScale scale = TruthScale(c);
    const RecordModel m(std::shared_ptr<const Family>(MakeFamily(c.family, scale)), {}, scale);
    const std::vector<double> params = m.family().linear() ? std::vector<double>{} : c.truth;
    const std::vector<double> weights = m.family().linear() ? c.truth : std::vector<double>{};
    std::vector<double> whole(r.size()), inside(r.end_scored);
    const double rest = m.Simulate(r, params, weights, r.size(), whole);
    m.Simulate(r, params, weights, r.end_scored, inside);
    ASSERT_TRUE(std::isfinite(rest));
    for (size_t k = 0; k < r.end_scored; ++k) {
      ASSERT_TRUE(std::isfinite(inside[k])) << k;
      EXPECT_NEAR(inside[k], rest, 1e-12 * std::max(1.0, std::abs(rest))) << k;
    }
    const RecordMetrics e = Evaluate(m, params, weights, r);
    EXPECT_TRUE(std::isfinite(e.rmse));
  }
}

/// A plant whose every simulation diverges (an unstable plant at this sample step).
class DivergingFamily final : public Family {
 public:
  std::string name() const override { return "diverging"; }
  std::string title() const override { return "diverging"; }
  std::string equation() const override { return "y = inf"; }
  const std::vector<ParamInfo>& params() const override { return params_; }
  void Simulate(std::span<const double>, std::span<const double>, double,
                std::span<double> y) const override {
    std::fill(y.begin(), y.end(), std::numeric_limits<double>::infinity());
  }

 private:
  std::vector<ParamInfo> params_{{"a", "1", 0, 1, false}};
};

TEST(RecordFit, AFitWhoseEverySimulationDivergesIsANamedError) {
  // Issue 37: `piezoid fit` reported RMSE nan on every record and wrote a fit.json of NaN.
  const io::RecordSet set = MakeSet(Cases()[1], synth::Waveform::kSine, 1);
  const DataScale scale = TruthScale(Cases()[1]);
  FitOptions o = QuickOptions("backlash-like");
  o.search.pso.particles = 4;
  o.search.pso.iterations = 2;
  const std::string e = pz::testing::InputErrorOf([&] {
    FitModel(set,
             std::make_shared<RecordModel>(std::make_shared<DivergingFamily>(),
                                           std::vector<EffectKind>{}, scale),
             o);
  });
  PZ_EXPECT_HAS(e, "diverging: the model's output on the training records (rec) is not finite");
  PZ_EXPECT_HAS(e, "--substeps");
}

TEST(RecordFit, BadRequestsAreNamed) {
  using pz::testing::InputErrorOf;
  io::RecordSet set = MakeSet(Cases()[1], synth::Waveform::kSine, 1);
  FitOptions o = QuickOptions("jiles-atherton");
  PZ_EXPECT_HAS(InputErrorOf([&] { FitRecords(set, o); }),
                "--family 'jiles-atherton' is unknown (families: stack-bouc-wen");
  PZ_EXPECT_HAS(InputErrorOf([] { ParseEffect("hum"); }), "effect 'hum' is unknown");
  // A beam effect of the one library: refused, and the error says where it runs.
  PZ_EXPECT_HAS(InputErrorOf([] { ParseEffect("hinge-friction"); }), "acts on the beam");
  PZ_EXPECT_HAS(InputErrorOf([] { ParseEffect("cubic-stiffening"); }), "piezoid diagnose --cases");
  for (auto& r : set.records) r.role = CaseRole::kTest;
  PZ_EXPECT_HAS(InputErrorOf([&] { FitRecords(set, QuickOptions("duhem")); }),
                "no training records");
}

}  // namespace
}  // namespace pz::records
