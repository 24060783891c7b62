// Complete-model searches on the workers of a piezoid-master (issue 7): the flags `piezoid boucwen`,
// `piezoid committee` (and `piezoid diagnose`) take to run every evaluation of their searches as
// evaluation sessions (--master, --timeout-ms, --retries, --curve-secret, --master-public), and the
// committee's EvaluatorFactory over the service. Each search is one session whose spec (the
// "complete_model" job kind, complete/job_kind.h) carries the fitness's records, so the results
// equal the local run's bit for bit.
#pragma once

#include <CLI/CLI.hpp>
#include <string>

#include "complete/committee.h"
#include "client/service_evaluator.h"
#include "records/fit.h"

namespace pz::client {

struct CompleteServiceFlags {
  std::string master;  ///< the master's client endpoint; empty = evaluate locally
  int timeout_ms = 4000;
  int retries = 3;
  std::string curve_secret, master_public;  ///< default: $PIEZOID_CURVE_SECRET, $PIEZOID_MASTER_PUBLIC
  CompleteServiceFlags();
  bool enabled() const { return !master.empty(); }
  /// The session options of these flags (CURVE keys loaded); throws InputError naming the flag.
  ServiceEvaluatorOptions Options() const;
};

/// Adds the flags to `cmd`.
void AddCompleteServiceFlags(CLI::App* cmd, CompleteServiceFlags& flags);

/// One session per global search of `piezoid fit` / `diagnose --records` (family RECORDS), its
/// family made with `family` as locally (sub-steps, plays), so that the costs are the local ones.
records::RecordEvaluatorFactory RecordsServiceFactory(const ServiceEvaluatorOptions& options,
                                                      const records::FamilyOptions& family, const std::string& owner);

/// One session per search of the committee, on the master of `options`; `family`: the committee's
/// family options (sub-steps, PI plays).
complete::EvaluatorFactory CommitteeServiceFactory(const ServiceEvaluatorOptions& options,
                                                   const records::FamilyOptions& family);

}  // namespace pz::client
