#include "master/job_store.h"

#include <spdlog/spdlog.h>

#include <chrono>

#include "master/job_runner.h"
#include "master/wire_codec.h"

namespace pz::master {

JobStore::JobStore(JobStoreOptions options, Broker& broker, const JobKindRegistry& kinds)
    : options_(std::move(options)), broker_(broker), kinds_(kinds), dir_(options_.state_dir) {}

JobStore::~JobStore() { Shutdown(); }

std::string JobStore::JobIdOf(const std::string& spec_bytes, const std::string& client_token) {
  std::string key = spec_bytes;
  key += '\0';
  key += client_token;
  return "j" + ContentHash(key).substr(0, 15);
}

Status JobStore::Resume() {
  for (const std::string& id : dir_.List()) {
    auto job = std::make_shared<Job>();
    job->id = id;
    std::vector<FieldViolation> violations;
    Status s = dir_.LoadSpec(id, &job->spec_bytes);
    if (s.ok()) s = DecodeJobSpec(job->spec_bytes, &job->spec, &violations);
    if (!s.ok()) {
      spdlog::error("job {}: cannot load its spec, skipped: {}", id, s.message());
      continue;
    }
    s = dir_.LoadCheckpoint(id, &job->checkpoint);
    if (s.code() == StatusCode::kNotFound) {
      job->checkpoint = JobCheckpoint{};
      job->checkpoint.job_id = id;
    } else if (!s.ok()) {
      spdlog::error("job {}: cannot load its checkpoint, skipped: {}", id, s.message());
      continue;
    }
    std::lock_guard lock(mu_);
    jobs_[id] = job;
    if (!IsFinal(job->checkpoint.state)) {
      spdlog::info("job {}: resuming after generation {}", id, job->checkpoint.log.size());
      Start(job);
    }
  }
  return Status::Ok();
}

void JobStore::Start(const std::shared_ptr<Job>& job) {
  job->thread = std::thread([this, job] { Run(*job); });
}

void JobStore::Save(Job& job, const JobCheckpoint& c, bool write, bool durable) {
  if (write) {
    if (Status s = dir_.SaveCheckpoint(c, durable); !s.ok())
      spdlog::error("job {}: checkpoint not saved: {}", job.id, s.message());
  }
  std::lock_guard lock(job.mu);
  job.checkpoint = c;
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
    broker_.Publish({job.id, state, c.log.empty() ? std::nullopt : std::optional(c.log.back()),
                     message});
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
    const bool durable = IsFinal(c.state) || options_.checkpoint_interval_s <= 0 ||
                         std::chrono::duration<double>(now - last_write).count() >= options_.checkpoint_interval_s;
    Save(job, c, /*write=*/true, durable);
    if (durable) last_write = now;
    unwritten = !durable;
    spdlog::info("job {}: generation {} best {:.9g} mean {:.6g} evaluations {}", job.id,
                 rec.generation, rec.best_cost, rec.mean_cost, rec.evaluations);
    broker_.Publish({job.id, c.state, rec, {}});
  }
  if (unwritten && !job.cancel) {  // shut down between writes (a failure was written by finish)
    std::lock_guard lock(job.mu);
    if (!IsFinal(job.checkpoint.state))
      if (Status st = dir_.SaveCheckpoint(job.checkpoint); !st.ok())
        spdlog::error("job {}: checkpoint not saved: {}", job.id, st.message());
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
}

JobInfo JobStore::Info(Job& job) {
  std::lock_guard lock(job.mu);
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
  i.quarantined = c.quarantined;
  i.elapsed_s = c.elapsed_s;
  i.seed = job.spec.seed;
  return i;
}

ClientReplyMsg JobStore::Handle(const ClientRequestMsg& req) {
  ClientReplyMsg r;
  r.request_id = req.request_id;
  r.code = WireCode::kOk;
  using T = ClientRequestMsg::Type;
  std::shared_ptr<Job> job;
  if (req.type == T::kStatus || req.type == T::kCancel || req.type == T::kFetch) {
    std::lock_guard lock(mu_);
    auto it = jobs_.find(req.job_id);
    if (it == jobs_.end()) {
      r.code = WireCode::kNotFound;
      r.error = "job_id = " + req.job_id + ": no such job";
      return r;
    }
    job = it->second;
  }
  switch (req.type) {
    case T::kSubmit: {
      r.violations = req.decode_violations;
      for (auto& v : kinds_.Validate(req.spec)) r.violations.push_back(std::move(v));
      if (!r.violations.empty()) {
        r.code = WireCode::kInvalidArgument;
        for (const auto& v : r.violations) r.error += (r.error.empty() ? "" : "; ") + v.description;
        return r;
      }
      r.type = ClientReplyMsg::Type::kSubmit;
      r.job_id = JobIdOf(req.spec_bytes, req.client_token);
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
      if (running >= options_.max_running_jobs) {
        r.code = WireCode::kResourceExhausted;
        r.error = "too many running jobs (" + std::to_string(running) + ")";
        return r;
      }
      if (Status s = dir_.SaveSpec(r.job_id, req.spec_bytes); !s.ok()) {
        r.code = WireCode::kInternal;
        r.error = s.message();
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
    case T::kStatus:
      r.type = ClientReplyMsg::Type::kStatus;
      r.info = Info(*job);
      return r;
    case T::kCancel: {
      r.type = ClientReplyMsg::Type::kStatus;
      r.info = Info(*job);
      if (IsFinal(r.info.state)) {
        r.code = WireCode::kFailedPrecondition;
        r.error = "job " + job->id + " is already " + JobStateName(r.info.state);
        return r;
      }
      job->cancel = true;
      broker_.UnregisterJob(job->id);
      return r;
    }
    case T::kFetch: {
      r.type = ClientReplyMsg::Type::kFetch;
      r.info = Info(*job);
      std::lock_guard lock(job->mu);
      const auto& best = job->checkpoint.best;
      r.best.assign(best.begin(), best.begin() + std::min<size_t>(best.size(), req.count));
      r.log = job->checkpoint.log;
      r.spec = job->spec;
      return r;
    }
    case T::kList: {
      r.type = ClientReplyMsg::Type::kList;
      std::vector<std::shared_ptr<Job>> all;
      {
        std::lock_guard lock(mu_);
        for (auto& [id, j] : jobs_) all.push_back(j);
      }
      for (auto& j : all) r.jobs.push_back(Info(*j));
      return r;
    }
    default:
      r.code = WireCode::kInvalidArgument;
      r.error = "unsupported request";
      return r;
  }
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
