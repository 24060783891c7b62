// Evaluates a batch on N persistent std::threads of this process. Dynamic partition: each thread
// takes the next unevaluated genome from an atomic counter and writes its result into that
// genome's own slot, so the results do not depend on N or on which thread finished first (the
// fitness is a pure function of the genome).
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>
#include <span>
#include <thread>
#include <vector>

#include "opt/evaluator.h"
#include "opt/inline_evaluator.h"

namespace pz::opt {

class ThreadPoolEvaluator final : public BatchEvaluator {
 public:
  /// Starts `threads` worker threads (≥ 1; 0 means std::thread::hardware_concurrency(), at least
  /// 1). `fitness` must be thread-safe and outlive the evaluator. Throws InputError if threads < 0.
  explicit ThreadPoolEvaluator(const FitnessFunction& fitness, int threads = 0,
                               double error_cost = kDefaultErrorCost);
  /// Stops and joins the threads.
  ~ThreadPoolEvaluator() override;
  ThreadPoolEvaluator(const ThreadPoolEvaluator&) = delete;
  ThreadPoolEvaluator& operator=(const ThreadPoolEvaluator&) = delete;

  /// Blocks until every genome of the batch is evaluated. Concurrent calls are serialised.
  void Evaluate(const EvalBatch& batch, std::span<FitnessResult> out) override;
  int concurrency() const override { return static_cast<int>(workers_.size()); }

 private:
  void WorkerLoop();

  const FitnessFunction& fitness_;
  const double error_cost_;
  std::mutex evaluate_mu_;  // one batch at a time
  std::mutex mu_;
  std::condition_variable work_cv_;
  std::condition_variable done_cv_;
  // The current batch, guarded by mu_ (published with epoch_).
  std::span<const Genome> genomes_;
  std::span<FitnessResult> out_;
  uint64_t epoch_ = 0;
  int active_ = 0;
  bool stop_ = false;
  std::atomic<size_t> next_{0};
  std::vector<std::thread> workers_;
};

}  // namespace pz::opt
