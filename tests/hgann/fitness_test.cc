// The HGANN fitness and a complete (small) identification: determinism across evaluators and thread
// counts, the penalty of unbounded loops, the paper's Table 3 preset forcing α = 0.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <sstream>
#include <unistd.h>
#include <filesystem>

#include "hgann/identify.h"
#include "io/bench_data.h"
#include "opt/ga.h"
#include "hgann/hgann_fitness.h"
#include "opt/inline_evaluator.h"
#include "opt/thread_pool_evaluator.h"
#include "model/chromosome.h"

namespace pz::hgann {

using opt::BatchEvaluator;
using opt::FitnessStatus;
using opt::GaOptions;
using opt::GenerationSummary;
using opt::GeneticAlgorithm;
using opt::Genome;
using opt::InlineEvaluator;
using opt::Rng;
using opt::ThreadPoolEvaluator;
namespace {

const io::CaseSet& Nominal() {
  static const io::CaseSet set =
      io::LoadCaseSet(std::string(PIEZOID_DATA_DIR) + "/bimorph-fin/nominal");
  return set;
}

HgannFitness MakeFitness(const model::ParameterRanges& ranges = {}, double spread = 0) {
  auto config = HgannConfigFromCaseSet(Nominal(), ranges);
  config.spread_penalty = spread;
  return HgannFitness(std::move(config));
}

TEST(HgannConfig, FromCaseSetUsesTrainingRolesAndFittedSaturations) {
  const auto config = HgannConfigFromCaseSet(Nominal(), {});
  ASSERT_EQ(config.cases.size(), 9u);
  int training = 0;
  for (const auto& c : config.cases) {
    training += c.training;
    EXPECT_GT(c.b1, 0);
    EXPECT_LT(c.b2, 0);
  }
  EXPECT_EQ(training, 4);
  // Normalisation over the training cases (1, 5, 6, 7): V in [375, 750], f in [0.25, 1].
  EXPECT_EQ(config.normalization.amplitude_lo_v, 375);
  EXPECT_EQ(config.normalization.amplitude_hi_v, 750);
  EXPECT_EQ(config.normalization.frequency_lo_hz, 0.25);
  EXPECT_EQ(config.normalization.frequency_hi_hz, 1.0);
}

TEST(HgannConfig, ValidateNamesTheField) {
  auto config = HgannConfigFromCaseSet(Nominal(), {});
  config.cases[2].measured_deg[17] = std::nan("");
  EXPECT_NE(config.Validate().message().find("cases[2].measured_deg[17]"), std::string::npos);
  config = HgannConfigFromCaseSet(Nominal(), {});
  config.spread_penalty = -1;
  EXPECT_NE(config.Validate().message().find("spread_penalty"), std::string::npos);
  config = HgannConfigFromCaseSet(Nominal(), {});
  for (auto& c : config.cases) c.training = false;
  EXPECT_NE(config.Validate().message().find("training"), std::string::npos);
  EXPECT_THROW(HgannFitness{config}, InputError);
}

TEST(HgannFitness, RandomGenomesGiveFiniteCostsAndPenaltiesRankLast) {
  const auto fitness = MakeFitness();
  Rng rng(7);
  int penalized = 0, ok = 0;
  double worst_ok = 0;
  for (int i = 0; i < 300; ++i) {
    Genome g;
    g.bits.resize(model::kChromosomeBits);
    for (auto& b : g.bits) b = static_cast<uint8_t>(rng.NextU64() & 1);
    const auto r = fitness.Evaluate(g);
    ASSERT_TRUE(std::isfinite(r.cost));
    if (r.status == FitnessStatus::kOk) {
      ++ok;
      worst_ok = std::max(worst_ok, r.cost);
      EXPECT_TRUE(r.reason.empty());
    } else {
      ++penalized;
      EXPECT_EQ(r.cost, fitness.penalty_cost());
      EXPECT_FALSE(r.reason.empty());
    }
  }
  EXPECT_GT(ok, 0);
  EXPECT_GT(penalized, 0) << "the default ranges allow beta - gamma < 0: some loops are unbounded";
  EXPECT_LT(worst_ok, fitness.penalty_cost());
}

TEST(HgannFitness, MalformedGenomeIsAnErrorNotACrash) {
  const auto fitness = MakeFitness();
  Genome g;
  g.bits.assign(100, 1);
  const auto r = fitness.Evaluate(g);
  EXPECT_EQ(r.status, FitnessStatus::kError);
  EXPECT_TRUE(std::isfinite(r.cost));
  EXPECT_NE(r.reason.find("invalid genome"), std::string::npos);
}

TEST(HgannFitness, SpreadPenaltyIsZeroForConstantOutputsAndAddsToCost) {
  const auto plain = MakeFitness({}, 0);
  const auto spread = MakeFitness({}, 10);
  Rng rng(3);
  int checked = 0;
  for (int i = 0; i < 50 && checked < 10; ++i) {
    Genome g;
    g.bits.resize(model::kChromosomeBits);
    for (auto& b : g.bits) b = static_cast<uint8_t>(rng.NextU64() & 1);
    const auto a = plain.Evaluate(g), b = spread.Evaluate(g);
    if (a.status != FitnessStatus::kOk) continue;
    ++checked;
    const double s = spread.OutputSpread(spread.Decode(g));
    EXPECT_GE(s, 0);
    if (!spread.BoundedOnEnvelope(spread.Decode(g))) {  // (SpreadPenaltyRefusesALoopUnbounded…)
      EXPECT_EQ(b.reason, "unbounded_hysteresis_in_envelope");
      EXPECT_EQ(b.cost, spread.penalty_cost());
      continue;
    }
    EXPECT_NEAR(b.cost, a.cost + 10 * s, 1e-9 * b.cost);
  }
  EXPECT_EQ(checked, 10);
}

// Which parameters a network holds at a bound on every training case (the report's "held at a
// bound" line): hard limits at either end, a tribas at its peak, an interior logsig, a hard limit
// that switches between the training cases, and a zero-width range.
TEST(HgannFitness, ParametersAtBoundOnEveryTrainingCase) {
  auto ranges = model::ParameterRanges{};
  ranges.a2 = {0.5, 0.5};  // zero width: never "at a bound"
  const auto fitness = MakeFitness(ranges);
  Genome g;
  g.bits.assign(model::kChromosomeBits, 0);
  Rng rng(11);
  for (auto& b : g.bits) b = static_cast<uint8_t>(rng.NextU64() & 1);
  model::Network n = fitness.Decode(g);
  // A hidden node whose output differs between the training cases, and a threshold between its
  // values.
  int node = -1;
  double threshold = 0;
  for (int tries = 0; node < 0 && tries < 200; ++tries) {
    for (auto& b : g.bits) b = static_cast<uint8_t>(rng.NextU64() & 1);
    n = fitness.Decode(g);
    for (int j = 0; j < n.hidden() && node < 0; ++j) {
      double lo = INFINITY, hi = -INFINITY;
      for (const auto& c : fitness.config().cases) {
        if (!c.training) continue;
        const double b = n.Forward(c.drive.amplitude_v, c.drive.frequency_hz).b(j);
        lo = std::min(lo, b), hi = std::max(hi, b);
      }
      if (hi - lo > 1e-3) node = j, threshold = (lo + hi) / 2;
    }
  }
  ASSERT_GE(node, 0);
  n.w2.setZero();
  n.output_tf = {model::TransferFunction::kHardlim, model::TransferFunction::kHardlims,
                 model::TransferFunction::kHardlim, model::TransferFunction::kLogsig,
                 model::TransferFunction::kTribas,  model::TransferFunction::kHardlims,
                 model::TransferFunction::kHardlim};
  n.c2 << 1, -1, -threshold, 0, 0, -1, 1;
  n.w2(node, 2) = 1;  // α: switches between 0 and 1 over the training cases
  const auto side = fitness.ParametersAtBound(n);
  EXPECT_EQ(side[0], 1);   // μ: hardlim(1) = 1, the upper bound
  EXPECT_EQ(side[1], -1);  // δ: hardlims(−1) = −1, the lower bound
  EXPECT_EQ(side[2], 0);   // α: at the top on some training cases, the bottom on others
  EXPECT_EQ(side[3], 0);   // β: logsig(0) = 0.5, inside
  EXPECT_EQ(side[4], 1);   // γ: tribas(0) = 1, the upper bound
  EXPECT_EQ(side[5], -1);  // a1
  EXPECT_EQ(side[6], 0);   // a2: a zero-width range has no side
}

// A network whose loop is bounded on the four training cases and unbounded at one corner of their
// box, (375 V, 1 Hz) — an operating point between the training cases (case 3, withheld): γ rises
// with f − V (normalised) and passes β only there. λ = 0 (the paper's cost) scores the training
// cases alone; λ > 0 penalises the network (HgannFitnessConfig::spread_penalty).
TEST(HgannFitness, SpreadPenaltyRefusesALoopUnboundedInsideTheTrainingBox) {
  const auto ten = MakeFitness({}, 10);
  const auto paper = MakeFitness({}, 0);
  model::Network n;
  using TF = model::TransferFunction;
  n.input_tf = {TF::kSatlin, TF::kSatlin};  // A = x on [0, 1]
  n.hidden_tf = {TF::kSatlin, TF::kSatlin};
  n.output_tf.fill(TF::kSatlin);
  n.w1 = Eigen::MatrixXd::Zero(2, 2);
  n.w1(0, 0) = -1;  // B0 = satlin(x_f − x_V)
  n.w1(1, 0) = 1;
  n.c1 = Eigen::VectorXd::Zero(2);
  n.w2 = Eigen::MatrixXd::Zero(2, 7);
  n.c2 = Eigen::VectorXd(7);
  n.c2 << 0.3, 0.1, 0.3, 0.5, 0.5, 0.05, 0.05;  // μ 90, δ 0.1, α 0.003, β 0.01, γ 0 at B0 = 0
  n.w2(0, 4) = 0.3;                             // γ = 0.012 · B0: 0.012 > β where B0 = 1
  n.normalization = ten.config().normalization;
  n.ranges = ten.config().ranges;
  ASSERT_TRUE(n.Validate().ok());
  double gamma_max = -INFINITY;
  for (const auto& c : ten.config().cases) {
    if (!c.training) continue;
    gamma_max = std::max(gamma_max, n.Predict(c.drive.amplitude_v, c.drive.frequency_hz).gamma);
  }
  EXPECT_NEAR(gamma_max, 0.008, 1e-12) << "(500 V, 1 Hz): B0 = 2/3, below β = 0.01";
  EXPECT_NEAR(n.Predict(375, 1).gamma, 0.012, 1e-12);
  EXPECT_FALSE(ten.BoundedOnEnvelope(n));
  const auto scored = paper.EvaluateNetwork(n);
  EXPECT_EQ(scored.status, FitnessStatus::kOk) << scored.reason;
  const auto refused = ten.EvaluateNetwork(n);
  EXPECT_EQ(refused.status, FitnessStatus::kPenalized);
  EXPECT_EQ(refused.reason, "unbounded_hysteresis_in_envelope");
  EXPECT_EQ(refused.cost, ten.penalty_cost());
  // γ = 0.009 · B0 stays below β everywhere: scored, with the spread it has.
  n.w2(0, 4) = 0.225;
  EXPECT_TRUE(ten.BoundedOnEnvelope(n));
  const auto kept = ten.EvaluateNetwork(n);
  ASSERT_EQ(kept.status, FitnessStatus::kOk) << kept.reason;
  EXPECT_NEAR(kept.cost, paper.EvaluateNetwork(n).cost + 10 * ten.OutputSpread(n),
              1e-9 * kept.cost);
  EXPECT_GT(ten.OutputSpread(n), 0);
}

GaOptions SmallGa(uint64_t seed) {
  GaOptions o;
  o.population_size = 40;
  o.max_generations = 12;
  o.seed = seed;
  return o;
}

struct RunRecord {
  Genome best;
  std::vector<GenerationSummary> log;
};

RunRecord RunWith(const HgannFitness& fitness, BatchEvaluator& evaluator, uint64_t seed) {
  auto o = SmallGa(seed);
  o.error_cost = fitness.penalty_cost();
  GeneticAlgorithm ga(o, &evaluator);
  ga.SetDescriber([](const Genome& g) { return model::DescribeChromosome(g.bits); });
  const auto summary = ga.Run();
  return {summary.best, ga.state().log};
}

TEST(HgannIdentification, SameSeedIsBitIdenticalInlineOneAndTwoThreads) {
  const auto fitness = MakeFitness();
  InlineEvaluator inline_eval(fitness, fitness.penalty_cost());
  ThreadPoolEvaluator one(fitness, 1, fitness.penalty_cost());
  ThreadPoolEvaluator two(fitness, 2, fitness.penalty_cost());
  const auto a = RunWith(fitness, inline_eval, 11);
  const auto b = RunWith(fitness, one, 11);
  const auto c = RunWith(fitness, two, 11);
  EXPECT_EQ(a.best, b.best);
  EXPECT_EQ(a.best, c.best);
  ASSERT_EQ(a.log.size(), 13u);
  ASSERT_EQ(a.log.size(), b.log.size());
  ASSERT_EQ(a.log.size(), c.log.size());
  for (size_t i = 0; i < a.log.size(); ++i) {
    EXPECT_TRUE(a.log[i].SameOutcome(b.log[i])) << i;
    EXPECT_TRUE(a.log[i].SameOutcome(c.log[i])) << i;
    // Bit-identical costs, not merely close.
    EXPECT_EQ(std::memcmp(&a.log[i].best_cost, &c.log[i].best_cost, sizeof(double)), 0) << i;
  }
  // A different seed gives a different run.
  const auto d = RunWith(fitness, two, 12);
  EXPECT_NE(a.best, d.best);
}

TEST(HgannIdentification, ShortRunImprovesAndBeatsRandom) {
  const auto fitness = MakeFitness();
  ThreadPoolEvaluator pool(fitness, 2, fitness.penalty_cost());
  const auto r = RunWith(fitness, pool, 5);
  EXPECT_LT(r.log.back().best_cost, r.log.front().best_cost);
  EXPECT_LT(r.log.back().best_cost, fitness.penalty_cost());
}

// With the paper's Table 3 ranges (α, β, γ ≤ 0) every α ≠ 0 gives an unbounded loop: the GA's
// survivors put α exactly at 0 (the top of its range) and the failures are counted as penalised.
TEST(HgannIdentification, PaperTable3RangesDriveAlphaToZero) {
  const auto fitness = MakeFitness(model::ParameterRanges::PaperTable3());
  ThreadPoolEvaluator pool(fitness, 2, fitness.penalty_cost());
  auto o = SmallGa(21);
  o.max_generations = 15;
  o.error_cost = fitness.penalty_cost();
  GeneticAlgorithm ga(o, &pool);
  const auto summary = ga.Run();
  ASSERT_EQ(summary.best_fitness.status, FitnessStatus::kOk);
  int64_t penalized = 0;
  std::map<std::string, int> reasons;
  for (const auto& g : ga.state().log) {
    penalized += g.penalized;
    for (const auto& [k, n] : g.failure_reasons) reasons[k] += n;
    EXPECT_TRUE(std::isfinite(g.mean_cost));
    EXPECT_TRUE(std::isfinite(g.worst_cost));
  }
  EXPECT_GT(penalized, 0);
  EXPECT_GT(reasons["unbounded_hysteresis"], 0);
  const auto net = fitness.Decode(summary.best);
  for (const auto& c : fitness.EvaluateCases(net)) {
    if (c.training) {
      EXPECT_EQ(c.params.alpha, 0.0) << "case " << c.number;
      EXPECT_TRUE(c.summary.ok()) << "case " << c.number;
    } else {
      // Untrained operating points: α = 0 again, or an unbounded loop reported as a status.
      EXPECT_TRUE(c.params.alpha == 0.0 ||
                  c.summary.status == model::SimStatus::kUnboundedHysteresis);
      EXPECT_TRUE(std::isfinite(c.pi));
    }
  }
}

TEST(HgannReport, PaperTable8Lookup) {
  EXPECT_DOUBLE_EQ(PaperTable8Pi(750, 1.0), 6.78);
  EXPECT_DOUBLE_EQ(PaperTable8Pi(375, 0.25), 1.42);
  EXPECT_TRUE(std::isnan(PaperTable8Pi(600, 1.0)));
  EXPECT_FALSE(RangesPreset("tabel3").has_value());
  EXPECT_EQ(*RangesPreset("paper"), model::ParameterRanges::PaperTable3());
  EXPECT_EQ(*RangesPreset(""), model::ParameterRanges{});
}

}  // namespace
}  // namespace pz::hgann
