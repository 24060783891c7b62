#include "svcclient/complete_service.h"

#include "complete/job_kind.h"

namespace pz::svcclient {
using namespace complete;

records::RecordEvaluatorFactory RecordsServiceFactory(const ServiceEvaluatorOptions& options,
                                                      const records::FamilyOptions& family,
                                                      const std::string& owner) {
  return [options, family, owner](
             const records::RecordFitness& f,
             records::RecordEvaluation e) -> std::unique_ptr<opt::BatchEvaluator> {
    const bool residuals = e == records::RecordEvaluation::kResiduals;
    const std::string what = owner + ": " + f.model().Describe() + " on " +
                             std::to_string(f.records().size()) + " record(s)" +
                             (residuals ? " (polish)" : "");
    return std::make_unique<ServiceEvaluator>(
        options,
        complete::CompleteModelJobSpec(complete::CompleteModelProblemOf(f, family, residuals),
                                       what),
        owner);
  };
}

EvaluatorFactory CommitteeServiceFactory(const ServiceEvaluatorOptions& options,
                                         const records::FamilyOptions& family) {
  return [options,
          family](const records::CriterionFitness& f) -> std::unique_ptr<opt::BatchEvaluator> {
    const std::string what = "committee " + f.model().Describe() + " on " +
                             std::to_string(f.records().size()) + " record(s)";
    return std::make_unique<ServiceEvaluator>(
        options, complete::CompleteModelJobSpec(complete::CompleteModelProblemOf(f, family), what),
        "piezoid committee");
  };
}

}  // namespace pz::svcclient
