#include "opt/inline_evaluator.h"

#include <algorithm>
#include <cmath>
#include <exception>
#include <sstream>

#include "model/status.h"

namespace pz::opt {

bool SanitizeFitness(FitnessResult& r, double error_cost) {
  if (std::isfinite(r.cost)) return false;
  std::ostringstream os;
  os << "non-finite cost " << r.cost;
  if (!r.reason.empty()) os << " (" << r.reason << ")";
  r.cost = error_cost;
  r.status = FitnessStatus::kError;
  r.reason = os.str();
  return true;
}

FitnessResult EvaluateGuarded(const FitnessFunction& fitness, const Genome& genome,
                              double error_cost) noexcept {
  FitnessResult r;
  try {
    r = fitness.Evaluate(genome);
  } catch (const std::exception& e) {
    r = {error_cost, FitnessStatus::kError, std::string("exception: ") + e.what()};
  } catch (...) {
    r = {error_cost, FitnessStatus::kError, "exception: unknown"};
  }
  SanitizeFitness(r, error_cost);
  return r;
}

void EvaluateManyGuarded(const FitnessFunction& fitness, std::span<const Genome* const> genomes,
                         std::span<FitnessResult> out, double error_cost) noexcept {
  try {
    fitness.EvaluateMany(genomes, out);
    for (FitnessResult& r : out) SanitizeFitness(r, error_cost);
  } catch (...) {
    for (size_t i = 0; i < genomes.size(); ++i)
      out[i] = EvaluateGuarded(fitness, *genomes[i], error_cost);
  }
}

void EvaluateGroupGuarded(const FitnessFunction& fitness, std::span<const Genome> genomes,
                          std::span<FitnessResult> out, double error_cost) noexcept {
  const Genome* group[kMaxLanes];
  for (size_t i = 0; i < genomes.size(); i += kMaxLanes) {
    const size_t m = std::min(kMaxLanes, genomes.size() - i);
    if (m == 1) {
      out[i] = EvaluateGuarded(fitness, genomes[i], error_cost);
      continue;
    }
    for (size_t j = 0; j < m; ++j) group[j] = &genomes[i + j];
    EvaluateManyGuarded(fitness, std::span<const Genome* const>(group, m), out.subspan(i, m),
                        error_cost);
  }
}

void InlineEvaluator::Evaluate(const EvalBatch& batch, std::span<FitnessResult> out) {
  PZ_CHECK(out.size() == batch.genomes.size());
  for (size_t i = 0; i < batch.genomes.size(); ++i) {
    out[i] = EvaluateGuarded(fitness_, batch.genomes[i], error_cost_);
  }
}

}  // namespace pz::opt
