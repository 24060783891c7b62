#include "svcclient/service_evaluator.h"

#include <algorithm>
#include <chrono>
#include <thread>

namespace pz::svcclient {

ServiceEvaluator::ServiceEvaluator(ServiceEvaluatorOptions options, job::JobSpec spec,
                                   const std::string& owner)
    : options_(std::move(options)), client_(options_.client) {
  spec.ga.reset();
  spec.external = job::ExternalSettings{options_.idle_timeout_s, owner};
  SubmitResult r;
  std::vector<job::FieldViolation> violations;
  Status s = client_.Submit(spec, &r, &violations);
  if (s.code() == StatusCode::kInvalidArgument) {
    std::string all;
    for (const auto& v : violations) all += (all.empty() ? "" : "; ") + v.description;
    throw InputError("the master refuses the session's spec: " + (all.empty() ? s.message() : all));
  }
  if (!s.ok()) throw ServiceError(s);
  job_id_ = r.job_id;
  // The live worker threads, for concurrency() before the first batch.
  std::vector<service::JobInfo> jobs;
  int workers = 0;
  (void)client_.List(&jobs, &workers, &worker_threads_);
}

ServiceEvaluator::~ServiceEvaluator() {
  if (!closed_) (void)Close();
}

Status ServiceEvaluator::Close() {
  if (closed_) return Status::Ok();
  closed_ = true;
  return client_.Close(job_id_);
}

void ServiceEvaluator::Evaluate(const opt::EvalBatch& batch, std::span<opt::FitnessResult> out) {
  PZ_CHECK(out.size() == batch.genomes.size());
  if (closed_)
    throw ServiceError({StatusCode::kFailedPrecondition, "session " + job_id_ + " is closed"});
  if (batch.genomes.empty()) return;
  const uint64_t seq = next_seq_++;
  const std::vector<opt::Genome> genomes(batch.genomes.begin(), batch.genomes.end());
  const std::vector<opt::Genome> none;
  std::vector<opt::FitnessResult> results;
  const auto start = std::chrono::steady_clock::now();
  bool done = false, send_genomes = true;
  int wait_us = 200;
  for (;;) {
    Status s = client_.Evaluate(job_id_, seq, send_genomes ? genomes : none, &done, &results,
                                &worker_threads_);
    if (s.code() == StatusCode::kNotFound && !send_genomes) {  // the master lost it: send it again
      send_genomes = true;
      continue;
    }
    if (!s.ok())
      throw ServiceError(
          {s.code(), "session " + job_id_ + ", batch " + std::to_string(seq) + ": " + s.message()});
    send_genomes = false;
    if (done) break;
    if (options_.batch_timeout_s > 0 &&
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
            options_.batch_timeout_s)
      throw ServiceError(
          {StatusCode::kUnavailable, "session " + job_id_ + ", batch " + std::to_string(seq) +
                                         ": not evaluated within " +
                                         std::to_string(options_.batch_timeout_s) + " s"});
    std::this_thread::sleep_for(std::chrono::microseconds(wait_us));
    wait_us = std::min(2 * wait_us, 1000 * std::max(1, options_.max_poll_ms));
  }
  if (results.size() != out.size())
    throw ServiceError(
        {StatusCode::kDataLoss, "session " + job_id_ + ", batch " + std::to_string(seq) + ": " +
                                    std::to_string(results.size()) + " results for " +
                                    std::to_string(out.size()) + " genomes"});
  std::move(results.begin(), results.end(), out.begin());
  evaluations_ += static_cast<int64_t>(out.size());
}

}  // namespace pz::svcclient
