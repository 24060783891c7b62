// The batch-evaluator seam (conventions 7, 9): the GA hands a batch of genomes to an evaluator and
// gets one FitnessResult per genome back. Implementations: inline (tests), threaded (one machine),
// and the broker-backed one (the distributed service). Results must not depend on which evaluator,
// how many threads or workers, or the order in which they finish: a fitness is a pure function of
// (genome, job context).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

namespace pz::opt {

/// A genome: binary genes one bit per byte (0/1), and/or real-coded genes.
struct Genome {
  std::vector<uint8_t> bits;
  std::vector<double> reals;
  bool operator==(const Genome&) const = default;
};

enum class FitnessStatus : int {
  kOk = 0,
  kPenalized = 1,  ///< physically invalid (unbounded loop, failed solve): finite penalty cost
  kError = 2,      ///< evaluation error (e.g. malformed genome) or quarantined: penalty cost
};

struct FitnessResult {
  double cost = 0;  ///< finite always; lower is better
  FitnessStatus status = FitnessStatus::kOk;
  std::string reason;  ///< empty when ok
  /// The residual vector behind the cost, for least-squares optimisers (job kinds that are asked
  /// for it: diagnose with `residuals`); empty for GA kinds, so the hot path carries nothing.
  std::vector<double> residuals{};
};

/// A pure, thread-safe fitness function of one genome.
class FitnessFunction {
 public:
  virtual ~FitnessFunction() = default;
  virtual FitnessResult Evaluate(const Genome& genome) const = 0;
  /// How many genomes EvaluateMany takes at once to gain from it (simulations run side by side in
  /// one thread); 1 = none. The thread pool then hands its threads that many at a time.
  virtual int lanes() const { return 1; }
  /// out[i] = Evaluate(*genomes[i]) for every i, bit for bit (the default calls Evaluate).
  virtual void EvaluateMany(std::span<const Genome* const> genomes,
                            std::span<FitnessResult> out) const {
    for (size_t i = 0; i < genomes.size(); ++i) out[i] = Evaluate(*genomes[i]);
  }
};

/// One batch: the genomes of a generation that need evaluating, with their population indices.
struct EvalBatch {
  uint64_t generation = 0;
  std::span<const Genome> genomes;
  std::span<const int> indices;  ///< population index of each genome (same length)
};

class BatchEvaluator {
 public:
  virtual ~BatchEvaluator() = default;
  /// Fills out[i] with the fitness of batch.genomes[i]; out.size() == batch.genomes.size().
  virtual void Evaluate(const EvalBatch& batch, std::span<FitnessResult> out) = 0;
  /// Worker threads or processes available (for progress reports), ≥ 1.
  virtual int concurrency() const { return 1; }
};

}  // namespace pz::opt
