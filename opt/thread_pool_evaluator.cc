#include "opt/thread_pool_evaluator.h"

#include <algorithm>
#include <string>

#include "model/status.h"

namespace pz::opt {
ThreadPoolEvaluator::ThreadPoolEvaluator(const FitnessFunction& fitness, int threads,
                                         double error_cost)
    : fitness_(fitness), error_cost_(error_cost) {
  if (threads < 0) throw InputError(FieldError("threads", threads, "must be >= 0 (0 = all cores)"));
  if (threads == 0) threads = std::max(1u, std::thread::hardware_concurrency());
  workers_.reserve(threads);
  for (int t = 0; t < threads; ++t) workers_.emplace_back([this] { WorkerLoop(); });
}

ThreadPoolEvaluator::~ThreadPoolEvaluator() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stop_ = true;
  }
  work_cv_.notify_all();
  for (std::thread& t : workers_) t.join();
}

void ThreadPoolEvaluator::Evaluate(const EvalBatch& batch, std::span<FitnessResult> out) {
  PZ_CHECK(out.size() == batch.genomes.size());
  if (batch.genomes.empty()) return;
  std::lock_guard<std::mutex> one_batch(evaluate_mu_);
  std::unique_lock<std::mutex> lock(mu_);
  genomes_ = batch.genomes;
  out_ = out;
  next_.store(0, std::memory_order_relaxed);
  active_ = static_cast<int>(workers_.size());
  ++epoch_;
  work_cv_.notify_all();
  done_cv_.wait(lock, [this] { return active_ == 0; });
  genomes_ = {};
  out_ = {};
}

void ThreadPoolEvaluator::WorkerLoop() {
  uint64_t seen = 0;
  for (;;) {
    std::span<const Genome> genomes;
    std::span<FitnessResult> out;
    {
      std::unique_lock<std::mutex> lock(mu_);
      work_cv_.wait(lock, [&] { return stop_ || epoch_ != seen; });
      if (stop_) return;
      seen = epoch_;
      genomes = genomes_;
      out = out_;
    }
    // A fitness with lanes takes that many genomes at a time (the same results as one by one).
    const size_t lanes = static_cast<size_t>(std::max(1, fitness_.lanes()));
    for (size_t i = next_.fetch_add(lanes, std::memory_order_relaxed); i < genomes.size();
         i = next_.fetch_add(lanes, std::memory_order_relaxed)) {
      const size_t m = std::min(lanes, genomes.size() - i);
      EvaluateGroupGuarded(fitness_, genomes.subspan(i, m), out.subspan(i, m), error_cost_);
    }
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (--active_ == 0) done_cv_.notify_one();
    }
  }
}

}  // namespace pz::opt
