// The loop repair (hgann/loop_repair.h; opt/ga.h 10.): a genome whose Bouc–Wen loop is unbounded
// where the fitness looks is rewritten, in its loop outputs alone, into a network the fitness
// accepts; a bounded genome is left as it is; the paper's preset has no repair.
#include "hgann/loop_repair.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "io/bench_data.h"
#include "model/chromosome.h"
#include "opt/random.h"

namespace pz::hgann {
namespace {

using opt::Genome;

HgannFitnessConfig Config(const model::ParameterRanges& ranges, double lambda) {
  HgannFitnessConfig c = HgannConfigFromCaseSet(
      io::LoadCaseSet(std::string(PIEZOID_DATA_DIR) + "/bimorph-fin/nominal"), ranges);
  c.spread_penalty = lambda;
  return c;
}

Genome RandomChromosome(opt::Rng& rng) {
  Genome g;
  g.bits.resize(model::kChromosomeBits);
  for (auto& b : g.bits) b = static_cast<uint8_t>(rng.NextU64() >> 63);
  return g;
}

// Bit `bit` lies in output k's genes (its transfer function, W2(·, k) or c2(k)) for some k in the
// loop's outputs 2–4.
bool InLoopOutputs(int bit) {
  for (int k = 2; k <= 4; ++k) {
    if (bit >= model::OutputTfBit(k) && bit < model::OutputTfBit(k) + model::kTransferCodeBits)
      return true;
    if (bit >= model::C2Bit(k) && bit < model::C2Bit(k) + model::kWeightCodeBits) return true;
    for (int j = 0; j < model::kMaxHidden; ++j)
      if (bit >= model::W2Bit(j, k) && bit < model::W2Bit(j, k) + model::kWeightCodeBits)
        return true;
  }
  return false;
}

TEST(LoopRepair, TheRobustPresetRepairsThePaperDoesNot) {
  EXPECT_TRUE(HgannRepairsLoops("robust"));
  EXPECT_TRUE(HgannRepairsLoops("")) << "the default preset";
  EXPECT_FALSE(HgannRepairsLoops("paper"));
}

// Default ranges with the robust preset's penalty grid: the fitness refuses none of the repaired
// genomes for their loop, the repair touches only the loop's output genes, and a second pass
// changes nothing.
TEST(LoopRepair, UnboundedChildrenBecomeBoundedInTheirLoopOutputsAlone) {
  const HgannFitness fitness(Config({}, 10));
  const LoopRepair repair(fitness.config());
  opt::Rng rng(47);
  int unbounded = 0, repaired = 0;
  for (int i = 0; i < 60; ++i) {
    const Genome before = RandomChromosome(rng);
    Genome g = before;
    const bool was = repair.Bounded(fitness.Decode(g));
    const bool changed = repair(g);
    EXPECT_EQ(changed, !was) << "genome " << i;
    unbounded += !was;
    repaired += changed;
    EXPECT_TRUE(repair.Bounded(fitness.Decode(g))) << "genome " << i;
    for (int b = 0; b < model::kChromosomeBits; ++b)
      if (g.bits[b] != before.bits[b])
        ASSERT_TRUE(InLoopOutputs(b)) << "genome " << i << " bit " << b;
    const opt::FitnessResult r = fitness.Evaluate(g);
    EXPECT_EQ(r.reason.find("unbounded"), std::string::npos) << "genome " << i << ": " << r.reason;
    Genome again = g;
    EXPECT_FALSE(repair(again));
    EXPECT_EQ(again.bits, g.bits);
  }
  EXPECT_GT(unbounded, 10) << "half the default (β, γ) box is unbounded";
  EXPECT_EQ(repaired, unbounded);
}

// The paper's Table 3 (β, γ ≤ 0) holds no bounded (β, γ) with α ≠ 0: the repair sets α to 0, an end
// of its range, exactly.
TEST(LoopRepair, WithoutABoundedBetaGammaAlphaGoesToZero) {
  const HgannFitness fitness(Config(model::ParameterRanges::PaperTable3(), 0));
  const LoopRepair repair(fitness.config());
  opt::Rng rng(3);
  int repaired = 0;
  for (int i = 0; i < 30; ++i) {
    Genome g = RandomChromosome(rng);
    if (!repair(g)) continue;
    ++repaired;
    for (const HgannCase& c : fitness.config().cases)
      EXPECT_EQ(fitness.Decode(g).Predict(c.drive.amplitude_v, c.drive.frequency_hz).alpha, 0.0);
  }
  EXPECT_GT(repaired, 0);
  std::array<double, 3> t{};
  EXPECT_TRUE(repair.BoundedConstants({0.5, 0.5, 0.5}, &t));
  EXPECT_GT(t[0], 1.0) << "α's output beyond its top (α = 0) by the margin";
}

TEST(LoopRepair, ConstantsKeepTheMeanWhereItIsBoundedAndClampGammaInsideBeta) {
  const LoopRepair repair(Config({}, 0));
  std::array<double, 3> t{};
  // β = 0.01, γ = 0.002: bounded, kept.
  ASSERT_TRUE(repair.BoundedConstants({0.4, 0.5, 0.55}, &t));
  EXPECT_DOUBLE_EQ(t[0], 0.4);
  EXPECT_DOUBLE_EQ(t[1], 0.5);
  EXPECT_DOUBLE_EQ(t[2], 0.55);
  // β = 0.004, γ = 0.018: γ clamped to β − the margins (0.004 − 2e-4 − 4e-4 = 0.0034).
  ASSERT_TRUE(repair.BoundedConstants({0.4, 0.2, 0.95}, &t));
  EXPECT_DOUBLE_EQ(t[1], 0.2);
  EXPECT_NEAR(-0.02 + 0.04 * t[2], 0.0034, 1e-15);
  // β = 0: raised to 2 (margins) = 1.2e-3, γ within ±6e-4.
  ASSERT_TRUE(repair.BoundedConstants({0.4, 0.0, 0.0}, &t));
  EXPECT_NEAR(0.02 * t[1], 1.2e-3, 1e-15);
  EXPECT_NEAR(-0.02 + 0.04 * t[2], -6e-4, 1e-15);
}

}  // namespace
}  // namespace pz::hgann
