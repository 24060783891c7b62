// The HGANN chromosome (spec hgann.md §2): 1415 bits, one bit per byte (0 or 1), genes in this
// order, each gene most significant bit first:
//
//   bits    0 …    2   hidden-node count, H = 2 + code (2 … 9)                  1 × 3 bits
//   bits    3 …   56   transfer functions: input 0–1, hidden 0–8, output 0–6    18 × 3 bits
//   bits   57 …  308   W1, input i to hidden j at gene 9 i + j                  18 × 14 bits
//   bits  309 …  434   c1, hidden biases                                         9 × 14 bits
//   bits  435 … 1316   W2, hidden j to output k at gene 7 j + k                 63 × 14 bits
//   bits 1317 … 1414   c2, output biases                                         7 × 14 bits
//
// A 14-bit weight code c decodes to −10 + 20 c / (2¹⁴ − 1). Genes of hidden nodes j ≥ H are
// carried and inherited but do not enter the network.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "model/network.h"
#include "model/status.h"

namespace pz::model {

inline constexpr int kHiddenCodeBits = 3;
inline constexpr int kTransferCodeBits = 3;
inline constexpr int kWeightCodeBits = 14;
inline constexpr uint32_t kMaxWeightCode = (1u << kWeightCodeBits) - 1;  ///< 16383
inline constexpr double kWeightMin = -10.0;
inline constexpr double kWeightMax = 10.0;
/// Number of transfer-function genes: 2 input + 9 hidden + 7 output.
inline constexpr int kNumTransferGenes = kNetworkInputs + kMaxHidden + kNetworkOutputs;

// Bit offsets of each gene group.
inline constexpr int kHiddenCountOffset = 0;
inline constexpr int kTransferOffset = kHiddenCountOffset + kHiddenCodeBits;                 // 3
inline constexpr int kW1Offset = kTransferOffset + kNumTransferGenes * kTransferCodeBits;    // 57
inline constexpr int kC1Offset = kW1Offset + kNetworkInputs * kMaxHidden * kWeightCodeBits;  // 309
inline constexpr int kW2Offset = kC1Offset + kMaxHidden * kWeightCodeBits;                   // 435
inline constexpr int kC2Offset =
    kW2Offset + kMaxHidden * kNetworkOutputs * kWeightCodeBits;                        // 1317
inline constexpr int kChromosomeBits = kC2Offset + kNetworkOutputs * kWeightCodeBits;  // 1415
static_assert(kChromosomeBits == 1415);

/// First bit of the transfer-function gene of input node i (0 … 1).
constexpr int InputTfBit(int i) { return kTransferOffset + kTransferCodeBits * i; }
/// First bit of the transfer-function gene of hidden node j (0 … 8).
constexpr int HiddenTfBit(int j) {
  return kTransferOffset + kTransferCodeBits * (kNetworkInputs + j);
}
/// First bit of the transfer-function gene of output node k (0 … 6).
constexpr int OutputTfBit(int k) {
  return kTransferOffset + kTransferCodeBits * (kNetworkInputs + kMaxHidden + k);
}
/// First bit of the weight gene W1(i, j).
constexpr int W1Bit(int i, int j) { return kW1Offset + kWeightCodeBits * (kMaxHidden * i + j); }
/// First bit of the bias gene c1(j).
constexpr int C1Bit(int j) { return kC1Offset + kWeightCodeBits * j; }
/// First bit of the weight gene W2(j, k).
constexpr int W2Bit(int j, int k) {
  return kW2Offset + kWeightCodeBits * (kNetworkOutputs * j + k);
}
/// First bit of the bias gene c2(k).
constexpr int C2Bit(int k) { return kC2Offset + kWeightCodeBits * k; }

/// −10 + 20 c / 16383. Requires c ≤ 16383 (checked).
double DecodeWeight(uint32_t code);
/// The nearest code to w (halfway cases round up, std::lround). Throws InputError
/// naming `field` if w is not finite or outside [−10, 10].
uint32_t EncodeWeight(double w, const std::string& field = "weight");

/// Unsigned value of bits[offset … offset + width), most significant bit first. No validation
/// beyond a bounds check (checked); non-zero bytes count as 1.
uint32_t ReadGene(std::span<const uint8_t> bits, int offset, int width);
/// Writes value (< 2^width, checked) at bits[offset …], most significant bit first, as 0/1 bytes.
void WriteGene(std::span<uint8_t> bits, int offset, int width, uint32_t value);

/// Length 1415 and every byte 0 or 1; the error names the first offending index.
Status ValidateChromosome(std::span<const uint8_t> bits);

/// H encoded by a chromosome (2 … 9). Requires a valid length (checked).
int DecodeHiddenCount(std::span<const uint8_t> bits);

/// Bits → network with the given normalisation and ranges (not validated here beyond the bits;
/// call Network::Validate() if they come from outside). Throws InputError on invalid bits.
Network DecodeChromosome(std::span<const uint8_t> bits, const InputNormalization& normalization,
                         const ParameterRanges& ranges);

/// Network → bits, nearest code for each weight. The genes of hidden nodes j ≥ H are copied from
/// `carrier` (a valid chromosome) when given, else all zero, so that
/// EncodeChromosome(DecodeChromosome(b, …), b) == b for every valid b, and
/// DecodeChromosome(EncodeChromosome(n), …) == n for every decoded network n. Throws InputError if
/// the network is invalid, a weight is outside [−10, 10], or the carrier is invalid.
std::vector<uint8_t> EncodeChromosome(const Network& network,
                                      std::span<const uint8_t> carrier = {});

/// Network::Describe() of the decoded chromosome, or the validation error. Never throws.
std::string DescribeChromosome(std::span<const uint8_t> bits);

/// Packs 0/1 bytes into bytes, LSB first as in wire.proto's Genome (bit i is
/// (packed[i / 8] >> (i % 8)) & 1); the last byte is zero-padded.
std::vector<uint8_t> PackBits(std::span<const uint8_t> bits);
/// Inverse of PackBits for `count` bits. Throws InputError if packed has the wrong size or a
/// padding bit is set.
std::vector<uint8_t> UnpackBits(std::span<const uint8_t> packed, int count);

}  // namespace pz::model
