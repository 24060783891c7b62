// The service as a BatchEvaluator: an optimiser that runs in this process (the diagnosis's
// differential evolution and Levenberg–Marquardt, say) evaluates its batches on the workers of a
// piezoid-master through an evaluation session (JobSpec.external, master/session.h).
//
//   pz::svcclient::ServiceEvaluator ev({.endpoint = "tcp://host:5556"}, spec);  // opens the
//   session ev.Evaluate({generation, genomes, indices}, results);   // same results as an
//   InlineEvaluator
//   // the destructor closes the session (it succeeds)
//
// Results are bit-identical to an InlineEvaluator of the job kind's fitness for the same genomes
// (a fitness is a pure function of (genome, spec); the master counts each result once), whatever
// the number of workers and whatever happens to them — except that an individual quarantined
// after repeated lost leases gets limits.penalty_cost, as in a GA job.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "svcclient/service_client.h"
#include "opt/evaluator.h"
#include "job/job_spec.h"

namespace pz::svcclient {

/// A failure of the service during an evaluation (master unreachable for longer than the retries,
/// session cancelled or failed): the batch has no results.
class ServiceError : public std::runtime_error {
 public:
  explicit ServiceError(Status s) : std::runtime_error(s.message()), status_(std::move(s)) {}
  const Status& status() const { return status_; }

 private:
  Status status_;
};

struct ServiceEvaluatorOptions {
  ServiceClientOptions client;
  double idle_timeout_s =
      120;              ///< the master cancels the session after this long without a request
  int max_poll_ms = 5;  ///< polls of a pending batch back off up to this interval [ms]
  /// A batch not done after this long (e.g. no worker connected) fails with ServiceError; 0 = wait
  /// for ever [s].
  double batch_timeout_s = 0;
};

class ServiceEvaluator final : public opt::BatchEvaluator {
 public:
  /// Opens a session for `spec` (its algorithm becomes `external`, with `owner` as the owner).
  /// Throws InputError with every violated field if the master refuses the spec, ServiceError if
  /// it cannot be reached.
  ServiceEvaluator(ServiceEvaluatorOptions options, job::JobSpec spec,
                   const std::string& owner = {});
  /// Closes the session (errors are ignored: an unclosed session ends by its idle timeout).
  ~ServiceEvaluator() override;
  ServiceEvaluator(const ServiceEvaluator&) = delete;
  ServiceEvaluator& operator=(const ServiceEvaluator&) = delete;

  /// Evaluates the batch on the service (blocking). Throws ServiceError on a service failure.
  void Evaluate(const opt::EvalBatch& batch, std::span<opt::FitnessResult> out) override;
  /// The master's live worker threads (as of the last reply), ≥ 1.
  int concurrency() const override { return std::max(1, worker_threads_); }

  const std::string& job_id() const { return job_id_; }
  int64_t evaluations() const { return evaluations_; }
  uint64_t batches() const { return next_seq_ - 1; }
  /// Ends the session now (it succeeds); later Evaluate calls throw.
  Status Close();

 private:
  ServiceEvaluatorOptions options_;
  ServiceClient client_;
  std::string job_id_;
  uint64_t next_seq_ = 1;
  int worker_threads_ = 0;
  int64_t evaluations_ = 0;
  bool closed_ = false;
};

}  // namespace pz::svcclient
