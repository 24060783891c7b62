// The client library of the piezoid service: submit / status / watch / list / cancel / fetch over
// ZeroMQ (a DEALER to the master's client endpoint), with per-request timeouts and Lazy-Pirate
// retries (a fresh socket per retry; submissions are idempotent through a client token).
//
//   pz::svcclient::ServiceClient c({.endpoint = "tcp://127.0.0.1:5556"});
//   pz::svcclient::SubmitResult r;
//   std::vector<pz::job::FieldViolation> bad;
//   pz::Status s = c.SubmitJson(json_text, &r, &bad);   // bad: field-named errors
//   c.Watch(r.job_id, [](const pz::service::JobEvent& e) { ...; return true; }, 10min);
//   c.Fetch(r.job_id, 5, &best, &log);
#pragma once

#include <chrono>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "service/security.h"
#include "service/service_types.h"
#include "model/status.h"

namespace pz::svcclient {

struct ServiceClientOptions {
  std::string endpoint = "tcp://127.0.0.1:5556";  ///< the master's client endpoint
  int timeout_ms = 5000;                          ///< per attempt [ms]
  int retries = 3;                                ///< attempts per request, ≥ 1
  /// Watch keeps re-trying an unreachable master (e.g. one being restarted) this long, then gives
  /// up with kUnavailable [s].
  double watch_reconnect_s = 30;
  /// CURVE: this client's key pair and the master's public key (Z85); plain when unset.
  std::optional<service::CurveKeyPair> curve;
  std::string master_public;
  /// A request larger than this is refused here, naming the limit (the master drops the
  /// connection of a sender above its own --max-message-bytes) [bytes].
  int64_t max_message_bytes = 64 << 20;
};

// Errors: a request that gets no answer at all returns kUnavailable, "cannot reach the master at
// <endpoint>: is piezoid-master running? … may require CURVE keys …"; a master that refuses this
// client's CURVE key (or expects another mechanism) returns kUnavailable at once, saying so,
// without retrying; a request above max_message_bytes is kInvalidArgument; the master's answers map
// by StatusFromWire (unknown job → kNotFound, invalid spec → kInvalidArgument with the violations,
// …).

struct SubmitResult {
  std::string job_id;
  bool existed = false;  ///< the same (spec, token) had been submitted before
};

class ServiceClient {
 public:
  explicit ServiceClient(ServiceClientOptions options = {});
  ~ServiceClient();

  /// Submits a job. On CODE_INVALID_ARGUMENT returns kInvalidArgument and the field errors.
  /// An empty token is replaced by a random one (retries of this call reuse it).
  Status Submit(const job::JobSpec& spec, SubmitResult* out,
                std::vector<job::FieldViolation>* violations = nullptr,
                std::string client_token = {});
  /// Parses a protobuf-JSON job spec (examples/) and submits it.
  Status SubmitJson(const std::string& json, SubmitResult* out,
                    std::vector<job::FieldViolation>* violations = nullptr,
                    std::string client_token = {});
  Status GetStatus(const std::string& job_id, service::JobInfo* info);
  Status List(std::vector<service::JobInfo>* jobs, int* workers = nullptr,
              int* worker_threads = nullptr);
  Status Cancel(const std::string& job_id);
  /// The connected workers (threads, speed, leases, tasks done) and the recent departures.
  Status Workers(service::WorkersSnapshot* out);
  /// A job's info and the records of its log from generation `from_generation` on (a live view's
  /// poll: no individuals, spec or networks travel).
  Status FetchLog(const std::string& job_id, uint64_t from_generation, service::JobInfo* info,
                  std::vector<service::GenerationRecord>* log);
  /// Deletes ended jobs from the master (see proto PruneRequest): those named, or by age / count.
  /// *pruned: deleted (dry run: would be); *refused: {job id, why not}.
  Status Prune(const std::vector<std::string>& job_ids, double older_than_s, int keep, bool dry_run,
               std::vector<std::string>* pruned, std::vector<job::FieldViolation>* refused);
  /// The best `count` individuals (best first, at most 32), the generation log, the job's state
  /// and its spec (any output may be nullptr).
  /// The job's best `count` (1 … 32) individuals, its log, status and spec, and for kinds whose
  /// genomes are networks (hgann) those networks as the master decoded them (`networks`), and for
  /// an ended hgann job with trend seeds the law's committee on its best (`committee`; nullopt
  /// otherwise).
  Status Fetch(const std::string& job_id, int count, std::vector<service::ScoredGenome>* best,
               std::vector<service::GenerationRecord>* log, service::JobInfo* info = nullptr,
               job::JobSpec* spec = nullptr, std::vector<io::SavedNetwork>* networks = nullptr,
               std::optional<job::LawCommittee>* committee = nullptr);
  /// Calls on_event for each pushed event until the job ends (returns Ok), on_event returns
  /// false (Ok) or `timeout` passes (kUnavailable). Survives a master restart (re-watches) that
  /// takes less than options.watch_reconnect_s; a master unreachable for longer is kUnavailable.
  Status Watch(const std::string& job_id,
               const std::function<bool(const service::JobEvent&)>& on_event,
               std::chrono::milliseconds timeout);
  /// Evaluation sessions (JobSpec.external, svcclient/service_evaluator.h): submits batch
  /// `batch_seq` of a session (genomes non-empty; a retry is a poll) or polls it (genomes empty).
  /// *done says whether *results holds its results (one per genome). A batch the master does not
  /// hold is kNotFound: send it again with its genomes.
  Status Evaluate(const std::string& job_id, uint64_t batch_seq,
                  const std::vector<opt::Genome>& genomes, bool* done,
                  std::vector<opt::FitnessResult>* results, int* worker_threads = nullptr);
  /// Ends an evaluation session: it succeeds (a retried close of a succeeded session is Ok).
  Status Close(const std::string& job_id);
  /// Waits (polling status) until the job is final; its last info in *info.
  Status WaitFinal(const std::string& job_id, std::chrono::milliseconds timeout,
                   service::JobInfo* info = nullptr);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// pz::Status for a reply's wire code (transient codes → kUnavailable).
Status StatusFromWire(service::WireCode code, const std::string& error);

}  // namespace pz::svcclient
