// The 1415-bit HGANN chromosome: gene positions and widths (spec hgann.md §2), MSB-first gene
// values, H decoding, weight-code extremes, unused hidden genes, encode/decode round trips, packing
// and validation messages.
#include "model/chromosome.h"

#include <gtest/gtest.h>

#include <limits>
#include <random>

namespace pz::model {
namespace {

std::vector<uint8_t> RandomBits(uint64_t seed) {
  std::mt19937_64 g(seed);
  std::vector<uint8_t> bits(kChromosomeBits);
  for (uint8_t& b : bits) b = static_cast<uint8_t>(g() >> 63);
  return bits;
}

void SetGene(std::vector<uint8_t>& bits, int offset, int width, const char* msb_first) {
  for (int b = 0; b < width; ++b) bits[offset + b] = msb_first[b] == '1';
}

TEST(ChromosomeLayout, GenePositionsAndTotalLength) {
  EXPECT_EQ(kChromosomeBits, 1415);
  EXPECT_EQ(3 + 54 + 97 * 14, kChromosomeBits);
  EXPECT_EQ(kHiddenCountOffset, 0);
  EXPECT_EQ(InputTfBit(0), 3);
  EXPECT_EQ(InputTfBit(1), 6);
  EXPECT_EQ(HiddenTfBit(0), 9);
  EXPECT_EQ(HiddenTfBit(8), 33);
  EXPECT_EQ(OutputTfBit(0), 36);
  EXPECT_EQ(OutputTfBit(6), 54);  // last TF gene ends at bit 56
  EXPECT_EQ(W1Bit(0, 0), 57);
  EXPECT_EQ(W1Bit(0, 1), 57 + 14);
  EXPECT_EQ(W1Bit(1, 0), 57 + 9 * 14);   // gene 9 i + j
  EXPECT_EQ(W1Bit(1, 8), 57 + 17 * 14);  // last W1 gene: 295 … 308
  EXPECT_EQ(C1Bit(0), 309);
  EXPECT_EQ(C1Bit(8), 309 + 8 * 14);
  EXPECT_EQ(W2Bit(0, 0), 435);
  EXPECT_EQ(W2Bit(1, 0), 435 + 7 * 14);  // gene 7 j + k
  EXPECT_EQ(W2Bit(8, 6), 435 + 62 * 14);
  EXPECT_EQ(C2Bit(0), 1317);
  EXPECT_EQ(C2Bit(6) + kWeightCodeBits, kChromosomeBits);
}

TEST(ChromosomeLayout, EveryBitBelongsToExactlyOneGene) {
  std::vector<int> owner(kChromosomeBits, 0);
  auto mark = [&](int offset, int width) {
    for (int b = offset; b < offset + width; ++b) ++owner[b];
  };
  mark(kHiddenCountOffset, 3);
  for (int i = 0; i < 2; ++i) mark(InputTfBit(i), 3);
  for (int j = 0; j < 9; ++j) mark(HiddenTfBit(j), 3);
  for (int k = 0; k < 7; ++k) mark(OutputTfBit(k), 3);
  for (int i = 0; i < 2; ++i)
    for (int j = 0; j < 9; ++j) mark(W1Bit(i, j), 14);
  for (int j = 0; j < 9; ++j) mark(C1Bit(j), 14);
  for (int j = 0; j < 9; ++j)
    for (int k = 0; k < 7; ++k) mark(W2Bit(j, k), 14);
  for (int k = 0; k < 7; ++k) mark(C2Bit(k), 14);
  for (int b = 0; b < kChromosomeBits; ++b) EXPECT_EQ(owner[b], 1) << "bit " << b;
}

TEST(ChromosomeCodec, HiddenCountIsTwoPlusCodeMsbFirst) {
  std::vector<uint8_t> bits(kChromosomeBits, 0);
  EXPECT_EQ(DecodeHiddenCount(bits), 2);
  SetGene(bits, 0, 3, "001");
  EXPECT_EQ(DecodeHiddenCount(bits), 3);
  SetGene(bits, 0, 3, "100");
  EXPECT_EQ(DecodeHiddenCount(bits), 6);
  SetGene(bits, 0, 3, "111");
  EXPECT_EQ(DecodeHiddenCount(bits), 9);
  const Network n = DecodeChromosome(bits, {}, {});
  EXPECT_EQ(n.hidden(), 9);
  EXPECT_EQ(n.w1.cols(), 9);
  EXPECT_EQ(n.w2.rows(), 9);
}

TEST(ChromosomeCodec, WeightCodeExtremesAndResolution) {
  EXPECT_EQ(DecodeWeight(0), -10.0);
  EXPECT_EQ(DecodeWeight(kMaxWeightCode), 10.0);
  EXPECT_NEAR(DecodeWeight(1) - DecodeWeight(0), 20.0 / 16383, 1e-15);  // 1.22e-3
  EXPECT_NEAR(DecodeWeight(8191), -10.0 / 16383, 1e-15);
  EXPECT_EQ(EncodeWeight(-10.0), 0u);
  EXPECT_EQ(EncodeWeight(10.0), kMaxWeightCode);
  EXPECT_EQ(EncodeWeight(0.0), 8192u);  // 8191.5 rounds up
  for (uint32_t c = 0; c <= kMaxWeightCode; ++c) ASSERT_EQ(EncodeWeight(DecodeWeight(c)), c);
  try {
    EncodeWeight(10.5, "w2(3, 1)");
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("w2(3, 1) = 10.5"), std::string::npos) << e.what();
  }
  EXPECT_THROW(EncodeWeight(std::numeric_limits<double>::quiet_NaN()), InputError);
}

TEST(ChromosomeCodec, GenesLandInTheirNetworkFields) {
  std::vector<uint8_t> bits(kChromosomeBits, 0);     // H = 2, all TFs hardlim, all weights −10
  SetGene(bits, 0, 3, "001");                        // H = 3
  SetGene(bits, InputTfBit(1), 3, "100");            // input 1: tribas (4)
  SetGene(bits, HiddenTfBit(2), 3, "011");           // hidden 2: satlins (3)
  SetGene(bits, OutputTfBit(6), 3, "111");           // output 6 (a2): radbas (7)
  SetGene(bits, W1Bit(1, 2), 14, "11111111111111");  // +10
  SetGene(bits, C1Bit(1), 14, "10000000000000");     // code 8192
  SetGene(bits, W2Bit(2, 5), 14, "11111111111111");  // +10
  SetGene(bits, C2Bit(3), 14, "00000000000001");     // code 1
  const Network n = DecodeChromosome(bits, {}, {});
  ASSERT_TRUE(n.Validate().ok()) << n.Validate().message();
  EXPECT_EQ(n.hidden(), 3);
  EXPECT_EQ(n.input_tf[0], TransferFunction::kHardlim);
  EXPECT_EQ(n.input_tf[1], TransferFunction::kTribas);
  EXPECT_EQ(n.hidden_tf[2], TransferFunction::kSatlins);
  EXPECT_EQ(n.output_tf[6], TransferFunction::kRadbas);
  EXPECT_EQ(n.output_tf[5], TransferFunction::kHardlim);
  EXPECT_EQ(n.w1(1, 2), 10.0);
  EXPECT_EQ(n.w1(0, 2), -10.0);
  EXPECT_EQ(n.c1(1), DecodeWeight(8192));
  EXPECT_EQ(n.w2(2, 5), 10.0);
  EXPECT_EQ(n.w2(2, 4), -10.0);
  EXPECT_EQ(n.c2(3), DecodeWeight(1));
  EXPECT_EQ(ReadGene(bits, C1Bit(1), 14), 8192u);
}

TEST(ChromosomeCodec, GenesOfUnusedHiddenNodesDoNotEnterTheNetwork) {
  std::vector<uint8_t> bits = RandomBits(7);
  SetGene(bits, 0, 3, "001");  // H = 3: nodes 3 … 8 unused
  const Network before = DecodeChromosome(bits, {}, {});
  for (int j = 3; j < 9; ++j) {
    SetGene(bits, HiddenTfBit(j), 3, "110");
    for (int i = 0; i < 2; ++i) SetGene(bits, W1Bit(i, j), 14, "10101010101010");
    SetGene(bits, C1Bit(j), 14, "01010101010101");
    for (int k = 0; k < 7; ++k) SetGene(bits, W2Bit(j, k), 14, "11110000111100");
  }
  EXPECT_TRUE(DecodeChromosome(bits, {}, {}) == before);
}

TEST(ChromosomeCodec, EncodeDecodeRoundTrips) {
  for (uint64_t seed = 1; seed <= 50; ++seed) {
    const std::vector<uint8_t> bits = RandomBits(seed);
    const Network n = DecodeChromosome(bits, {}, ParameterRanges::PaperTable3());
    // decode ∘ encode is the identity on bits (unused genes carried from the original) …
    ASSERT_EQ(EncodeChromosome(n, bits), bits) << "seed " << seed;
    // … and encode ∘ decode the identity on decoded networks.
    const std::vector<uint8_t> fresh = EncodeChromosome(n);
    ASSERT_TRUE(DecodeChromosome(fresh, {}, ParameterRanges::PaperTable3()) == n)
        << "seed " << seed;
    // Without a carrier the unused genes are zero, everything else equal.
    std::vector<uint8_t> expected = bits;
    for (int j = n.hidden(); j < kMaxHidden; ++j) {
      for (int b = 0; b < 3; ++b) expected[HiddenTfBit(j) + b] = 0;
      for (int b = 0; b < 14; ++b) {
        expected[W1Bit(0, j) + b] = expected[W1Bit(1, j) + b] = expected[C1Bit(j) + b] = 0;
        for (int k = 0; k < 7; ++k) expected[W2Bit(j, k) + b] = 0;
      }
    }
    ASSERT_EQ(fresh, expected) << "seed " << seed;
  }
}

TEST(ChromosomeCodec, EncodeRejectsUncodableNetworks) {
  Network n = DecodeChromosome(RandomBits(3), {}, {});
  n.c2(4) = -10.25;
  try {
    EncodeChromosome(n);
    FAIL() << "no throw";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("c2(4)"), std::string::npos) << e.what();
  }
  std::vector<uint8_t> short_carrier(100, 0);
  n = DecodeChromosome(RandomBits(3), {}, {});
  EXPECT_THROW(EncodeChromosome(n, short_carrier), InputError);
}

TEST(ChromosomeCodec, ValidationNamesTheProblem) {
  std::vector<uint8_t> bits(1414, 0);
  Status s = ValidateChromosome(bits);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.message().find("chromosome length = 1414"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("1415"), std::string::npos);
  bits.assign(kChromosomeBits, 0);
  bits[700] = 2;
  s = ValidateChromosome(bits);
  EXPECT_NE(s.message().find("chromosome[700] = 2"), std::string::npos) << s.message();
  EXPECT_THROW(DecodeChromosome(bits, {}, {}), InputError);
  EXPECT_EQ(DescribeChromosome(bits).rfind("invalid chromosome", 0), 0u);
  bits[700] = 1;
  EXPECT_TRUE(ValidateChromosome(bits).ok());
  EXPECT_EQ(DescribeChromosome(bits).substr(0, 5), "2-2-7");
}

TEST(ChromosomePacking, LsbFirstRoundTrip) {
  const std::vector<uint8_t> bits = RandomBits(11);
  const std::vector<uint8_t> packed = PackBits(bits);
  ASSERT_EQ(packed.size(), 177u);
  for (int i = 0; i < kChromosomeBits; ++i) ASSERT_EQ((packed[i / 8] >> (i % 8)) & 1, bits[i]) << i;
  EXPECT_EQ(UnpackBits(packed, kChromosomeBits), bits);
  std::vector<uint8_t> padded = packed;
  padded.back() |= 0x80;  // bit 1415 + … is padding
  EXPECT_THROW(UnpackBits(padded, kChromosomeBits), InputError);
  EXPECT_THROW(UnpackBits(std::vector<uint8_t>(176), kChromosomeBits), InputError);
}

}  // namespace
}  // namespace pz::model
