#include "master/session.h"

#include <algorithm>
#include <cmath>

#include "master/job_runner.h"

namespace pz::master {

using job::ExternalSettings;
using job::GenomeLayout;
using opt::BatchEvaluator;
using opt::FitnessResult;
using opt::FitnessStatus;
using opt::Genome;
using service::ClientReplyMsg;
using service::ClientRequestMsg;
using service::GenerationRecord;
using service::JobCheckpoint;
using service::ScoredGenome;
using service::WireCode;

Session::Session(std::string job_id, ExternalSettings settings, GenomeLayout layout,
                 std::string kind)
    : job_id_(std::move(job_id)),
      settings_(std::move(settings)),
      layout_(layout),
      kind_(std::move(kind)),
      last_request_(std::chrono::steady_clock::now()) {}

ClientReplyMsg Session::Error(const ClientRequestMsg& req, WireCode code,
                              std::string message) const {
  ClientReplyMsg r;
  r.request_id = req.request_id;
  r.code = code;
  r.error = std::move(message);
  return r;
}

void Session::Touch() {
  std::lock_guard lock(mu_);
  last_request_ = std::chrono::steady_clock::now();
}

void Session::Close() {
  {
    std::lock_guard lock(mu_);
    closed_ = true;
    last_request_ = std::chrono::steady_clock::now();
  }
  cv_.notify_all();
}

ClientReplyMsg Session::Evaluate(const ClientRequestMsg& req) {
  if (req.batch_seq == 0)
    return Error(req, WireCode::kInvalidArgument, "batch_seq = 0: must be >= 1");
  if (req.genomes.size() > static_cast<size_t>(kMaxSessionBatch))
    return Error(req, WireCode::kInvalidArgument,
                 "genomes: " + std::to_string(req.genomes.size()) + " in one batch, at most " +
                     std::to_string(kMaxSessionBatch));
  for (size_t i = 0; i < req.genomes.size(); ++i) {
    const Genome& g = req.genomes[i];
    if (g.bits.size() != static_cast<size_t>(layout_.bits) ||
        g.reals.size() != static_cast<size_t>(layout_.reals))
      return Error(req, WireCode::kInvalidArgument,
                   "genomes[" + std::to_string(i) + "] has " + std::to_string(g.bits.size()) +
                       " bits and " + std::to_string(g.reals.size()) + " reals: the " + kind_ +
                       " genomes of session " + job_id_ + " have " + std::to_string(layout_.bits) +
                       " bits and " + std::to_string(layout_.reals) + " reals");
  }
  ClientReplyMsg r;
  r.request_id = req.request_id;
  r.code = WireCode::kOk;
  r.type = ClientReplyMsg::Type::kEvaluate;
  r.job_id = job_id_;
  r.batch_seq = req.batch_seq;
  bool wake = false;
  {
    std::lock_guard lock(mu_);
    last_request_ = std::chrono::steady_clock::now();
    if (closed_)
      return Error(req, WireCode::kFailedPrecondition, "session " + job_id_ + " is closed");
    auto it = batches_.find(req.batch_seq);
    if (it == batches_.end()) {
      if (req.genomes.empty())
        return Error(req, WireCode::kNotFound,
                     "batch_seq = " + std::to_string(req.batch_seq) + ": session " + job_id_ +
                         " does not hold this batch (send it with its genomes)");
      Batch b;
      b.genomes = req.genomes;
      batches_.emplace(req.batch_seq, std::move(b));
      queue_.push_back(req.batch_seq);
      wake = true;
    } else if (!req.genomes.empty() && !(req.genomes == it->second.genomes)) {
      return Error(req, WireCode::kInvalidArgument,
                   "batch_seq = " + std::to_string(req.batch_seq) + ": session " + job_id_ +
                       " holds another batch under this number");
    } else if (it->second.done) {
      r.done = true;
      r.results = it->second.results;
    }
  }
  if (wake) cv_.notify_all();
  return r;
}

Session::End Session::Run(BatchEvaluator& evaluator, uint64_t generation,
                          const std::function<bool()>& stop,
                          const std::function<bool(uint64_t, std::span<const Genome>,
                                                   std::span<const FitnessResult>)>& on_batch) {
  const auto idle = std::chrono::duration<double>(settings_.idle_timeout_s);
  for (;;) {
    uint64_t seq = 0;
    std::vector<Genome> genomes;
    {
      std::unique_lock lock(mu_);
      for (;;) {
        if (stop()) return End::kStopped;
        if (!queue_.empty()) break;
        if (closed_) return End::kClosed;
        if (std::chrono::steady_clock::now() - last_request_ > idle) return End::kIdle;
        cv_.wait_for(lock, std::chrono::milliseconds(100));
      }
      seq = queue_.front();
      queue_.pop_front();
      genomes = batches_.at(seq).genomes;
    }
    std::vector<int> indices(genomes.size());
    for (size_t i = 0; i < indices.size(); ++i) indices[i] = static_cast<int>(i);
    std::vector<FitnessResult> results(genomes.size());
    evaluator.Evaluate({generation++, genomes, indices}, results);
    if (stop()) return End::kStopped;
    if (!on_batch(seq, genomes, results)) return End::kStopped;
    {
      std::lock_guard lock(mu_);
      Batch& b = batches_.at(seq);
      b.results = std::move(results);
      b.done = true;  // b.genomes stay: a retry of the submission is recognised as a poll
      // Keep the last kSessionBatchesHeld completed batches.
      int done = 0;
      for (auto it = batches_.rbegin(); it != batches_.rend(); ++it) done += it->second.done;
      for (auto it = batches_.begin(); it != batches_.end() && done > kSessionBatchesHeld;) {
        if (it->second.done) {
          it = batches_.erase(it);
          --done;
        } else {
          ++it;
        }
      }
    }
  }
}

const GenerationRecord& FoldSessionBatch(JobCheckpoint& c, std::span<const Genome> genomes,
                                         std::span<const FitnessResult> results,
                                         double wall_time_s) {
  GenerationRecord rec;
  rec.generation = c.log.size() + 1;
  rec.evaluations = static_cast<int>(results.size());
  c.optimizer.evaluations += static_cast<int64_t>(results.size());
  rec.evaluations_total = c.optimizer.evaluations;
  double sum = 0;
  rec.best_cost = results.empty() ? 0 : INFINITY;
  rec.worst_cost = results.empty() ? 0 : -INFINITY;
  for (const FitnessResult& r : results) {
    rec.best_cost = std::min(rec.best_cost, r.cost);
    rec.worst_cost = std::max(rec.worst_cost, r.cost);
    sum += r.cost;
    if (r.status != FitnessStatus::kOk) {
      ++rec.failures;
      rec.penalized += r.status == FitnessStatus::kPenalized;
      rec.errors += r.status == FitnessStatus::kError;
      rec.quarantined += r.reason == "quarantined";
      ++rec.failure_reasons[r.reason];
    }
  }
  c.optimizer.failures += rec.failures;
  rec.mean_cost = results.empty() ? 0 : sum / static_cast<double>(results.size());
  if (!results.empty()) {  // the batch's median cost
    std::vector<double> costs;
    costs.reserve(results.size());
    for (const FitnessResult& r : results) costs.push_back(r.cost);
    std::sort(costs.begin(), costs.end());
    const double lo = costs[(costs.size() - 1) / 2], hi = costs[costs.size() / 2];
    rec.median_cost = lo + (hi - lo) / 2;
  }
  rec.wall_time_s = wall_time_s;
  const double before = c.best.empty() ? INFINITY : c.best.front().fitness.cost;
  // Best individuals seen: merge this batch in (stable: earlier batches first on ties).
  std::vector<ScoredGenome> merged = c.best;
  for (size_t i = 0; i < results.size(); ++i) {
    FitnessResult f = results[i];
    f.residuals.clear();
    merged.push_back({static_cast<int>(i), genomes[i], std::move(f)});
  }
  std::stable_sort(merged.begin(), merged.end(), [](const ScoredGenome& a, const ScoredGenome& b) {
    return a.fitness.cost < b.fitness.cost;
  });
  if (merged.size() > static_cast<size_t>(kBestKept)) merged.resize(kBestKept);
  c.best = std::move(merged);
  const double after = c.best.empty() ? INFINITY : c.best.front().fitness.cost;
  rec.improved = after < before;
  const uint32_t last_stall = c.log.empty() ? 0 : c.log.back().stall;
  rec.stall = rec.improved ? 0 : last_stall + 1;
  c.elapsed_s += wall_time_s;
  c.log.push_back(std::move(rec));
  return c.log.back();
}

}  // namespace pz::master
