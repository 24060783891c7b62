// The master's transport: one ROUTER for workers, one for clients, one thread owning both
// (conventions 10, 11). Job threads hand it generations to evaluate through BrokerEvaluator (the
// broker-backed BatchEvaluator) and events to push to watching clients; client requests are
// answered by a ClientHandler (the job store). Scheduling is master/dispatcher.h.
//
// Robustness: every frame is decoded into a status, never trusted; a frame above
// max_message_bytes is refused by ZeroMQ (ZMQ_MAXMSGSIZE drops the sender's connection); a bad
// frame gets a typed error answer (CODE_MALFORMED / CODE_VERSION_MISMATCH) and is counted.
//
// Security (docs/service.md, "Security"): with `curve` set both sockets are CURVE servers and a
// ZAP handler (service/security.h) admits only the allowed worker / client keys. Limits on client
// submissions: a spec above max_spec_bytes serialised is refused (CODE_INVALID_ARGUMENT, field
// "spec"), and a client identity (its CURVE key name, or its IP address without CURVE) with
// max_jobs_per_client running jobs gets CODE_RESOURCE_EXHAUSTED.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <span>
#include <string>
#include <thread>
#include <vector>

#include "master/dispatcher.h"
#include "opt/evaluator.h"
#include "service/security.h"
#include "service/service_types.h"
#include "model/status.h"

namespace pz::master {

struct BrokerOptions {
  std::string worker_endpoint = "tcp://127.0.0.1:5555";  ///< "tcp://127.0.0.1:*" = any free port
  std::string client_endpoint = "tcp://127.0.0.1:5556";
  int heartbeat_ms = 500;                ///< heartbeat interval, both ways [ms]
  int liveness = 6;                      ///< missed intervals before a worker is dead
  int64_t max_message_bytes = 64 << 20;  ///< larger frames are refused
  int max_watchers_per_job = 64;
  /// Messages the client socket queues per client at most (ZeroMQ's send high-water mark): a client
  /// that stops reading loses its watch events beyond this, and the master's memory stays bounded
  /// (≈ client_queue × event size × watchers). Workers keep their own, larger queue.
  int client_queue = 1000;
  int64_t max_spec_bytes = 16 << 20;  ///< serialised job spec (with its data) at most
  int max_jobs_per_client = 16;       ///< running jobs submitted by one client identity
  std::optional<service::CurveServerConfig> curve;  ///< CURVE on both endpoints (ZAP-checked keys)
  /// Workers announce their arithmetic profile (model::ArithmeticProfile()): the first one accepted
  /// fixes it for the master's lifetime and a worker announcing another is refused (DISCONNECT with
  /// CODE_INVALID_ARGUMENT), so that no job's results depend on which kind of machine computed
  /// them. True: accept every profile (results bit for bit only among workers of one profile).
  bool allow_mixed_arithmetic = false;
  /// Serve this profile from the start instead of the first worker's, because of `pinned_by` (a job
  /// resumed from the state directory was computed on it; master/checkpoint.h PinnedArithmetic).
  std::string pinned_arithmetic, pinned_by;
  DispatchOptions dispatch;
};

/// Answers client requests (called on the broker thread; must not block for long).
class ClientHandler {
 public:
  virtual ~ClientHandler() = default;
  virtual service::ClientReplyMsg Handle(const service::ClientRequestMsg& request) = 0;
};

/// One generation handed to the broker; completed by the broker thread.
struct EvalTicket {
  std::mutex mu;
  std::condition_variable cv;
  bool finished = false;
  bool interrupted = false;  ///< cancelled or shut down: results are meaningless
  std::string error;         ///< a worker's deterministic error: the job must fail
  std::vector<opt::FitnessResult> results;
  std::vector<service::QuarantineRecord> quarantined;
};

struct BrokerStats {
  int workers = 0, worker_threads = 0;
  uint64_t leases_sent = 0, results_accepted = 0, results_ignored = 0, bad_frames = 0;
  uint64_t tasks_done = 0;
  uint64_t refused_submissions = 0;  ///< spec too large or too many jobs of a client
  uint64_t dropped_watchers = 0;     ///< the oldest watcher of a job at the maximum, for a new one
  uint64_t speculative_leases = 0;   ///< copies of straggling leases sent
  uint64_t speculative_wins = 0;     ///< … that answered first for at least one task
  double eval_seconds = 0;           ///< summed evaluation time the accepted results report [s]
};

class Broker {
 public:
  explicit Broker(BrokerOptions options);
  ~Broker();
  Broker(const Broker&) = delete;
  Broker& operator=(const Broker&) = delete;

  /// Binds both endpoints and starts the broker thread.
  Status Start(ClientHandler* handler);
  /// Stops the thread; outstanding tickets are interrupted.
  void Stop();
  /// The bound endpoints (with the actual port when bound to '*').
  const std::string& worker_endpoint() const { return worker_endpoint_; }
  const std::string& client_endpoint() const { return client_endpoint_; }

  // Thread-safe, for job threads.
  void RegisterJob(const std::string& job_id, const std::string& spec_bytes,
                   const job::JobLimits& limits);
  /// Forgets the job and interrupts its outstanding ticket (cancel).
  void UnregisterJob(const std::string& job_id);
  std::shared_ptr<EvalTicket> Submit(const std::string& job_id, uint64_t generation,
                                     std::span<const opt::Genome> genomes,
                                     std::span<const int> indices);
  void Publish(const service::JobEvent& event);
  BrokerStats stats() const;
  /// The arithmetic profile served ("" until the first worker fixes it, or when mixing is allowed).
  /// Thread-safe.
  std::string served_arithmetic() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::string worker_endpoint_, client_endpoint_;
};

/// The broker-backed BatchEvaluator of one job (blocks until the generation is evaluated).
class BrokerEvaluator final : public opt::BatchEvaluator {
 public:
  BrokerEvaluator(Broker& broker, std::string job_id)
      : broker_(broker), job_id_(std::move(job_id)) {}
  void Evaluate(const opt::EvalBatch& batch, std::span<opt::FitnessResult> out) override;
  int concurrency() const override;
  /// The last Evaluate was interrupted (cancel / shutdown) or failed (error() non-empty).
  bool interrupted() const { return interrupted_; }
  const std::string& error() const { return error_; }
  std::vector<service::QuarantineRecord> TakeQuarantined() { return std::move(quarantined_); }

 private:
  Broker& broker_;
  std::string job_id_;
  bool interrupted_ = false;
  std::string error_;
  std::vector<service::QuarantineRecord> quarantined_;
};

}  // namespace pz::master
