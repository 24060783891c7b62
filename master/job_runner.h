// One job's generation loop, shared by the master's job threads and in-process runs so both are
// the same computation: the project GA (opt/ga.h) configured from the job spec, restored from a
// checkpoint, stepped one generation at a time through any BatchEvaluator.
#pragma once

#include <memory>
#include <string>

#include "opt/evaluator.h"
#include "opt/ga.h"
#include "job/job_kind.h"
#include "service/service_types.h"

namespace pz::master {

inline constexpr int kBestKept = 32;  ///< best individuals stored in each checkpoint

/// The GA options of a job: its GaSettings plus genome length (from the kind), seed, target and
/// penalty cost (from the limits).
using job::ToGaOptions;  // job/job_kind.h

class JobRunner {
 public:
  JobRunner(std::string job_id, job::JobSpec spec);
  ~JobRunner();
  /// Builds the GA; with `resume`, continues from that checkpoint.
  Status Init(const job::JobKindRegistry& kinds, const service::JobCheckpoint* resume = nullptr);
  /// True once the GA's stopping rule holds.
  bool Done() const;
  /// Runs one generation (the first evaluates the initial population) through `evaluator` and
  /// folds it into the checkpoint. If the evaluator was interrupted (cancel, shutdown), the
  /// caller must discard the runner.
  const service::GenerationRecord& Step(opt::BatchEvaluator& evaluator);
  const service::JobCheckpoint& checkpoint() const { return checkpoint_; }
  service::JobCheckpoint& mutable_checkpoint() { return checkpoint_; }
  const job::JobSpec& spec() const { return spec_; }

 private:
  class Forward final : public opt::BatchEvaluator {
   public:
    opt::BatchEvaluator* target = nullptr;
    void Evaluate(const opt::EvalBatch& b, std::span<opt::FitnessResult> out) override {
      target->Evaluate(b, out);
    }
  };
  job::JobSpec spec_;
  Forward forward_;
  std::unique_ptr<opt::GeneticAlgorithm> ga_;
  std::vector<opt::Genome> seeds_;  ///< the kind's seeds of generation 0 (JobKind::seeds)
  const job::JobKindRegistry* kinds_ = nullptr;  ///< Init's (the committee at the end)
  service::JobCheckpoint checkpoint_;
};

/// Runs a whole job in this process (the reference for the service's determinism tests).
Status RunJobInProcess(const std::string& job_id, const job::JobSpec& spec,
                       const job::JobKindRegistry& kinds, service::JobCheckpoint* out);

}  // namespace pz::master
