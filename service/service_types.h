// Domain structs of the service protocol (proto/wire.proto decoded by service/wire_codec.h):
// the master, the workers and the client library only handle these, never protobuf types.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "opt/evaluator.h"
#include "opt/ga.h"
#include "io/network_io.h"
#include "job/job_spec.h"
#include "job/law_committee.h"

namespace pz::service {

inline constexpr uint32_t kProtocolVersion = 1;

/// Request outcome; IsTransient() tells the retryable ones apart (wire.proto Code).
enum class WireCode : int {
  kUnspecified = 0,
  kOk = 1,
  kInvalidArgument = 2,
  kNotFound = 3,
  kFailedPrecondition = 4,
  kVersionMismatch = 5,
  kMalformed = 6,
  kUnavailable = 100,
  kDeadlineExceeded = 101,
  kResourceExhausted = 102,
  kInternal = 103,
};
inline bool IsTransient(WireCode c) { return static_cast<int>(c) >= 100; }
const char* WireCodeName(WireCode c);

enum class JobState : int { kUnspecified = 0, kRunning, kSucceeded, kFailed, kCancelled };
const char* JobStateName(JobState s);
inline bool IsFinal(JobState s) { return s != JobState::kRunning && s != JobState::kUnspecified; }

struct ScoredGenome {
  int index = 0;  ///< population index
  opt::Genome genome;
  opt::FitnessResult fitness;
};

/// One generation of a job (proto GenerationRecord; opt/ga.h GenerationSummary).
/// One generation's record (a batch's, for an evaluation session) is the GA's own summary: the
/// service stores, sends and shows it as it is (opt/ga.h).
using GenerationRecord = opt::GenerationSummary;

struct QuarantineRecord {
  uint64_t generation = 0;
  int index = 0;
  uint32_t strikes = 0;
};

struct JobInfo {
  std::string job_id, name, kind;
  JobState state = JobState::kUnspecified;
  uint64_t generation = 0, max_generations = 0;
  double best_cost = 0;
  uint64_t evaluations = 0;
  std::string message;
  std::vector<QuarantineRecord> quarantined;
  double elapsed_s = 0;
  uint64_t seed = 0;
  std::string algorithm;  ///< "ga" or "external" (a session: generation = batches evaluated)
  std::string notice;     ///< what the master repaired on loading the job (names the file), or ""
  std::string storage_error;  ///< checkpoints cannot be written now: why, or ""
  double storage_error_since_unix_s = 0;
  bool archived = false;    ///< ended, kept on disk only: fetch reads it from the state directory
  double ended_unix_s = 0;  ///< when it ended (0 while running)
  std::optional<opt::GaTermination> termination;  ///< the GA's rule, for a GA job that ended by it
};

struct JobEvent {
  std::string job_id;
  JobState state = JobState::kUnspecified;
  std::optional<GenerationRecord> record;
  std::string message;
  int workers = 0, worker_threads = 0;  ///< connected when sent (filled in by the broker)
  std::string storage_error;            ///< the job's checkpoints cannot be written now (JobInfo)
};

// ------------------------------------------------------------------ worker protocol

struct TaskBatchMsg {
  uint64_t lease_id = 0;
  std::string job_id;
  uint64_t generation = 0;
  std::string context_hash;
  std::vector<int> indices;
  std::vector<opt::Genome> genomes;  ///< same length as indices
  double deadline_s = 0;
};

struct BatchResultMsg {
  uint64_t lease_id = 0;
  std::string job_id;
  uint64_t generation = 0;
  std::vector<int> indices;
  std::vector<opt::FitnessResult> results;  ///< same length as indices
  WireCode code = WireCode::kOk;
  std::string error;
  double eval_seconds = 0;
};

/// What travels between a worker and the master (both directions share the struct; `type` says
/// which fields are meaningful).
struct WorkerMsg {
  enum class Type { kReady, kHeartbeat, kDisconnect, kContextRequest, kContext, kBatch, kResult };
  Type type = Type::kHeartbeat;
  int threads = 0;                ///< kReady
  std::string host;               ///< kReady
  int64_t pid = 0;                ///< kReady
  std::string arithmetic;         ///< kReady: model::ArithmeticProfile() of the worker
  std::string reason;             ///< kDisconnect
  std::string context_hash;       ///< kContextRequest, kContext
  std::string context_spec;       ///< kContext: serialised JobSpec
  WireCode code = WireCode::kOk;  ///< kContext (not found), or an error answer
  TaskBatchMsg batch;             ///< kBatch
  BatchResultMsg result;          ///< kResult
};

// ------------------------------------------------------------------ client protocol

struct ClientRequestMsg {
  enum class Type {
    kSubmit,
    kStatus,
    kWatch,
    kCancel,
    kList,
    kFetch,
    kPing,
    kEvaluate,
    kClose,
    kPrune,
    kWorkers
  };
  Type type = Type::kPing;
  uint64_t request_id = 0;
  job::JobSpec spec;       ///< kSubmit (decoded)
  std::string spec_bytes;  ///< kSubmit: the deterministic serialisation of the spec
  std::vector<job::FieldViolation> decode_violations;  ///< kSubmit: fields that did not decode
  std::string client_token;                            ///< kSubmit
  std::string job_id;     ///< kStatus, kWatch, kCancel, kFetch, kEvaluate, kClose
  int count = 1;          ///< kFetch
  bool log_only = false;  ///< kFetch: only the info and the log (records of generations ≥ log_from)
  uint64_t log_from = 0;             ///< kFetch with log_only
  uint64_t batch_seq = 0;            ///< kEvaluate: ≥ 1
  std::vector<opt::Genome> genomes;  ///< kEvaluate: the batch, or empty (a poll)
  std::vector<std::string> job_ids;  ///< kPrune: jobs named
  double older_than_s = 0;           ///< kPrune: ended longer ago than this (> 0)
  int keep = 0;                      ///< kPrune: all but the `keep` most recently ended (> 0)
  bool dry_run = false;              ///< kPrune
};

/// A connected worker as the scheduler sees it (proto WorkerInfo).
struct WorkerView {
  std::string id, host, key, arithmetic;
  int64_t pid = 0;
  int threads = 0;
  double item_seconds = -1;  ///< per task per thread [s]; < 0 unknown
  int leases = 0, tasks_in_flight = 0;
  uint64_t tasks_done = 0;
  double connected_unix_s = 0;
  bool solo = false;
  bool operator==(const WorkerView&) const = default;
};
/// A worker that left (proto WorkerDeparture).
struct WorkerDepartureView {
  std::string id, host, reason;
  int64_t pid = 0;
  double at_unix_s = 0;
  uint64_t tasks_done = 0;
  bool operator==(const WorkerDepartureView&) const = default;
};
/// The master's workers (proto WorkersReply).
struct WorkersSnapshot {
  std::vector<WorkerView> workers;
  std::vector<WorkerDepartureView> departed;  ///< most recent last
  uint64_t leases_sent = 0, tasks_done = 0, results_ignored = 0, bad_frames = 0;
  uint64_t speculative_leases = 0;  ///< copies of straggling leases sent
  uint64_t speculative_wins = 0;    ///< … that answered first for at least one task
  double uptime_s = 0;
  bool operator==(const WorkersSnapshot&) const = default;
};

struct ClientReplyMsg {
  enum class Type { kNone, kSubmit, kStatus, kList, kFetch, kEvent, kEvaluate, kPrune, kWorkers };
  Type type = Type::kNone;
  uint64_t request_id = 0;
  WireCode code = WireCode::kOk;
  std::string error;
  std::vector<job::FieldViolation> violations;
  std::string job_id;                        ///< kSubmit
  bool existed = false;                      ///< kSubmit
  JobInfo info;                              ///< kStatus, kFetch
  std::vector<JobInfo> jobs;                 ///< kList
  int workers = 0, worker_threads = 0;       ///< kList
  std::vector<ScoredGenome> best;            ///< kFetch
  std::vector<GenerationRecord> log;         ///< kFetch
  std::optional<job::JobSpec> spec;          ///< kFetch: the job's spec
  std::vector<io::SavedNetwork> networks;    ///< kFetch: best[i] as networks (hgann), or empty
  std::optional<job::LawCommittee> committee;  ///< kFetch: JobCheckpoint::committee
  JobEvent event;                            ///< kEvent
  uint64_t batch_seq = 0;                    ///< kEvaluate
  bool done = false;                         ///< kEvaluate: results holds the batch's results
  std::vector<opt::FitnessResult> results;   ///< kEvaluate (worker_threads: connected threads)
  std::vector<std::string> pruned;           ///< kPrune: deleted (dry run: would be)
  std::vector<job::FieldViolation> refused;  ///< kPrune: {job id, why not}
  WorkersSnapshot workers_snapshot;          ///< kWorkers
};

}  // namespace pz::service

namespace pz::service {

/// What the master stores per job after each generation.
struct JobCheckpoint {
  std::string job_id;
  JobState state = JobState::kRunning;
  opt::GaState optimizer;  ///< without its log (the log is `log` below)
  std::vector<GenerationRecord> log;
  std::vector<ScoredGenome> best;  ///< best first
  std::string message;
  std::optional<opt::GaTermination> termination;  ///< the GA's rule, for a GA job that ended by it
  std::vector<QuarantineRecord> quarantined;
  double elapsed_s = 0;
  std::string arithmetic;  ///< the profile of the workers that computed it ("" = none recorded)
  /// An hgann job with trend seeds that ended: the law's committee on its best (job kind's
  /// `committee`), computed once before the final state is saved.
  std::optional<job::LawCommittee> committee;
};

}  // namespace pz::service
