// The "diagnose" job kind: the global fit of one diagnosis model structure as a job on the service
// (issue 6: "re-identify the augmented model … as jobs on the service"). Its spec (proto
// DiagnoseProblem) carries the bench cases, the structure (effect names), the parameter boxes and
// the simulation options, so that DiagnosisFitness is a pure function of (genome.reals, spec); the
// optimiser (DE, Levenberg–Marquardt) runs in the client and evaluates through an evaluation
// session (JobSpec.external, svcclient/service_evaluator.h). The master and the workers register
// the kind from their main(); pz::master cannot depend on pz::diagnose.
#pragma once

#include "diagnose/problem.h"
#include "job/job_kind.h"
#include "job/job_spec.h"

namespace pz::diagnose {

/// The spec's problem for `fitness` (its model's cases, its layout and residual mode). The model
/// must run on the bench's default beam (the kind builds that plant).
job::DiagnoseProblem DiagnoseProblemOf(const DiagnosisFitness& fitness);

/// A whole session spec for `fitness` (algorithm set by the caller; seed 0; errors and quarantined
/// individuals cost opt::kDefaultErrorCost, as in the local evaluators).
job::JobSpec DiagnoseJobSpec(const DiagnosisFitness& fitness, const std::string& name);

job::JobKind DiagnoseJobKind();

}  // namespace pz::diagnose
