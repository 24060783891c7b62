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
//  * Quarantine only on evidence that the task itself kills workers (issue 12.1), never because the
//    cluster churns. A lease lost to a dead worker or a passed deadline makes its unfinished tasks
//    suspects, re-run ALONE: a suspect goes only to an idle worker, which gets nothing else until
//    it answers (if no worker is idle, the least loaded one is drained). Evidence (a strike) is:
//      - the worker running a suspect alone dies, and no other worker (one not running that same
//        task) left the cluster within quiet_window_s before or after: the cluster was otherwise
//        healthy, so the death is the task's; decided quiet_window_s after the death
//        (ConfirmStrikes);
//      - or a suspect running alone passes its deadline while its worker stays alive (a hang).
//    Strikes count once per worker; at quarantine_after strikes the task is quarantined.
//    Under churn, deaths are never isolated, so they never strike: the result stays bit-identical.
//  * Results count once: a position already done, or a lease no longer held by the sender, or an
//    old generation, is ignored.
//  * Stragglers (speculative re-dispatch): once a job has nothing left to hand out, a lease that
//  has
//    run longer than `speculate_after` × the expected time (the generation's median time per task
//    of the leases completed so far × the lease's rounds, and at least `speculate_min_s`) gets one
//    copy, on an idle worker other than its holder. The first answer for each task counts and the
//    other is ignored (results are a function of the genome alone, so the job's result does not
//    change); a copy is never copied again, and a solo (suspect) lease is never copied.
#pragma once

#include <cstdint>
#include <deque>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "service/liveness.h"

namespace pz::master {

using service::Duration;
using service::TimePoint;

struct DispatchOptions {
  double target_batch_s = 0.25;  ///< wall time a batch should keep a worker busy [s]
  int max_batch = 4096;          ///< tasks per lease, ≥ 1
  int leases_per_worker = 2;     ///< pipelining depth, ≥ 1
  /// A death strikes a task only if no other worker left within this long before or after [s].
  double quiet_window_s = 5.0;
  /// A lease running longer than this many times its expected time gets a copy on an idle worker
  /// when its job has nothing else to hand out; 0 = never.
  double speculate_after = 3.0;
  double speculate_min_s = 0.2;  ///< … and at least this long [s]
};

/// Why a lease's tasks go back to the queue.
enum class RequeueCause {
  kTransient,   ///< the worker answered "retry" or left in good order: no suspicion
  kWorkerLost,  ///< the holder died (missed heartbeats): its tasks become suspects
  kDeadline,    ///< the lease passed its deadline with its holder alive: suspects (a hang if alone)
};

struct Lease {
  uint64_t id = 0;
  std::string worker;
  std::string job_id;
  uint64_t generation = 0;
  std::vector<int> positions;
  TimePoint granted{}, deadline{};
  bool solo =
      false;  ///< one suspect on an otherwise idle worker, which gets nothing else meanwhile
  bool speculative = false;  ///< a copy of a straggling lease (see Stragglers above)
  bool copied = false;       ///< a copy of this lease was handed out
  int rounds = 1;            ///< ⌈tasks / the holder's threads⌉ when granted
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
  /// Removes a worker and re-queues its leases: `lost` (it died) makes their tasks suspects and a
  /// solo task a strike candidate (see ConfirmStrikes); otherwise they are simply re-queued.
  void RemoveWorker(const std::string& id, bool lost, TimePoint now);
  int worker_count() const { return static_cast<int>(workers_.size()); }
  int total_threads() const { return total_threads_; }

  // ---- leases
  /// The next lease to send, or nullopt when no worker has room or no task is pending.
  std::optional<Lease> NextLease(TimePoint now);
  /// Completes a lease held by `worker`; nullopt if it is not (ignored result). Updates the
  /// worker's speed estimate from the summed evaluation time of its tasks.
  std::optional<Lease> Complete(const std::string& worker, uint64_t lease_id, double eval_seconds);
  /// Re-queues the tasks of a lease that are not done (see RequeueCause).
  std::vector<Quarantined> Requeue(const Lease& lease, RequeueCause cause, TimePoint now);
  /// Takes the leases whose deadline has passed and re-queues them (a solo one strikes: a hang).
  std::vector<Quarantined> ExpireLeases(TimePoint now);
  /// Decides the strike candidates older than quiet_window_s: a strike each when no other worker
  /// left around its death; returns the tasks quarantined by them.
  std::vector<Quarantined> ConfirmStrikes(TimePoint now);
  /// The earliest lease deadline or strike decision (TimePoint::max() if none).
  TimePoint NextDeadline() const;
  size_t leases_outstanding() const { return leases_.size(); }

  /// Copies of straggling leases handed out since the start.
  uint64_t speculative_leases() const { return speculative_leases_; }

  /// Measured time of one evaluation on one thread of the worker [s] (< 0 when unknown).
  double worker_item_seconds(const std::string& id) const;

  /// What the scheduler holds of a worker now (for the dashboard's worker table).
  struct WorkerLoad {
    std::string id;
    int threads = 0;
    double item_s = -1;  ///< < 0 unknown
    int leases = 0, items = 0;
    bool solo = false;
  };
  std::vector<WorkerLoad> Workers() const;

 private:
  struct JobTasks {
    uint64_t generation = 0;
    int tasks = 0, remaining = 0, in_flight = 0;
    double task_timeout_s = 60;
    int quarantine_after = 3;
    std::deque<int> pending, suspects;
    std::vector<uint8_t> done;
    std::vector<std::vector<std::string>> struck_by;  ///< distinct workers that gave evidence
    uint64_t last_served = 0;
    std::vector<double> task_s;  ///< time per task of each lease of this generation completed [s]
    /// The median of task_s, computed when a straggler check first needs it after a completion
    /// (NextDeadline asks for every lease on every turn of the broker's loop).
    mutable double median_task_s = -1;
  };
  struct WorkerSlot {
    int threads = 1;
    double item_s = -1;
    int leases = 0, items = 0;
    uint64_t last_served = 0;
    bool exclusive = false;  ///< holds a solo lease: nothing else until it answers
  };
  /// A worker that left: the task it was running alone then (none: position < 0), and every
  /// task it held (a task's own deaths never count against its evidence).
  struct Departure {
    std::string worker, job_id;
    uint64_t generation = 0;
    int position = -1;
    TimePoint at{};
    std::vector<std::pair<std::string, uint64_t>> held_jobs;  ///< (job, generation) per lease
    std::vector<std::vector<int>> held;                       ///< its positions, per lease
    bool Held(const std::string& job, uint64_t generation, int position) const;
  };
  bool HasRoom(const WorkerSlot& w) const;
  /// When the lease becomes a straggler (TimePoint::max() if it cannot: a copy, solo, copied, or
  /// no completed lease of its generation to compare with).
  TimePoint StragglerAt(const Lease& l) const;
  /// A copy of a straggling lease for an idle worker, if any.
  std::optional<Lease> Speculate(TimePoint now);
  int BatchSize(const WorkerSlot& w, const JobTasks& j) const;
  void Release(const Lease& lease);
  Lease Grant(const std::string& job_id, JobTasks& job, const std::string& worker_id,
              WorkerSlot& worker, std::vector<int> positions, bool solo, TimePoint now);
  /// Adds one strike of `worker` to a task (once per worker); the quarantine it causes, if any.
  std::optional<Quarantined> Strike(const std::string& job_id, uint64_t generation, int position,
                                    const std::string& worker);
  Duration quiet_window() const;

  DispatchOptions options_;
  uint64_t next_lease_id_;
  uint64_t serve_counter_ = 0;
  int total_threads_ = 0;
  std::map<std::string, JobTasks> jobs_;
  std::map<std::string, WorkerSlot> workers_;
  std::map<uint64_t, Lease> leases_;
  std::deque<Departure> departures_;  ///< recent, oldest first (kept 2 quiet windows)
  std::deque<Departure> candidates_;  ///< solo deaths awaiting ConfirmStrikes, oldest first
  uint64_t speculative_leases_ = 0;
};

}  // namespace pz::master
