#include "hgann/loop_repair.h"

#include <algorithm>

#include "hgann/output_move.h"
#include "job/job_spec.h"
#include "model/chromosome.h"

namespace pz::hgann {

namespace {
constexpr int kAlpha = 2, kBeta = 3, kGamma = 4;  // output order μ, δ, α, β, γ, a1, a2
}  // namespace

LoopRepair::LoopRepair(const HgannFitnessConfig& config)
    : normalization_(config.normalization), ranges_(config.ranges) {
  for (const HgannCase& c : config.cases)
    if (c.training) training_.emplace_back(c.drive.amplitude_v, c.drive.frequency_hz);
  points_ = training_;
  if (config.spread_penalty > 0)
    for (const auto& p : HgannFitness::EnvelopeGrid(config.normalization)) points_.push_back(p);
}

bool HgannRepairsLoops(std::string_view preset) {
  return job::HgannSearchPreset(preset).value_or(*job::HgannSearchPreset("")).repair_loops;
}

bool LoopRepair::Bounded(const model::Network& network) const {
  for (const auto& [v, f] : points_)
    if (!LoopBounded(network.Predict(v, f))) return false;
  return true;
}

bool LoopRepair::BoundedConstants(const std::array<double, 3>& mean,
                                  std::array<double, 3>* t) const {
  const model::ParameterRange &rb = ranges_[kBeta], &rg = ranges_[kGamma], &ra = ranges_[kAlpha];
  const double wb = rb.upper - rb.lower, wg = rg.upper - rg.lower;
  const double mb = kMargin * wb, mg = kMargin * wg;
  *t = mean;
  // |γ| + its margin < β − β's margin, inside both ranges by their margins.
  const double beta = std::clamp(std::max(rb.lower + mean[1] * wb, 2 * (mb + mg)),
                                 rb.lower + mb, rb.upper - mb);
  const double g = beta - mb - mg;
  const double lo = std::max(rg.lower + mg, -g), hi = std::min(rg.upper - mg, g);
  if (wb > 0 && wg > 0 && g > 0 && lo <= hi) {
    (*t)[1] = (beta - rb.lower) / wb;
    (*t)[2] = (std::clamp(rg.lower + mean[2] * wg, lo, hi) - rg.lower) / wg;
    return true;
  }
  // No bounded (β, γ) in the ranges: α = 0 (a loop-free model), where 0 is an end of α's range
  // (the bias beyond the end by the margin: satlin pins the output there exactly).
  if (ra.lower == 0 && ra.upper > 0) (*t)[0] = -kMargin;
  else if (ra.upper == 0 && ra.lower < 0) (*t)[0] = 1 + kMargin;
  else return false;
  return true;
}

bool LoopRepair::operator()(opt::Genome& genome) const {
  if (!model::ValidateChromosome(genome.bits).ok()) return false;
  model::Network net;
  try {
    net = model::DecodeChromosome(genome.bits, normalization_, ranges_);
    if (Bounded(net)) return false;
  } catch (const InputError&) {
    return false;
  }
  std::array<double, 3> mean{};
  for (const auto& [v, f] : training_) {
    const model::NetworkActivations a = net.Forward(v, f);
    for (int k = 0; k < 3; ++k) mean[k] += a.s[kAlpha + k];
  }
  for (double& m : mean) m /= static_cast<double>(std::max<size_t>(1, training_.size()));
  std::array<double, 3> t{};
  if (!BoundedConstants(mean, &t)) return false;
  std::vector<uint8_t> bits = genome.bits;
  for (int k = 0; k < 3; ++k) OutputMove::WriteConstantOutput(&bits, kAlpha + k, t[k]);
  if (!Bounded(model::DecodeChromosome(bits, normalization_, ranges_))) return false;
  genome.bits = std::move(bits);
  return true;
}

}  // namespace pz::hgann
