// The output move of HGANN (opt/ga.h, file comment 9.): an offspring made in the model's parameter
// space instead of the network's bits.
//
// From a parent network (an island's best): s̄_k = the mean over the training cases of output k
// scaled to [0, 1] (spec hgann.md §1: s_k = (O_k − lo_TF)/(hi_TF − lo_TF)); one step size
// σ = σ_min (σ_max/σ_min)^u, u uniform in [0, 1) (log-uniform: from fine polishing to a jump across
// the range); t_k = clamp(s̄_k + σ z_k, 0, 1) with z_k standard normal (Box–Muller, two draws
// each).
// The child is the parent with its output layer rewritten to give t on every input: each output's
// transfer function satlin, every hidden-to-output weight the code nearest 0 (±6.1e-4) and the
// output bias the code nearest t_k (resolution 1.22e-3 of the range). The input and hidden genes
// are kept, so the child still breeds with the population, and the bits can add back an input
// dependence where the data pay for it.
//
// Why (docs/performance.md, "Islands"): on the nominal bench the islands settle on a plateau with
// α, β, γ at the tops of their ranges (≈ 2.3 deg²), where leaving takes three outputs to change
// together through their transfer functions and weights — what bit flips rarely do, and a step in
// the parameters does directly.
#pragma once

#include <array>
#include <span>
#include <utility>
#include <vector>

#include "hgann/hgann_fitness.h"
#include "opt/evaluator.h"
#include "opt/ga.h"
#include "opt/random.h"
#include "model/network.h"

namespace pz::hgann {

/// The output moves per island of an hgann run: ga.OutputMoves(), except that unset (auto) means
/// none without a spread penalty (λ = 0, the paper's cost). There nothing checks the network
/// between the training cases, and the moves' lineages sit at the edge of a bounded loop (β ≈ γ):
/// with 4 islands, seeds 1 and 3 gave unbounded loops on withheld cases (docs/performance.md,
/// "Islands"). Given explicitly, the count holds at any λ.
int HgannOutputMoves(const opt::GaOptions& ga, double spread_penalty);

class OutputMove {
 public:
  static constexpr double kSigmaMin = 1e-3;  ///< smallest step, share of a range
  static constexpr double kSigmaMax = 0.3;   ///< largest step, share of a range

  /// The problem's input normalisation and training drives. Requires a valid configuration.
  explicit OutputMove(const HgannFitnessConfig& config);

  /// opt::GeneticAlgorithm::Move: writes a moved child of `parent` (a valid chromosome) into each
  /// of `children`, in order; the parent is decoded once.
  void operator()(const opt::Genome& parent, opt::Rng& rng, std::span<opt::Genome> children) const;

  /// s̄: the mean over the training cases of the network's outputs scaled to [0, 1].
  std::array<double, model::kNetworkOutputs> MeanOutputs(const model::Network& network) const;
  /// `bits` (a chromosome) with its output layer giving `t` ∈ [0, 1]⁷ on every input (file
  /// comment).
  static void WriteConstantOutputs(std::vector<uint8_t>* bits,
                                   const std::array<double, model::kNetworkOutputs>& t);
  /// Output k alone: satlin, every hidden-to-output weight the code nearest 0, the bias the code
  /// nearest `t` (unclamped: t < 0 or t > 1 pins the output at a bound of its range exactly).
  static void WriteConstantOutput(std::vector<uint8_t>* bits, int k, double t);

 private:
  model::InputNormalization normalization_;
  model::ParameterRanges ranges_;
  std::vector<std::pair<double, double>> training_;  ///< (V, f) of each training case
};

}  // namespace pz::hgann
