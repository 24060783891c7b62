// The sequential batch evaluator, and the guard every evaluator and the GA put around a fitness:
// an exception or a non-finite cost becomes a finite kError result, so that nothing a fitness
// function does can crash an evaluation thread or put a NaN into the population's ranking.
#pragma once

#include <span>

#include "opt/evaluator.h"

namespace pz::opt {

/// Cost given to an individual whose evaluation failed without a penalty of its own.
inline constexpr double kDefaultErrorCost = 1e30;

/// Makes r safe to rank: a non-finite cost becomes error_cost with status kError and a reason
/// naming the bad value ("non-finite cost nan" + the original reason, if any). Returns true if r
/// was changed.
bool SanitizeFitness(FitnessResult& r, double error_cost = kDefaultErrorCost);

/// fitness.Evaluate(genome), with exceptions turned into kError results ("exception: what()")
/// and the result sanitised. Never throws.
FitnessResult EvaluateGuarded(const FitnessFunction& fitness, const Genome& genome,
                              double error_cost = kDefaultErrorCost) noexcept;
/// out[i] = EvaluateGuarded(fitness, *genomes[i], error_cost) for every i, through
/// fitness.EvaluateMany (an exception there: each genome by EvaluateGuarded). Never throws.
void EvaluateManyGuarded(const FitnessFunction& fitness, std::span<const Genome* const> genomes,
                         std::span<FitnessResult> out,
                         double error_cost = kDefaultErrorCost) noexcept;
/// The most genomes one EvaluateMany call takes (a fitness with more lanes gets them in groups of
/// this many).
inline constexpr size_t kMaxLanes = 8;
/// out[i] = EvaluateGuarded(fitness, genomes[i], error_cost) for a run of consecutive genomes (a
/// group of at most fitness.lanes(), as the thread pool and the worker's compute threads take
/// them): side by side through EvaluateManyGuarded in groups of at most kMaxLanes, one alone by
/// EvaluateGuarded. Never throws.
void EvaluateGroupGuarded(const FitnessFunction& fitness, std::span<const Genome> genomes,
                          std::span<FitnessResult> out,
                          double error_cost = kDefaultErrorCost) noexcept;

/// Evaluates a batch in order on the calling thread (tests, single-core runs).
class InlineEvaluator final : public BatchEvaluator {
 public:
  /// `fitness` must outlive the evaluator.
  explicit InlineEvaluator(const FitnessFunction& fitness, double error_cost = kDefaultErrorCost)
      : fitness_(fitness), error_cost_(error_cost) {}
  void Evaluate(const EvalBatch& batch, std::span<FitnessResult> out) override;

 private:
  const FitnessFunction& fitness_;
  double error_cost_;
};

}  // namespace pz::opt
