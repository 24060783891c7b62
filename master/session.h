// Evaluation sessions (JobSpec.external): an optimiser that lives in a client process sends batches
// of genomes, and the master evaluates each one through its workers exactly as it evaluates a GA
// generation (BrokerEvaluator: leases, retries, quarantine, fair share with the other jobs).
//
// Protocol (wire.proto EvaluateRequest / EvaluateReply, submit + poll): the client numbers its
// batches 1, 2, 3 …; a request with genomes submits a batch (a retry of a held batch is a poll), a
// request without genomes polls it; the reply carries the results once the batch is done. The
// master holds the last few completed batches; a batch it does not hold (restarted master, old
// batch) is answered kNotFound and the client sends it again with its genomes. A session whose
// client sends nothing for external.idle_timeout_s is cancelled; closing it marks it succeeded.
//
// Threads: Submit/Poll/Close/Touch are called on the broker thread (JobStore::Handle) and never
// block; Run is the job's thread.
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <mutex>
#include <span>
#include <string>
#include <vector>

#include "opt/evaluator.h"
#include "job/job_kind.h"
#include "service/service_types.h"

namespace pz::master {

inline constexpr int kMaxSessionBatch = 1000000;  ///< genomes per batch at most
inline constexpr int kSessionBatchesHeld = 4;     ///< completed batches kept for polls

class Session {
 public:
  Session(std::string job_id, job::ExternalSettings settings, job::GenomeLayout layout,
          std::string kind);

  /// An evaluate request (submit or poll): the reply (type kEvaluate, or an error code).
  service::ClientReplyMsg Evaluate(const service::ClientRequestMsg& request);
  /// The client ends the session (it will succeed).
  void Close();
  /// Any request of the client keeps the session alive.
  void Touch();

  enum class End { kClosed, kIdle, kStopped };
  /// The job thread: evaluates batches in order through `evaluator` until the session is closed,
  /// idle too long, or stop() / an interrupted evaluation ends it. After each batch, on_batch gets
  /// its genomes and results (the broker generation is `evaluations so far`-independent: numbered
  /// first_generation, first_generation + 1, …). `stop` is polled at least every 100 ms.
  End Run(opt::BatchEvaluator& evaluator, uint64_t first_generation,
          const std::function<bool()>& stop,
          const std::function<bool(uint64_t batch_seq, std::span<const opt::Genome>,
                                   std::span<const opt::FitnessResult>)>& on_batch);

 private:
  struct Batch {
    std::vector<opt::Genome> genomes;
    std::vector<opt::FitnessResult> results;
    bool done = false;
  };
  service::ClientReplyMsg Error(const service::ClientRequestMsg& req, service::WireCode code,
                                std::string message) const;

  const std::string job_id_;
  const job::ExternalSettings settings_;
  const job::GenomeLayout layout_;
  const std::string kind_;
  std::mutex mu_;
  std::condition_variable cv_;
  std::map<uint64_t, Batch> batches_;  // held: pending and the last completed ones
  std::deque<uint64_t> queue_;         // submitted, not yet evaluated, in arrival order
  bool closed_ = false;
  std::chrono::steady_clock::time_point last_request_;
};

/// Folds one evaluated batch into a session's checkpoint: a GenerationRecord (generation = the
/// number of batches so far, evaluated, best / mean / worst cost, errors, failure reasons), the
/// evaluation count, and the best individuals seen (at most kBestKept, without residuals).
const service::GenerationRecord& FoldSessionBatch(service::JobCheckpoint& checkpoint,
                                                  std::span<const opt::Genome> genomes,
                                                  std::span<const opt::FitnessResult> results,
                                                  double wall_time_s);

}  // namespace pz::master
