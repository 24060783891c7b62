#include "model/chromosome.h"

#include <algorithm>
#include <cmath>

namespace pz::model {

double DecodeWeight(uint32_t code) {
  PZ_CHECK_MSG(code <= kMaxWeightCode, "weight code " + std::to_string(code));
  return kWeightMin + (kWeightMax - kWeightMin) * static_cast<double>(code) / kMaxWeightCode;
}

uint32_t EncodeWeight(double w, const std::string& field) {
  if (!std::isfinite(w) || w < kWeightMin || w > kWeightMax) {
    throw InputError(FieldError(field, w, "must be finite and within the codable range [-10, 10]"));
  }
  const long code = std::lround((w - kWeightMin) * kMaxWeightCode / (kWeightMax - kWeightMin));
  return static_cast<uint32_t>(std::clamp<long>(code, 0, kMaxWeightCode));
}

uint32_t ReadGene(std::span<const uint8_t> bits, int offset, int width) {
  PZ_CHECK(offset >= 0 && width > 0 && width <= 32 &&
           offset + width <= static_cast<int>(bits.size()));
  uint32_t v = 0;
  for (int b = 0; b < width; ++b) v = (v << 1) | (bits[offset + b] != 0 ? 1u : 0u);
  return v;
}

void WriteGene(std::span<uint8_t> bits, int offset, int width, uint32_t value) {
  PZ_CHECK(offset >= 0 && width > 0 && width < 32 &&
           offset + width <= static_cast<int>(bits.size()));
  PZ_CHECK(value < (1u << width));
  for (int b = 0; b < width; ++b)
    bits[offset + b] = static_cast<uint8_t>((value >> (width - 1 - b)) & 1u);
}

Status ValidateChromosome(std::span<const uint8_t> bits) {
  if (bits.size() != static_cast<size_t>(kChromosomeBits)) {
    return InvalidArgument(
        FieldError("chromosome length", bits.size(), "an HGANN chromosome has exactly 1415 bits"));
  }
  for (size_t i = 0; i < bits.size(); ++i) {
    if (bits[i] > 1) {
      return InvalidArgument(FieldError("chromosome[" + std::to_string(i) + "]", int(bits[i]),
                                        "every bit must be 0 or 1"));
    }
  }
  return Status::Ok();
}

int DecodeHiddenCount(std::span<const uint8_t> bits) {
  PZ_CHECK(bits.size() == static_cast<size_t>(kChromosomeBits));
  return kMinHidden + static_cast<int>(ReadGene(bits, kHiddenCountOffset, kHiddenCodeBits));
}

Network DecodeChromosome(std::span<const uint8_t> bits, const InputNormalization& normalization,
                         const ParameterRanges& ranges) {
  ThrowIfError(ValidateChromosome(bits));
  auto tf = [&bits](int offset) {
    return TransferFromCode(static_cast<int>(ReadGene(bits, offset, kTransferCodeBits)));
  };
  auto weight = [&bits](int offset) {
    return DecodeWeight(ReadGene(bits, offset, kWeightCodeBits));
  };
  const int h = DecodeHiddenCount(bits);
  Network n;
  for (int i = 0; i < kNetworkInputs; ++i) n.input_tf[i] = tf(InputTfBit(i));
  for (int j = 0; j < h; ++j) n.hidden_tf.push_back(tf(HiddenTfBit(j)));
  for (int k = 0; k < kNetworkOutputs; ++k) n.output_tf[k] = tf(OutputTfBit(k));
  n.w1.resize(kNetworkInputs, h);
  n.c1.resize(h);
  n.w2.resize(h, kNetworkOutputs);
  n.c2.resize(kNetworkOutputs);
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < kNetworkInputs; ++i) n.w1(i, j) = weight(W1Bit(i, j));
    n.c1(j) = weight(C1Bit(j));
    for (int k = 0; k < kNetworkOutputs; ++k) n.w2(j, k) = weight(W2Bit(j, k));
  }
  for (int k = 0; k < kNetworkOutputs; ++k) n.c2(k) = weight(C2Bit(k));
  n.normalization = normalization;
  n.ranges = ranges;
  return n;
}

std::vector<uint8_t> EncodeChromosome(const Network& network, std::span<const uint8_t> carrier) {
  ThrowIfError(network.Validate());
  std::vector<uint8_t> bits(kChromosomeBits, 0);
  if (!carrier.empty()) {
    Status s = ValidateChromosome(carrier);
    if (!s.ok()) throw InputError(InvalidArgument("carrier: " + s.message()));
    bits.assign(carrier.begin(), carrier.end());  // genes of nodes j ≥ H are kept from here
  }
  auto put_weight = [&bits](int offset, double w, const std::string& field) {
    WriteGene(bits, offset, kWeightCodeBits, EncodeWeight(w, field));
  };
  auto idx = [](const char* name, int a, int b) {
    return std::string(name) + "(" + std::to_string(a) + (b >= 0 ? ", " + std::to_string(b) : "") +
           ")";
  };
  const int h = network.hidden();
  WriteGene(bits, kHiddenCountOffset, kHiddenCodeBits, static_cast<uint32_t>(h - kMinHidden));
  for (int i = 0; i < kNetworkInputs; ++i) {
    WriteGene(bits, InputTfBit(i), kTransferCodeBits, static_cast<uint32_t>(network.input_tf[i]));
  }
  for (int j = 0; j < h; ++j) {
    WriteGene(bits, HiddenTfBit(j), kTransferCodeBits, static_cast<uint32_t>(network.hidden_tf[j]));
  }
  for (int k = 0; k < kNetworkOutputs; ++k) {
    WriteGene(bits, OutputTfBit(k), kTransferCodeBits, static_cast<uint32_t>(network.output_tf[k]));
  }
  for (int j = 0; j < h; ++j) {
    for (int i = 0; i < kNetworkInputs; ++i)
      put_weight(W1Bit(i, j), network.w1(i, j), idx("w1", i, j));
    put_weight(C1Bit(j), network.c1(j), idx("c1", j, -1));
    for (int k = 0; k < kNetworkOutputs; ++k)
      put_weight(W2Bit(j, k), network.w2(j, k), idx("w2", j, k));
  }
  for (int k = 0; k < kNetworkOutputs; ++k) put_weight(C2Bit(k), network.c2(k), idx("c2", k, -1));
  return bits;
}

std::string DescribeChromosome(std::span<const uint8_t> bits) {
  Status s = ValidateChromosome(bits);
  if (!s.ok()) return "invalid chromosome: " + s.message();
  return DecodeChromosome(bits, InputNormalization{}, ParameterRanges{}).Describe();
}

std::vector<uint8_t> PackBits(std::span<const uint8_t> bits) {
  std::vector<uint8_t> packed((bits.size() + 7) / 8, 0);
  for (size_t i = 0; i < bits.size(); ++i) {
    if (bits[i] != 0) packed[i / 8] |= static_cast<uint8_t>(1u << (i % 8));
  }
  return packed;
}

std::vector<uint8_t> UnpackBits(std::span<const uint8_t> packed, int count) {
  if (count < 0 || packed.size() != (static_cast<size_t>(count) + 7) / 8) {
    throw InputError(FieldError("packed bits size", packed.size(),
                                "must be ceil(" + std::to_string(count) + " / 8) bytes"));
  }
  std::vector<uint8_t> bits(count);
  for (int i = 0; i < count; ++i) bits[i] = (packed[i / 8] >> (i % 8)) & 1u;
  for (size_t i = count; i < packed.size() * 8; ++i) {
    if ((packed[i / 8] >> (i % 8)) & 1u) {
      throw InputError(FieldError("packed bit " + std::to_string(i), 1, "padding bits must be 0"));
    }
  }
  return bits;
}

}  // namespace pz::model
