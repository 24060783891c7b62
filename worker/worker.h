// piezoid-worker's engine: stateless evaluation of task batches for a master (conventions 9–11).
// The calling thread is the I/O thread and owns the DEALER socket to the master; `threads`
// compute threads take the leases it queues (a queue under a mutex, in arrival order) and their
// tasks one at a time (an atomic counter per lease; a fitness with lanes() > 1: that many
// consecutive tasks of the lease at a time, side by side, each result the single path's bit for
// bit), going straight on to the next queued lease; the last thread out of a lease tells the I/O
// thread over inproc:// (which replies). They never block heartbeats. Job contexts are fetched
// once by content hash and cached (LRU). When the master falls silent or
// asks, the worker drops its leases (the master re-queues them) and reconnects with back-off.
#pragma once

#include <atomic>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "job/job_kind.h"
#include "service/security.h"

namespace pz::worker {

struct WorkerOptions {
  std::string master = "tcp://127.0.0.1:5555";  ///< the master's worker endpoint
  int threads = 1;                              ///< compute threads, 1..4096
  int heartbeat_ms = 500;                       ///< heartbeat interval; match the master's [ms]
  int liveness = 6;              ///< silent intervals before the master is presumed gone
  int backoff_initial_ms = 100;  ///< first reconnect delay [ms]
  int backoff_max_ms = 5000;     ///< reconnect delay cap [ms]
  int64_t max_message_bytes = 64 << 20;
  int max_contexts = 8;       ///< job contexts cached
  int stop_grace_ms = 10000;  ///< on stop, how long running evaluations may finish [ms]
  /// CURVE: this worker's key pair and the master's public key (Z85); plain when unset.
  std::optional<service::CurveKeyPair> curve;
  std::string master_public;
  /// Announced in READY; empty: model::ArithmeticProfile() of this process.
  std::string arithmetic;
};

struct WorkerStats {
  uint64_t tasks = 0, leases = 0, reconnects = 0, contexts_fetched = 0;
  uint64_t handshake_failures = 0;  ///< e.g. the master refused this worker's CURVE key
  /// Non-empty when the master refused this worker for good (DISCONNECT with CODE_INVALID_ARGUMENT,
  /// e.g. another arithmetic profile than the one it serves): Run returned without retrying.
  std::string refused;
  /// Compute threads still inside an evaluation when Run returned (stop_grace_ms ran out). They
  /// cannot be interrupted, so the Worker keeps everything they use: its destructor leaves it
  /// allocated. The library never ends the process; a program that sees this should (what
  /// piezoid-worker does: it exits at once).
  int stuck_threads = 0;
};

class Worker {
 public:
  Worker(WorkerOptions options, const job::JobKindRegistry& kinds);
  ~Worker();
  /// Serves until `stop` becomes true, then says DISCONNECT, gives running evaluations
  /// stop_grace_ms to finish, and returns (see WorkerStats::stuck_threads).
  WorkerStats Run(const std::atomic<bool>& stop);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace pz::worker
