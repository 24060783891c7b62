// Complete-model searches on the workers of a piezoid-master (issue 7): the evaluator factories
// of `piezoid fit`, `diagnose --records` and the committee over the service (their flags, --master
// and the rest, are the CLI's: client/service_flags.h CompleteServiceFlags). Each search is one
// session whose spec (the "complete_model" job kind, complete/job_kind.h) carries the fitness's
// records, so the results equal the local run's bit for bit.
#pragma once

#include <string>

#include "complete/committee.h"
#include "records/fit.h"
#include "svcclient/service_evaluator.h"

namespace pz::svcclient {

/// One session per global search of `piezoid fit` / `diagnose --records` (family RECORDS) and one
/// per Levenberg–Marquardt polish (RecordEvaluation::kResiduals: the spec's `residuals`, a Jacobian
/// per batch), its family made with `family` as locally (sub-steps, plays), so that the costs and
/// residuals are the local ones.
records::RecordEvaluatorFactory RecordsServiceFactory(const ServiceEvaluatorOptions& options,
                                                      const records::FamilyOptions& family,
                                                      const std::string& owner);

/// One session per search of the committee, on the master of `options`; `family`: the committee's
/// family options (sub-steps, PI plays).
complete::EvaluatorFactory CommitteeServiceFactory(const ServiceEvaluatorOptions& options,
                                                   const records::FamilyOptions& family);

}  // namespace pz::svcclient
