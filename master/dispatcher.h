// The broker's scheduling core, socket-free and clock-free (takes `now`): which tasks of which job
// go to which worker as a lease, fair sharing between jobs, adaptive batch sizes, lease deadlines,
// re-queueing and quarantine. Tasks are identified by (job, generation, position in the batch).
//
// Rules:
//  * Fairness: the next lease goes to the job with the fewest tasks in flight (ties: the one
//    served longest ago), so concurrent jobs share the workers evenly.
//  * Batch size: enough tasks for `target_batch_s` of the worker's measured speed (whole rounds
//    of its threads), no more than a guided share of what is left (pending × threads / 2·total
//    threads), never below one round of its threads, never above max_batch.
//  * A worker holds at most leases_per_worker leases, or more while it has idle threads.
//  * Deadline: now + rounds × task_timeout_s, rounds = ⌈tasks held by the worker / threads⌉.
//  * Re-queue with a strike when the holder dies or the deadline passes; a struck task is then
//    leased alone, so further strikes are its own; at quarantine_after strikes it is quarantined.
//  * Results count once: a position already done, or a lease no longer held by the sender, or an
//    old generation, is ignored.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "service/liveness.h"

namespace pz::master {

struct DispatchOptions {
  double target_batch_s = 0.25;  ///< wall time a batch should keep a worker busy [s]
  int max_batch = 4096;          ///< tasks per lease, ≥ 1
  int leases_per_worker = 2;     ///< pipelining depth, ≥ 1
};

struct Lease {
  uint64_t id = 0;
  std::string worker;
  std::string job_id;
  uint64_t generation = 0;
  std::vector<int> positions;
  service::TimePoint granted{}, deadline{};
};

/// A task quarantined by Requeue.
struct Quarantined {
  std::string job_id;
  uint64_t generation = 0;
  int position = 0;
  int strikes = 0;
};

class Dispatcher {
 public:
  explicit Dispatcher(DispatchOptions options = {}, uint64_t first_lease_id = 1);

  // ---- jobs
  /// Starts a job's generation of `tasks` tasks (replacing its previous one).
  void StartGeneration(const std::string& job_id, uint64_t generation, int tasks,
                       double task_timeout_s, int quarantine_after);
  /// Forgets the job; its outstanding leases are dropped (their results will be ignored).
  void RemoveJob(const std::string& job_id);
  /// Tasks of the job's generation not yet done (0 if unknown).
  int remaining(const std::string& job_id) const;
  /// Marks a task done; false when it was already done or (job, generation) is not current.
  bool MarkDone(const std::string& job_id, uint64_t generation, int position);

  // ---- workers
  void AddWorker(const std::string& id, int threads);
  bool HasWorker(const std::string& id) const { return workers_.count(id) > 0; }
  /// Removes a worker and re-queues its leases (with a strike when `strike`).
  std::vector<Quarantined> RemoveWorker(const std::string& id, bool strike);
  int worker_count() const { return static_cast<int>(workers_.size()); }
  int total_threads() const { return total_threads_; }

  // ---- leases
  /// The next lease to send, or nullopt when no worker has room or no task is pending.
  std::optional<Lease> NextLease(service::TimePoint now);
  /// Completes a lease held by `worker`; nullopt if it is not (ignored result). Updates the
  /// worker's speed estimate from the summed evaluation time of its tasks.
  std::optional<Lease> Complete(const std::string& worker, uint64_t lease_id, double eval_seconds);
  /// Re-queues the tasks of a lease that are not done (a strike each when `strike`).
  std::vector<Quarantined> Requeue(const Lease& lease, bool strike);
  /// Takes the leases whose deadline has passed, re-queues them with a strike.
  std::vector<Quarantined> ExpireLeases(service::TimePoint now);
  service::TimePoint NextDeadline() const;
  size_t leases_outstanding() const { return leases_.size(); }

  /// Measured time of one evaluation on one thread of the worker [s] (< 0 when unknown).
  double worker_item_seconds(const std::string& id) const;

 private:
  struct JobTasks {
    uint64_t generation = 0;
    int tasks = 0, remaining = 0, in_flight = 0;
    double task_timeout_s = 60;
    int quarantine_after = 3;
    std::deque<int> pending, suspects;
    std::vector<uint8_t> done;
    std::vector<uint16_t> strikes;
    uint64_t last_served = 0;
  };
  struct WorkerSlot {
    int threads = 1;
    double item_s = -1;
    int leases = 0, items = 0;
    uint64_t last_served = 0;
  };
  bool HasRoom(const WorkerSlot& w) const;
  int BatchSize(const WorkerSlot& w, const JobTasks& j) const;
  void Release(const Lease& lease);

  DispatchOptions options_;
  uint64_t next_lease_id_;
  uint64_t serve_counter_ = 0;
  int total_threads_ = 0;
  std::map<std::string, JobTasks> jobs_;
  std::map<std::string, WorkerSlot> workers_;
  std::map<uint64_t, Lease> leases_;
};

}  // namespace pz::master
