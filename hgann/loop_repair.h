// The repair of a child whose Bouc–Wen loop is unbounded (issue 47 part 4), the robust preset's
// (job::HgannSearchSettings::repair_loops; `--preset paper` has none: the paper's GA bit for bit).
//
// What fails: the fitness refuses, before any simulation, a network whose (α, β, γ) leave the loop
// unbounded (model::BimorphParams::HysteresisBounded: α = 0, or |γ| < β at the boundary lines of
// bouc_wen.h) at a training case, or, with a spread penalty, at a point of its 5 × 5 grid. With the
// default ranges (β ∈ [0, 0.02], γ ∈ [−0.02, 0.02]) half of the (β, γ) box is unbounded, so a third
// of the robust preset's children were such refusals on the nominal bench (8,812 of 25,600
// evaluations: 8,422 at a training case, 390 on the grid), slots of the GA's budget that carried
// no information but "unbounded".
//
// The rule: a fresh genome (bred, moved or drawn) whose decoded network is unbounded at one of
// those points has its three loop outputs (α, β, γ: outputs 2–4) rewritten, as the output move
// writes outputs (hgann/output_move.h), as constants in the bounded region nearest their mean over
// the training cases: ᾱ kept; β ≥ the margin; γ clamped into (−β, β) with the margin; the margin
// (kMargin of each range) covers what the chromosome's near-zero weights and the bias's
// resolution leave of an output's dependence on the input (≤ 10 · 6.1e-4 in scaled units). Where
// the ranges hold no such (β, γ) (e.g. the paper's Table 3, β ≤ 0), α is set to 0 if 0 is an end
// of its range (a loop-free model is bounded). The input, hidden and other output genes are kept,
// so the child still breeds with the population; a loop constant over the envelope is the
// bench's own (the nominal loop does not vary with V or f), and the trend seeds make the same
// choice (operating_law.cc FlattenLoopIfUnbounded). A genome still unbounded after the rewrite
// (none on the benches of docs/operating-law.md) is left as it is and refused by the fitness.
#pragma once

#include <array>
#include <string_view>
#include <utility>
#include <vector>

#include "hgann/hgann_fitness.h"
#include "model/network.h"
#include "opt/evaluator.h"

namespace pz::hgann {

/// Whether a run of search preset `preset` repairs loops (job::HgannSearchSettings::repair_loops;
/// an unknown name: the default preset's, which validation refuses anyway).
bool HgannRepairsLoops(std::string_view preset);

class LoopRepair {
 public:
  static constexpr double kMargin = 0.01;  ///< share of a range kept from the unbounded region

  /// The problem's normalisation, ranges, training points and (λ > 0) the spread grid's points.
  explicit LoopRepair(const HgannFitnessConfig& config);

  /// opt::GeneticAlgorithm::Repair: rewrites `genome`'s loop outputs when its network's loop is
  /// unbounded at a checked point; true when it did. A genome that does not decode is left alone
  /// (the fitness names its error).
  bool operator()(opt::Genome& genome) const;

  /// The loop is bounded at every checked point (the fitness's refusal, without simulating).
  bool Bounded(const model::Network& network) const;
  /// The scaled constants t_α, t_β, t_γ the rule writes for loop means `mean` (scaled, [0, 1]);
  /// false where the ranges hold no bounded loop the rule can write.
  bool BoundedConstants(const std::array<double, 3>& mean, std::array<double, 3>* t) const;

 private:
  model::InputNormalization normalization_;
  model::ParameterRanges ranges_;
  std::vector<std::pair<double, double>> training_;  ///< (V, f) of each training case
  std::vector<std::pair<double, double>> points_;    ///< every (V, f) checked
};

}  // namespace pz::hgann
