#include "hgann/output_move.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <span>

#include "model/chromosome.h"

namespace pz::hgann {

int HgannOutputMoves(const opt::GaOptions& ga, double spread_penalty) {
  if (ga.output_moves == opt::GaOptions::kAutoOutputMoves && !(spread_penalty > 0)) return 0;
  return ga.OutputMoves();
}

OutputMove::OutputMove(const HgannFitnessConfig& config)
    : normalization_(config.normalization), ranges_(config.ranges) {
  for (const HgannCase& c : config.cases)
    if (c.training) training_.emplace_back(c.drive.amplitude_v, c.drive.frequency_hz);
}

std::array<double, model::kNetworkOutputs> OutputMove::MeanOutputs(
    const model::Network& network) const {
  std::array<double, model::kNetworkOutputs> s{};
  for (const auto& [v, f] : training_) {
    const model::NetworkActivations a = network.Forward(v, f);
    for (int k = 0; k < model::kNetworkOutputs; ++k) s[k] += a.s[k];
  }
  for (double& x : s) x /= static_cast<double>(std::max<size_t>(1, training_.size()));
  return s;
}

void OutputMove::WriteConstantOutputs(std::vector<uint8_t>* bits,
                                      const std::array<double, model::kNetworkOutputs>& t) {
  for (int k = 0; k < model::kNetworkOutputs; ++k)
    WriteConstantOutput(bits, k, std::clamp(t[k], 0.0, 1.0));
}

void OutputMove::WriteConstantOutput(std::vector<uint8_t>* bits, int k, double t) {
  std::span<uint8_t> b(*bits);
  const uint32_t zero = model::EncodeWeight(0.0);
  model::WriteGene(b, model::OutputTfBit(k), model::kTransferCodeBits,
                   static_cast<uint32_t>(model::TransferFunction::kSatlin));
  for (int j = 0; j < model::kMaxHidden; ++j)
    model::WriteGene(b, model::W2Bit(j, k), model::kWeightCodeBits, zero);
  model::WriteGene(b, model::C2Bit(k), model::kWeightCodeBits, model::EncodeWeight(t));
}

void OutputMove::operator()(const opt::Genome& parent, opt::Rng& rng,
                            std::span<opt::Genome> children) const {
  if (children.empty()) return;
  const std::array<double, model::kNetworkOutputs> mean =
      MeanOutputs(model::DecodeChromosome(parent.bits, normalization_, ranges_));
  for (opt::Genome& child : children) {
    const double sigma = kSigmaMin * std::exp(rng.Uniform01() * std::log(kSigmaMax / kSigmaMin));
    std::array<double, model::kNetworkOutputs> t{};
    for (int k = 0; k < model::kNetworkOutputs; ++k) {
      const double u1 = 1.0 - rng.Uniform01(), u2 = rng.Uniform01();  // u1 in (0, 1]
      const double z = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
      t[k] = std::clamp(mean[k] + sigma * z, 0.0, 1.0);
    }
    child.bits = parent.bits;
    WriteConstantOutputs(&child.bits, t);
  }
}

}  // namespace pz::hgann
