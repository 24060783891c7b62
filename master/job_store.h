// The master's jobs: validation on submission, one thread per running job (JobRunner over a
// BrokerEvaluator), a checkpoint after every generation, resumption of every unfinished job on
// start, and the answers to client requests.
#pragma once

#include <atomic>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "master/broker.h"
#include "master/checkpoint.h"
#include "master/log_throttle.h"
#include "job/job_kind.h"
#include "master/session.h"

namespace pz::master {

struct JobStoreOptions {
  std::filesystem::path state_dir = "piezoid-state";
  int max_running_jobs = 64;  ///< further submissions are refused (CODE_RESOURCE_EXHAUSTED)
  /// A running job's checkpoint is replaced atomically after every generation (a killed master
  /// resumes from the last generation, bit for bit: the GA's state includes its generator); it is
  /// also made durable (fsync of file and directory, which costs as much as a generation on a
  /// slow disk) at most this often, and always when the job ends or the master shuts down;
  /// 0 = fsync after every generation [s].
  double checkpoint_interval_s = 1.0;
  /// Ended jobs whose whole state (log, best, GA state, spec with its data) stays in memory, the
  /// most recently ended ones; older ones are archived: a summary answers status and list, fetch
  /// reads them from the state directory. `piezoid prune` deletes ended jobs for good.
  int keep_in_memory = 100;
};

class JobStore final : public ClientHandler {
 public:
  JobStore(JobStoreOptions options, Broker& broker, const job::JobKindRegistry& kinds);
  ~JobStore() override;

  /// Loads every stored job and restarts the unfinished ones from their last checkpoint.
  Status Resume();
  service::ClientReplyMsg Handle(const service::ClientRequestMsg& request) override;
  /// Stops the broker and every job thread without changing any job's stored state.
  void Shutdown();

 private:
  struct Job {
    std::string id, spec_bytes;
    job::JobSpec spec;
    std::mutex mu;
    service::JobCheckpoint checkpoint;  // the last saved one
    std::atomic<bool> cancel{false}, shutdown{false};
    std::thread thread;
    std::shared_ptr<Session> session;  // external jobs (evaluation sessions) only
    std::string notice;                // what loading it repaired (JobInfo.notice)
    std::string arithmetic;  // under mu: the profile that computed it (stamped on its checkpoints)
    std::string storage_error;       // under mu: the last checkpoint write failed (JobInfo)
    double storage_error_since = 0;  // under mu: since when [unix s]
    double ended_unix_s = 0;         // under mu: when it ended (0 while running)
    bool archived = false;           // under mu: state on disk only; `summary` answers status
    service::JobInfo summary;        // under mu: when archived
  };
  // One handler per client request (Handle picks it by the request's type).
  service::ClientReplyMsg AnswerSubmit(const service::ClientRequestMsg& req);
  service::ClientReplyMsg AnswerList(const service::ClientRequestMsg& req);
  service::ClientReplyMsg AnswerPrune(const service::ClientRequestMsg& req);
  /// The requests about one job (status, cancel, fetch, evaluate, close): NotFound for an
  /// unknown job id, else the job's handler below.
  service::ClientReplyMsg AnswerAboutJob(const service::ClientRequestMsg& req);
  service::ClientReplyMsg AnswerStatus(const service::ClientRequestMsg& req, Job& job);
  service::ClientReplyMsg AnswerCancel(const service::ClientRequestMsg& req, Job& job);
  service::ClientReplyMsg AnswerFetch(const service::ClientRequestMsg& req, Job& job);
  /// Evaluate and close: to an evaluation session that is still open (a retried close of a
  /// closed one is answered OK).
  service::ClientReplyMsg AnswerSessionRequest(const service::ClientRequestMsg& req, Job& job);

  void Start(const std::shared_ptr<Job>& job);
  /// Archives the ended jobs beyond keep_in_memory, oldest first.
  void Retain();
  /// Fetch of an archived job: its spec and checkpoint read from the state directory.
  Status LoadArchived(const Job& job, job::JobSpec* spec, service::JobCheckpoint* c) const;
  /// The job's spec and checkpoint: copies of what is in memory, or read from disk when it is
  /// archived.
  Status SpecAndCheckpoint(Job& job, job::JobSpec* spec, service::JobCheckpoint* c) const;
  /// The job's generation records from generation `from` on (from disk when it is archived).
  Status LogFrom(Job& job, uint64_t from, std::vector<service::GenerationRecord>* log) const;
  void Run(Job& job);
  void RunSession(Job& job);  // the job thread of an evaluation session
  /// Makes c the job's current checkpoint; writes it to disk if `write`.
  void Save(Job& job, const service::JobCheckpoint& c, bool write = true, bool durable = true);
  service::JobInfo Info(Job& job);
  /// The kind's networks of a fetch's best individuals, with their provenance (none for kinds
  /// without networks).
  std::vector<io::SavedNetwork> NetworksOf(const std::string& job_id, const job::JobSpec& spec,
                                           const std::vector<service::ScoredGenome>& best,
                                           uint64_t best_generation, size_t generations) const;
  /// A generation's (or batch's) event for the job's watchers, with its storage condition.
  void PublishGeneration(Job& job, service::JobState state, const service::GenerationRecord& rec);
  /// The job's final event (state, message, its last record).
  void PublishFinal(Job& job, const service::JobCheckpoint& c, service::JobState state,
                    const std::string& message);

  JobStoreOptions options_;
  Broker& broker_;
  const job::JobKindRegistry& kinds_;
  JobDirectory dir_;
  LogThrottle log_throttle_{std::chrono::minutes(1)};
  std::mutex mu_;
  std::map<std::string, std::shared_ptr<Job>> jobs_;
};

}  // namespace pz::master
