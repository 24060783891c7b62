#include "client/complete_service.h"

#include <cstdlib>

#include "client/cmd_service.h"
#include "complete/job_kind.h"

namespace pz::client {
using namespace complete;

namespace {
std::string Env(const char* name) {
  const char* env = std::getenv(name);
  return env ? env : "";
}
}  // namespace

CompleteServiceFlags::CompleteServiceFlags()
    : curve_secret(Env("PIEZOID_CURVE_SECRET")), master_public(Env("PIEZOID_MASTER_PUBLIC")) {}

ServiceEvaluatorOptions CompleteServiceFlags::Options() const {
  ServiceEvaluatorOptions o;
  o.client = ClientOptionsOf(master, timeout_ms, retries, curve_secret, master_public);
  return o;
}

void AddCompleteServiceFlags(CLI::App* cmd, CompleteServiceFlags& f) {
  cmd->add_option("--master", f.master,
                  "run every evaluation of the searches on the workers of this piezoid-master (its client endpoint, "
                  "e.g. tcp://127.0.0.1:5556), one evaluation session per search or fit: the same result, bit for "
                  "bit, as the local run")
      ->type_name("ENDPOINT");
  cmd->add_option("--timeout-ms", f.timeout_ms, "with --master: per-request timeout [ms]")
      ->check(CLI::Range(10, 3600000))
      ->capture_default_str();
  cmd->add_option("--retries", f.retries, "with --master: attempts per request")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option("--curve-secret", f.curve_secret,
                  "with --master, CURVE: this client's key pair, NAME.key from `piezoid keygen` (default: "
                  "$PIEZOID_CURVE_SECRET)");
  cmd->add_option("--master-public", f.master_public,
                  "with --master, CURVE: the master's public key file (default: $PIEZOID_MASTER_PUBLIC)");
}

records::RecordEvaluatorFactory RecordsServiceFactory(const ServiceEvaluatorOptions& options,
                                                      const records::FamilyOptions& family, const std::string& owner) {
  return [options, family, owner](const records::RecordFitness& f) -> std::unique_ptr<opt::BatchEvaluator> {
    const std::string what = owner + ": " + f.model().Describe() + " on " + std::to_string(f.records().size()) + " record(s)";
    return std::make_unique<ServiceEvaluator>(
        options, complete::CompleteModelJobSpec(complete::CompleteModelProblemOf(f, family), what), owner);
  };
}

EvaluatorFactory CommitteeServiceFactory(const ServiceEvaluatorOptions& options, const records::FamilyOptions& family) {
  return [options, family](const records::CriterionFitness& f) -> std::unique_ptr<opt::BatchEvaluator> {
    const std::string what = "committee " + f.model().Describe() + " on " + std::to_string(f.records().size()) + " record(s)";
    return std::make_unique<ServiceEvaluator>(
        options, complete::CompleteModelJobSpec(complete::CompleteModelProblemOf(f, family), what), "piezoid committee");
  };
}

}  // namespace pz::client
