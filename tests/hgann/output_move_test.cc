// The HGANN output move (hgann/output_move.h; opt/ga.h 9.): the child's network gives the target
// outputs on every input, keeps the parent's input and hidden genes, and the target is a step from
// the parent's mean outputs of every size between the fine and the coarse bound.
#include "hgann/output_move.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include "io/bench_data.h"
#include "model/chromosome.h"
#include "opt/random.h"

namespace pz::hgann {
namespace {

using opt::Genome;
using opt::Rng;

const HgannFitness& Fitness() {
  static const HgannFitness f(HgannConfigFromCaseSet(
      io::LoadCaseSet(std::string(PIEZOID_DATA_DIR) + "/bimorph-fin/nominal"), {}));
  return f;
}

Genome RandomChromosome(uint64_t seed) {
  Rng rng(seed);
  Genome g;
  g.bits.resize(model::kChromosomeBits);
  for (auto& b : g.bits) b = static_cast<uint8_t>(rng.NextU64() >> 63);
  return g;
}

// The outputs scaled to [0, 1] of a network at (V, f).
std::array<double, model::kNetworkOutputs> Outputs(const model::Network& n, double v, double f) {
  const auto a = n.Forward(v, f);
  std::array<double, model::kNetworkOutputs> s{};
  for (int k = 0; k < model::kNetworkOutputs; ++k) s[k] = a.s[k];
  return s;
}

// The output layer (transfer functions of the outputs, W2, c2) and nothing else.
bool InOutputLayer(int bit) {
  for (int k = 0; k < model::kNetworkOutputs; ++k)
    if (bit >= model::OutputTfBit(k) && bit < model::OutputTfBit(k) + model::kTransferCodeBits)
      return true;
  return bit >= model::kW2Offset;
}

TEST(OutputMove, UnsetTheyNeedSeveralIslandsAndASpreadPenalty) {
  opt::GaOptions ga;
  EXPECT_EQ(HgannOutputMoves(ga, 10), 0) << "one island";
  ga.islands = 4;
  EXPECT_EQ(HgannOutputMoves(ga, 10), 32);
  EXPECT_EQ(HgannOutputMoves(ga, 0), 0)
      << "λ = 0: nothing checks the loop between the training cases";
  ga.output_moves = 5;
  EXPECT_EQ(HgannOutputMoves(ga, 0), 5) << "given: at any λ";
  ga.output_moves = 0;
  EXPECT_EQ(HgannOutputMoves(ga, 10), 0);
}

TEST(OutputMove, ConstantOutputsGiveTheTargetOnEveryInputAndKeepTheOtherGenes) {
  const std::array<double, model::kNetworkOutputs> t = {0, 1, 0.3, 0.123456, 0.5, 0.999, 0.0007};
  for (uint64_t seed : {1u, 2u, 3u}) {
    const Genome parent = RandomChromosome(seed);
    std::vector<uint8_t> bits = parent.bits;
    OutputMove::WriteConstantOutputs(&bits, t);
    for (int b = 0; b < model::kChromosomeBits; ++b) {
      if (InOutputLayer(b)) continue;
      ASSERT_EQ(bits[b], parent.bits[b]) << "bit " << b << " is not in the output layer";
    }
    const model::Network n = Fitness().Decode(Genome{bits, {}});
    for (int k = 0; k < model::kNetworkOutputs; ++k)
      EXPECT_EQ(n.output_tf[k], model::TransferFunction::kSatlin);
    EXPECT_EQ(n.w2.cwiseAbs().maxCoeff(), model::DecodeWeight(model::EncodeWeight(0.0)));
    // Every input, trained or not (also outside the training box): the bias code nearest t, plus at
    // most H · 6.1e-4 from the hidden nodes' weights nearest 0.
    const double slack =
        0.5 * 20.0 / model::kMaxWeightCode + n.hidden() * std::abs(model::DecodeWeight(8192));
    for (double v : {375.0, 500.0, 750.0, 100.0, 1000.0})
      for (double f : {0.25, 0.5, 1.0, 0.1, 3.0}) {
        const auto s = Outputs(n, v, f);
        for (int k = 0; k < model::kNetworkOutputs; ++k)
          EXPECT_NEAR(s[k], t[k], slack) << "output " << k << " at " << v << " V " << f << " Hz";
      }
  }
}

TEST(OutputMove, MeanOutputsAreTheMeanOverTheTrainingCases) {
  const OutputMove move(Fitness().config());
  const model::Network n = Fitness().Decode(RandomChromosome(7));
  std::array<double, model::kNetworkOutputs> mean{};
  int count = 0;
  for (const auto& c : Fitness().config().cases) {
    if (!c.training) continue;
    const auto s = Outputs(n, c.drive.amplitude_v, c.drive.frequency_hz);
    for (int k = 0; k < model::kNetworkOutputs; ++k) mean[k] += s[k];
    ++count;
  }
  ASSERT_EQ(count, 4);
  const auto got = move.MeanOutputs(n);
  for (int k = 0; k < model::kNetworkOutputs; ++k) EXPECT_NEAR(got[k], mean[k] / count, 1e-15) << k;
}

TEST(OutputMove, StepsFromTheParentsMeanAtEveryScaleWithTheGeneratorOnly) {
  const OutputMove move(Fitness().config());
  const Genome parent = RandomChromosome(11);
  const auto center = move.MeanOutputs(Fitness().Decode(parent));
  // A function of (parent, draws): the same generator state gives the same child, bit for bit.
  Rng a(5), b(5);
  Genome ca, cb;
  move(parent, a, std::span(&ca, 1));
  move(parent, b, std::span(&cb, 1));
  EXPECT_EQ(ca.bits, cb.bits);
  EXPECT_EQ(a, b) << "the same draws";
  Rng once(5);
  for (int i = 0; i < 15; ++i) once.NextU64();
  EXPECT_EQ(a, once) << "one draw for the step size, two for each of the seven outputs";
  // Several children in one call (one decode of the parent) are the children of calls one by one.
  Rng many(8), one_by_one(8);
  std::vector<Genome> three(3), singles(3);
  move(parent, many, three);
  for (Genome& g : singles) move(parent, one_by_one, std::span(&g, 1));
  for (int i = 0; i < 3; ++i) EXPECT_EQ(three[i].bits, singles[i].bits) << "child " << i;
  EXPECT_EQ(many, one_by_one);
  // Over many moves: every target in [0, 1]; the largest step per child spans the log-uniform
  // range from below 3 · σ_min to above σ_max; the outputs off the bounds move by both signs.
  Rng rng(99);
  double smallest = INFINITY, largest = 0;
  int up = 0, down = 0;
  for (int i = 0; i < 2000; ++i) {
    Genome child;
    move(parent, rng, std::span(&child, 1));
    ASSERT_EQ(child.bits.size(), parent.bits.size());
    const auto s = move.MeanOutputs(Fitness().Decode(child));
    double step = 0;
    for (int k = 0; k < model::kNetworkOutputs; ++k) {
      ASSERT_GE(s[k], -1e-2);
      ASSERT_LE(s[k], 1 + 1e-2);
      step = std::max(step, std::abs(s[k] - center[k]));
      if (center[k] > 0.05 && center[k] < 0.95) (s[k] > center[k] ? up : down) += 1;
    }
    smallest = std::min(smallest, step), largest = std::max(largest, step);
  }
  EXPECT_LT(smallest, 3 * OutputMove::kSigmaMin + 0.01);
  EXPECT_GT(largest, OutputMove::kSigmaMax);
  EXPECT_GT(up, 0);
  EXPECT_GT(down, 0);
}

}  // namespace
}  // namespace pz::hgann
