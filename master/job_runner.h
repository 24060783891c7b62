// One job's generation loop, shared by the master's job threads and in-process runs so both are
// the same computation: the project GA (master/ga.h) configured from the job spec, restored from a
// checkpoint, stepped one generation at a time through any BatchEvaluator.
#pragma once

#include <memory>
#include <string>

#include "master/evaluator.h"
#include "master/ga.h"
#include "master/job_kinds.h"
#include "master/service_types.h"

namespace pz::master {

inline constexpr int kBestKept = 32;  ///< best individuals stored in each checkpoint

/// The GA options of a job: its GaSettings plus genome length (from the kind), seed, target and
/// penalty cost (from the limits).
GaOptions ToGaOptions(const JobSpec& spec, const GenomeLayout& layout);

class JobRunner {
 public:
  JobRunner(std::string job_id, JobSpec spec);
  ~JobRunner();
  /// Builds the GA; with `resume`, continues from that checkpoint.
  Status Init(const JobKindRegistry& kinds, const JobCheckpoint* resume = nullptr);
  /// True once the GA's stopping rule holds.
  bool Done() const;
  /// Runs one generation (the first evaluates the initial population) through `evaluator` and
  /// folds it into the checkpoint. If the evaluator was interrupted (cancel, shutdown), the
  /// caller must discard the runner.
  const GenerationRecord& Step(BatchEvaluator& evaluator);
  const JobCheckpoint& checkpoint() const { return checkpoint_; }
  JobCheckpoint& mutable_checkpoint() { return checkpoint_; }
  const JobSpec& spec() const { return spec_; }

 private:
  class Forward final : public BatchEvaluator {
   public:
    BatchEvaluator* target = nullptr;
    void Evaluate(const EvalBatch& b, std::span<FitnessResult> out) override {
      target->Evaluate(b, out);
    }
  };
  JobSpec spec_;
  Forward forward_;
  std::unique_ptr<GeneticAlgorithm> ga_;
  JobCheckpoint checkpoint_;
};

/// Runs a whole job in this process (the reference for the service's determinism tests).
Status RunJobInProcess(const std::string& job_id, const JobSpec& spec,
                       const JobKindRegistry& kinds, JobCheckpoint* out);

}  // namespace pz::master
