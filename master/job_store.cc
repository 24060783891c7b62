#include "master/job_store.h"

#include <spdlog/spdlog.h>

#include <sys/stat.h>

#include <algorithm>
#include <chrono>

#include "master/job_runner.h"
#include "service/wire_codec.h"

namespace pz::master {
namespace {

double UnixNow() {
  return std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
}

/// The reply to req that its handler fills: req's request id, code OK.
service::ClientReplyMsg ReplyTo(
    const service::ClientRequestMsg& req,
    service::ClientReplyMsg::Type type = service::ClientReplyMsg::Type::kNone) {
  service::ClientReplyMsg r;
  r.request_id = req.request_id;
  r.type = type;
  return r;
}

/// r refused with code and error.
service::ClientReplyMsg Refused(service::ClientReplyMsg r, service::WireCode code,
                                std::string error) {
  r.code = code;
  r.error = std::move(error);
  return r;
}

}  // namespace

using job::FieldViolation;
using job::GenomeLayout;
using job::JobKindRegistry;
using opt::FitnessResult;
using opt::Genome;
using service::ClientReplyMsg;
using service::ClientRequestMsg;
using service::DecodeJobSpec;
using service::GenerationRecord;
using service::IsFinal;
using service::JobCheckpoint;
using service::JobEvent;
using service::JobInfo;
using service::JobState;
using service::JobStateName;
using service::ScoredGenome;
using service::WireCode;

JobStore::JobStore(JobStoreOptions options, Broker& broker, const JobKindRegistry& kinds)
    : options_(std::move(options)), broker_(broker), kinds_(kinds), dir_(options_.state_dir) {}

JobStore::~JobStore() { Shutdown(); }

Status JobStore::Resume() {
  for (const std::string& id : dir_.List()) {
    auto job = std::make_shared<Job>();
    job->id = id;
    std::vector<FieldViolation> violations;
    Status s = dir_.LoadSpec(id, &job->spec_bytes);
    std::string notice;
    if (s.code() == StatusCode::kNotFound) {
      // No spec: a submission that could not be written (e.g. disk full). Nothing to resume.
      if (dir_.LoadCheckpoint(id, &job->checkpoint, &notice).code() == StatusCode::kNotFound) {
        const Status r = dir_.Remove(id);
        spdlog::warn("job folder {}: no spec.pb (a submission that could not be written): {}",
                     dir_.dir(id).string(), r.ok() ? "removed" : r.message());
        continue;
      }
    }
    if (s.ok()) s = DecodeJobSpec(job->spec_bytes, &job->spec, &violations);
    if (s.ok() && !violations.empty()) s = {StatusCode::kDataLoss, violations.front().description};
    if (!s.ok()) {
      // The job cannot run again, but it does not vanish: it is listed, failed, with the reason
      // (and what its checkpoint holds, if that is readable).
      if (!dir_.LoadCheckpoint(id, &job->checkpoint, &notice).ok())
        job->checkpoint = JobCheckpoint{};
      job->checkpoint.job_id = id;
      job->checkpoint.state = JobState::kFailed;
      job->checkpoint.message = "its spec cannot be read, so it cannot be resumed: " + s.message();
      job->notice = s.message();
      spdlog::error("job {}: {}", id, job->checkpoint.message);
      std::lock_guard lock(mu_);
      jobs_[id] = job;
      continue;
    }
    s = dir_.LoadCheckpoint(id, &job->checkpoint, &notice);
    if (!s.ok()) {  // a new job, or (notice) one whose checkpoints are unusable: generation 0
      job->checkpoint = JobCheckpoint{};
      job->checkpoint.job_id = id;
    }
    job->arithmetic = job->checkpoint.arithmetic;
    const std::string served = broker_.served_arithmetic();
    if (!IsFinal(job->checkpoint.state) && !job->arithmetic.empty() && !served.empty() &&
        served != job->arithmetic)
      notice += std::string(notice.empty() ? "" : "; ") + "computed on arithmetic '" +
                job->arithmetic + "' and resumed on '" + served +
                "' (another job running on this state directory fixed it): " +
                "its results may differ in their last bits from an uninterrupted run";
    if (!notice.empty()) {
      job->notice = notice;
      spdlog::warn("job {}: {}", id, notice);
    }
    if (IsFinal(job->checkpoint.state)) {  // ended when its last checkpoint was written
      struct stat st {};
      if (::stat((dir_.dir(id) / JobDirectory::kCheckpointFile).c_str(), &st) == 0)
        job->ended_unix_s =
            static_cast<double>(st.st_mtim.tv_sec) + 1e-9 * static_cast<double>(st.st_mtim.tv_nsec);
    }
    {
      std::lock_guard lock(mu_);
      jobs_[id] = job;
      if (!IsFinal(job->checkpoint.state)) {
        spdlog::info("job {}: resuming after generation {}", id, job->checkpoint.log.size());
        Start(job);
      }
    }
    Retain();  // one ended job in memory beyond the limit at a time, not all of them
  }
  return Status::Ok();
}

void JobStore::Start(const std::shared_ptr<Job>& job) {
  if (job->spec.external) {
    GenomeLayout layout;
    (void)kinds_.Layout(job->spec, &layout);  // a failure fails the job in RunSession
    job->session =
        std::make_shared<Session>(job->id, *job->spec.external, layout, job->spec.kind());
  }
  job->thread = std::thread([this, job] { job->session ? RunSession(*job) : Run(*job); });
}

void JobStore::RunSession(Job& job) {
  JobCheckpoint c;
  {
    std::lock_guard lock(job.mu);
    c = job.checkpoint;
  }
  auto finish = [&](JobState state, const std::string& message) {
    c.state = state;
    c.message = message;
    Save(job, c);
    PublishFinal(job, c, state, message);
    spdlog::info("session {}: {} {}", job.id, JobStateName(state), message);
  };
  GenomeLayout layout;
  if (Status s = kinds_.Layout(job.spec, &layout); !s.ok()) {
    finish(JobState::kFailed, "cannot start: " + s.message());
    return;
  }
  broker_.RegisterJob(job.id, job.spec_bytes, job.spec.limits);
  BrokerEvaluator eval(broker_, job.id);
  auto last_write = std::chrono::steady_clock::now();
  auto t0 = std::chrono::steady_clock::now();
  const Session::End end = job.session->Run(
      eval, c.log.size() + 1, [&] { return job.cancel || job.shutdown; },
      [&](uint64_t seq, std::span<const Genome> genomes, std::span<const FitnessResult> results) {
        if (eval.interrupted()) return false;
        const auto now = std::chrono::steady_clock::now();
        const GenerationRecord& rec =
            FoldSessionBatch(c, genomes, results, std::chrono::duration<double>(now - t0).count());
        t0 = now;
        for (const auto& q : eval.TakeQuarantined()) c.quarantined.push_back(q);
        const bool durable = options_.checkpoint_interval_s <= 0 ||
                             std::chrono::duration<double>(now - last_write).count() >=
                                 options_.checkpoint_interval_s;
        Save(job, c, /*write=*/true, durable);
        if (durable) last_write = now;
        spdlog::debug("session {}: batch {} ({} genomes) best {:.9g}", job.id, seq, genomes.size(),
                      rec.best_cost);
        PublishGeneration(job, c.state, rec);
        return true;
      });
  if (!eval.error().empty()) {
    finish(JobState::kFailed, eval.error());
  } else if (job.cancel) {
    finish(JobState::kCancelled, "cancelled by a client");
  } else if (end == Session::End::kClosed) {
    finish(JobState::kSucceeded, "closed by its client");
  } else if (end == Session::End::kIdle) {
    finish(JobState::kCancelled, "its client sent nothing for " +
                                     std::to_string(job.spec.external->idle_timeout_s) +
                                     " s (external.idle_timeout_s)");
  } else {  // shutdown: resumed on the next start
    JobCheckpoint last;
    {
      std::lock_guard lock(job.mu);
      last = job.checkpoint;
    }
    Save(job, last);
  }
  broker_.UnregisterJob(job.id);
  Retain();
}

void JobStore::PublishGeneration(Job& job, JobState state, const GenerationRecord& rec) {
  JobEvent e;
  e.job_id = job.id;
  e.state = state;
  e.record = rec;
  {
    std::lock_guard lock(job.mu);
    e.storage_error = job.storage_error;
  }
  broker_.Publish(e);
}

void JobStore::PublishFinal(Job& job, const JobCheckpoint& c, JobState state,
                            const std::string& message) {
  JobEvent e;
  e.job_id = job.id;
  e.state = state;
  if (!c.log.empty()) e.record = c.log.back();
  e.message = message;
  {
    std::lock_guard lock(job.mu);
    e.storage_error = job.storage_error;
  }
  broker_.Publish(e);
}

void JobStore::Save(Job& job, const JobCheckpoint& checkpoint, bool write, bool durable) {
  // Stamped with the profile of the workers that computed it, from its first generation on.
  JobCheckpoint c = checkpoint;
  {
    std::lock_guard lock(job.mu);
    if (job.arithmetic.empty() && !c.log.empty()) job.arithmetic = broker_.served_arithmetic();
    c.arithmetic = job.arithmetic;
  }
  Status s;
  if (write) s = dir_.SaveCheckpoint(c, durable);
  std::lock_guard lock(job.mu);
  job.checkpoint = c;
  if (IsFinal(c.state) && job.ended_unix_s == 0) job.ended_unix_s = UnixNow();
  if (!write) return;
  const auto now = std::chrono::steady_clock::now();
  if (!s.ok()) {
    // The job runs on (its state is in memory), but status and watch say that a restart would
    // lose what was not written; the log says it once a minute, with the count in between.
    if (job.storage_error.empty())
      job.storage_error_since =
          std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch())
              .count();
    job.storage_error = s.message();
    uint64_t suppressed = 0;
    if (log_throttle_.Allow("checkpoint " + job.id, now, &suppressed))
      spdlog::error(
          "job {}: checkpoint not saved: {}{}", job.id, s.message(),
          suppressed ? " (" + std::to_string(suppressed) + " more failed writes not logged)" : "");
  } else if (!job.storage_error.empty()) {
    spdlog::info(
        "job {}: checkpoints are written again (failing since {:.0f} s ago)", job.id,
        std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count() -
            job.storage_error_since);
    job.storage_error.clear();
    job.storage_error_since = 0;
  }
}

void JobStore::Run(Job& job) {
  JobCheckpoint resume;
  {
    std::lock_guard lock(job.mu);
    resume = job.checkpoint;
  }
  const bool has_state = resume.optimizer.initialized;
  JobRunner runner(job.id, job.spec);
  Status s = runner.Init(kinds_, has_state ? &resume : nullptr);
  auto finish = [&](JobCheckpoint c, JobState state, const std::string& message) {
    c.state = state;
    c.message = message;
    Save(job, c);
    PublishFinal(job, c, state, message);
    spdlog::info("job {}: {} {}", job.id, JobStateName(state), message);
  };
  if (!s.ok()) {
    finish(resume, JobState::kFailed, "cannot start: " + s.message());
    return;
  }
  broker_.RegisterJob(job.id, job.spec_bytes, job.spec.limits);
  BrokerEvaluator eval(broker_, job.id);
  auto last_write = std::chrono::steady_clock::now();
  bool unwritten = false;  // the current checkpoint is newer than the one on disk
  while (!runner.Done() && !job.cancel && !job.shutdown) {
    const GenerationRecord rec = runner.Step(eval);
    if (eval.interrupted()) {
      if (!eval.error().empty()) {
        std::lock_guard lock(job.mu);
        resume = job.checkpoint;
      }
      if (!eval.error().empty()) finish(resume, JobState::kFailed, eval.error());
      break;
    }
    JobCheckpoint& c = runner.mutable_checkpoint();
    for (const auto& q : eval.TakeQuarantined()) c.quarantined.push_back(q);
    const auto now = std::chrono::steady_clock::now();
    const bool durable =
        IsFinal(c.state) || options_.checkpoint_interval_s <= 0 ||
        std::chrono::duration<double>(now - last_write).count() >= options_.checkpoint_interval_s;
    Save(job, c, /*write=*/true, durable);
    if (durable) last_write = now;
    unwritten = !durable;
    spdlog::info("job {}: generation {} best {:.9g} mean {:.6g} evaluations {}", job.id,
                 rec.generation, rec.best_cost, rec.mean_cost, rec.evaluations_total);
    PublishGeneration(job, c.state, rec);
  }
  if (unwritten && !job.cancel) {  // shut down between writes (a failure was written by finish)
    JobCheckpoint last;
    {
      std::lock_guard lock(job.mu);
      last = job.checkpoint;
    }
    if (!IsFinal(last.state)) Save(job, last);
  }
  if (job.cancel) {
    JobCheckpoint last;
    {
      std::lock_guard lock(job.mu);
      last = job.checkpoint;
    }
    finish(last, JobState::kCancelled, "cancelled by a client");
  } else if (runner.Done() && !job.shutdown) {
    spdlog::info("job {}: succeeded ({})", job.id, runner.checkpoint().message);
  }
  broker_.UnregisterJob(job.id);
  Retain();
}

std::vector<io::SavedNetwork> JobStore::NetworksOf(const std::string& job_id,
                                                   const job::JobSpec& spec,
                                                   const std::vector<ScoredGenome>& best,
                                                   uint64_t best_generation,
                                                   size_t generations) const {
  std::vector<io::SavedNetwork> out;
  std::vector<Genome> genomes;
  for (const auto& b : best) genomes.push_back(b.genome);
  std::vector<model::Network> nets;
  const Status s = kinds_.Networks(spec, genomes, &nets);
  if (s.code() == StatusCode::kNotFound) return out;  // a kind without networks
  if (!s.ok() || nets.size() != best.size()) {
    spdlog::error("job {}: its networks cannot be built for fetch: {}", job_id, s.message());
    return out;
  }
  std::vector<std::string> training;
  if (const auto* h = std::get_if<job::HgannProblem>(&spec.problem))
    for (const auto& c : h->cases)
      if (c.role == job::CaseRole::kTrain) training.push_back("case" + std::to_string(c.number));
  const int64_t now_ms = std::chrono::duration_cast<std::chrono::milliseconds>(
                             std::chrono::system_clock::now().time_since_epoch())
                             .count();
  for (size_t k = 0; k < best.size(); ++k) {
    io::SavedNetwork n;
    n.network = std::move(nets[k]);
    n.chromosome = best[k].genome.bits;
    auto& p = n.provenance;
    p.job_id = job_id;
    p.seed = spec.seed;
    // The best was found in the GA's best generation; the others are members of the last
    // population (the generations after the initial one), which is all a checkpoint keeps.
    p.generation = k == 0 ? best_generation : (generations > 0 ? generations - 1 : 0);
    p.fitness = best[k].fitness.cost;
    p.created_unix_ms = now_ms;
    p.piezoid_version = PIEZOID_VERSION;
    p.training_cases = training;
    out.push_back(std::move(n));
  }
  return out;
}

JobInfo JobStore::Info(Job& job) {
  std::lock_guard lock(job.mu);
  if (job.archived) return job.summary;
  const JobCheckpoint& c = job.checkpoint;
  JobInfo i;
  i.job_id = job.id;
  i.name = job.spec.name;
  i.kind = job.spec.kind();
  i.state = c.state == JobState::kUnspecified ? JobState::kRunning : c.state;
  i.generation = c.log.size();
  i.max_generations = job.spec.ga ? static_cast<uint64_t>(job.spec.ga->generations) : 0;
  i.best_cost = c.best.empty() ? 0 : c.best.front().fitness.cost;
  i.evaluations = static_cast<uint64_t>(c.optimizer.evaluations);
  i.message = c.message;
  i.termination = c.termination;
  i.quarantined = c.quarantined;
  i.elapsed_s = c.elapsed_s;
  i.seed = job.spec.seed;
  i.algorithm = job.spec.algorithm();
  i.notice = job.notice;
  i.storage_error = job.storage_error;
  i.storage_error_since_unix_s = job.storage_error_since;
  i.ended_unix_s = job.ended_unix_s;
  return i;
}

void JobStore::Retain() {
  std::vector<std::shared_ptr<Job>> ended;
  {
    std::lock_guard lock(mu_);
    for (auto& [id, j] : jobs_) {
      std::lock_guard jl(j->mu);
      if (IsFinal(j->checkpoint.state) && !j->archived) ended.push_back(j);
    }
  }
  const auto keep = static_cast<size_t>(std::max(0, options_.keep_in_memory));
  if (ended.size() <= keep) return;
  std::sort(ended.begin(), ended.end(), [](const auto& a, const auto& b) {
    return a->ended_unix_s != b->ended_unix_s ? a->ended_unix_s > b->ended_unix_s : a->id > b->id;
  });
  for (size_t k = keep; k < ended.size(); ++k) {
    Job& j = *ended[k];
    JobInfo summary = Info(j);
    summary.archived = true;
    std::lock_guard jl(j.mu);
    j.summary = std::move(summary);
    j.archived = true;
    j.checkpoint = JobCheckpoint{};  // what a fetch needs is on disk
    j.checkpoint.job_id = j.id;
    j.checkpoint.state = j.summary.state;
    j.spec = job::JobSpec{};
    std::string().swap(j.spec_bytes);
    spdlog::debug("job {}: archived (on disk only)", j.id);
  }
}

Status JobStore::LoadArchived(const Job& job, job::JobSpec* spec, JobCheckpoint* c) const {
  std::string bytes, notice;
  if (Status s = dir_.LoadSpec(job.id, &bytes); !s.ok())
    return {StatusCode::kDataLoss, s.message()};
  std::vector<FieldViolation> v;
  if (Status s = DecodeJobSpec(bytes, spec, &v); !s.ok())
    return {StatusCode::kDataLoss, s.message()};
  if (Status s = dir_.LoadCheckpoint(job.id, c, &notice); !s.ok())
    return {StatusCode::kDataLoss,
            "archived job " + job.id + ": " + (notice.empty() ? s.message() : notice)};
  return Status::Ok();
}

ClientReplyMsg JobStore::AnswerPrune(const ClientRequestMsg& req) {
  ClientReplyMsg r = ReplyTo(req, ClientReplyMsg::Type::kPrune);
  if (req.job_ids.empty() && req.older_than_s <= 0 && req.keep <= 0)
    return Refused(
        std::move(r), WireCode::kInvalidArgument,
        "prune: name the jobs, or give older_than_s or keep (nothing is pruned without a rule)");
  // The candidates: the jobs named, or every job; running ones are refused when named.
  struct Candidate {
    std::shared_ptr<Job> job;
    double ended = 0;
  };
  std::vector<Candidate> ended;
  {
    std::lock_guard lock(mu_);
    auto consider = [&](const std::string& id, bool named) {
      auto it = jobs_.find(id);
      if (it == jobs_.end()) {
        if (named) r.refused.push_back({id, "no such job"});
        return;
      }
      std::lock_guard jl(it->second->mu);
      if (!IsFinal(it->second->checkpoint.state)) {
        if (named)
          r.refused.push_back({id, "running: cancel it first (only ended jobs are pruned)"});
        return;
      }
      ended.push_back({it->second, it->second->ended_unix_s});
    };
    if (req.job_ids.empty()) {
      for (const auto& [id, j] : jobs_) consider(id, false);
    } else {
      for (const auto& id : req.job_ids) consider(id, true);
    }
  }
  std::sort(ended.begin(), ended.end(), [](const Candidate& a, const Candidate& b) {
    return a.ended != b.ended ? a.ended > b.ended : a.job->id > b.job->id;
  });
  const double now = UnixNow();
  for (size_t k = 0; k < ended.size(); ++k) {
    if (req.keep > 0 && k < static_cast<size_t>(req.keep)) continue;  // among the newest
    if (req.older_than_s > 0 && now - ended[k].ended < req.older_than_s) continue;  // too recent
    r.pruned.push_back(ended[k].job->id);
  }
  if (req.dry_run) return r;
  for (const std::string& id : r.pruned) {
    std::shared_ptr<Job> j;
    {
      std::lock_guard lock(mu_);
      auto it = jobs_.find(id);
      if (it == jobs_.end()) continue;
      j = it->second;
      jobs_.erase(it);
    }
    if (j->thread.joinable()) j->thread.join();  // it has ended: this returns at once
    if (Status s = dir_.Remove(id); !s.ok()) spdlog::error("prune {}: {}", id, s.message());
  }
  if (!r.pruned.empty()) spdlog::info("pruned {} ended job(s)", r.pruned.size());
  return r;
}

ClientReplyMsg JobStore::Handle(const ClientRequestMsg& req) {
  using T = ClientRequestMsg::Type;
  switch (req.type) {
    case T::kSubmit:
      return AnswerSubmit(req);
    case T::kList:
      return AnswerList(req);
    case T::kPrune:
      return AnswerPrune(req);
    case T::kStatus:
    case T::kCancel:
    case T::kFetch:
    case T::kEvaluate:
    case T::kClose:
      return AnswerAboutJob(req);
    default:
      return Refused(ReplyTo(req), WireCode::kInvalidArgument, "unsupported request");
  }
}

ClientReplyMsg JobStore::AnswerSubmit(const ClientRequestMsg& req) {
  ClientReplyMsg r = ReplyTo(req);
  r.violations = req.decode_violations;
  for (auto& v : kinds_.Validate(req.spec)) r.violations.push_back(std::move(v));
  if (!r.violations.empty()) {
    r.code = WireCode::kInvalidArgument;
    for (const auto& v : r.violations) r.error += (r.error.empty() ? "" : "; ") + v.description;
    return r;
  }
  r.type = ClientReplyMsg::Type::kSubmit;
  r.job_id = service::JobIdOf(req.spec_bytes, req.client_token);
  std::lock_guard lock(mu_);
  if (jobs_.count(r.job_id)) {
    r.existed = true;
    return r;
  }
  int running = 0;
  for (auto& [id, j] : jobs_) {
    std::lock_guard jl(j->mu);
    running += !IsFinal(j->checkpoint.state);
  }
  if (running >= options_.max_running_jobs)
    return Refused(std::move(r), WireCode::kResourceExhausted,
                   "too many running jobs (" + std::to_string(running) + ")");
  if (Status s = dir_.SaveSpec(r.job_id, req.spec_bytes); !s.ok()) {
    (void)dir_.Remove(r.job_id);  // no empty folder left for every restart to complain about
    r = Refused(std::move(r), WireCode::kUnavailable,
                "the master cannot store the job: " + s.message() + " (retry when it has space)");
    uint64_t suppressed = 0;
    if (log_throttle_.Allow("submit", std::chrono::steady_clock::now(), &suppressed))
      spdlog::error("submission refused: {}{}", r.error,
                    suppressed ? " (" + std::to_string(suppressed) + " more not logged)" : "");
    return r;
  }
  auto j = std::make_shared<Job>();
  j->id = r.job_id;
  j->spec = req.spec;
  j->spec_bytes = req.spec_bytes;
  j->checkpoint.job_id = r.job_id;
  jobs_[r.job_id] = j;
  spdlog::info("job {} submitted: {} '{}' seed {}", r.job_id, req.spec.kind(), req.spec.name,
               req.spec.seed);
  Start(j);
  return r;
}

ClientReplyMsg JobStore::AnswerList(const ClientRequestMsg& req) {
  ClientReplyMsg r = ReplyTo(req, ClientReplyMsg::Type::kList);
  std::vector<std::shared_ptr<Job>> all;
  {
    std::lock_guard lock(mu_);
    for (auto& [id, j] : jobs_) all.push_back(j);
  }
  for (auto& j : all) r.jobs.push_back(Info(*j));
  return r;
}

ClientReplyMsg JobStore::AnswerAboutJob(const ClientRequestMsg& req) {
  std::shared_ptr<Job> job;
  {
    std::lock_guard lock(mu_);
    auto it = jobs_.find(req.job_id);
    if (it != jobs_.end()) job = it->second;
  }
  if (!job)
    return Refused(ReplyTo(req), WireCode::kNotFound, "job_id = " + req.job_id + ": no such job");
  using T = ClientRequestMsg::Type;
  switch (req.type) {
    case T::kStatus:
      return AnswerStatus(req, *job);
    case T::kCancel:
      return AnswerCancel(req, *job);
    case T::kFetch:
      return AnswerFetch(req, *job);
    default:
      return AnswerSessionRequest(req, *job);  // kEvaluate, kClose
  }
}

ClientReplyMsg JobStore::AnswerStatus(const ClientRequestMsg& req, Job& job) {
  ClientReplyMsg r = ReplyTo(req, ClientReplyMsg::Type::kStatus);
  r.info = Info(job);
  return r;
}

ClientReplyMsg JobStore::AnswerCancel(const ClientRequestMsg& req, Job& job) {
  ClientReplyMsg r = AnswerStatus(req, job);
  if (IsFinal(r.info.state))
    return Refused(std::move(r), WireCode::kFailedPrecondition,
                   "job " + job.id + " is already " + JobStateName(r.info.state));
  job.cancel = true;
  broker_.UnregisterJob(job.id);
  return r;
}

ClientReplyMsg JobStore::AnswerFetch(const ClientRequestMsg& req, Job& job) {
  ClientReplyMsg r = ReplyTo(req);
  if (req.count < 1 || req.count > kBestKept) {
    r = Refused(std::move(r), WireCode::kInvalidArgument,
                "count = " + std::to_string(req.count) + ": must be in [1, " +
                    std::to_string(kBestKept) + "] (the master keeps the " +
                    std::to_string(kBestKept) + " best individuals of a job)");
    r.violations.push_back({"count", r.error});
    return r;
  }
  r.type = ClientReplyMsg::Type::kFetch;
  r.info = Info(job);
  if (req.log_only) {  // a live view's poll: the info and the log's tail, nothing else
    if (Status s = LogFrom(job, req.log_from, &r.log); !s.ok())
      return Refused(std::move(r), WireCode::kInternal, s.message());
    return r;
  }
  JobCheckpoint c;
  job::JobSpec spec;
  if (Status s = SpecAndCheckpoint(job, &spec, &c); !s.ok())
    return Refused(std::move(r), WireCode::kInternal, s.message());
  r.best.assign(c.best.begin(), c.best.begin() + std::min<size_t>(c.best.size(), req.count));
  r.log = std::move(c.log);
  r.networks = NetworksOf(job.id, spec, r.best, c.optimizer.best_generation, r.log.size());
  r.committee = c.committee;
  r.spec = std::move(spec);
  return r;
}

Status JobStore::SpecAndCheckpoint(Job& job, job::JobSpec* spec, JobCheckpoint* c) const {
  {
    std::lock_guard lock(job.mu);
    if (!job.archived) {
      *c = job.checkpoint;
      *spec = job.spec;
      return Status::Ok();
    }
  }
  return LoadArchived(job, spec, c);
}

Status JobStore::LogFrom(Job& job, uint64_t from, std::vector<GenerationRecord>* log) const {
  {
    std::lock_guard lock(job.mu);
    if (!job.archived) {
      for (const auto& rec : job.checkpoint.log)
        if (rec.generation >= from) log->push_back(rec);
      return Status::Ok();
    }
  }
  job::JobSpec spec;
  JobCheckpoint c;
  if (Status s = LoadArchived(job, &spec, &c); !s.ok()) return s;
  for (auto& rec : c.log)
    if (rec.generation >= from) log->push_back(std::move(rec));
  return Status::Ok();
}

ClientReplyMsg JobStore::AnswerSessionRequest(const ClientRequestMsg& req, Job& job) {
  const bool close = req.type == ClientRequestMsg::Type::kClose;
  ClientReplyMsg r = ReplyTo(req);
  if (!job.session)
    return Refused(std::move(r), WireCode::kFailedPrecondition,
                   "job " + job.id + " runs the GA (algorithm " + job.spec.algorithm() +
                       "): only an evaluation session (algorithm external) takes " +
                       (close ? "close" : "evaluate") + " requests");
  r.info = Info(job);
  if (IsFinal(r.info.state)) {
    if (close && r.info.state == JobState::kSucceeded) {  // a retried close
      r.type = ClientReplyMsg::Type::kStatus;
      return r;
    }
    return Refused(std::move(r), WireCode::kFailedPrecondition,
                   "session " + job.id + " is " + JobStateName(r.info.state) +
                       (r.info.message.empty() ? "" : " (" + r.info.message + ")"));
  }
  if (!close) return job.session->Evaluate(req);
  job.session->Close();
  r.type = ClientReplyMsg::Type::kStatus;
  return r;
}

void JobStore::Shutdown() {
  std::vector<std::shared_ptr<Job>> all;
  {
    std::lock_guard lock(mu_);
    for (auto& [id, j] : jobs_) {
      j->shutdown = true;
      all.push_back(j);
    }
  }
  broker_.Stop();
  for (auto& j : all)
    if (j->thread.joinable()) j->thread.join();
}

}  // namespace pz::master
