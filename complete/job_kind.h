// The "complete_model" job kind (issue 7): complete-model identification on the service. The
// optimiser (PSO, real or binary GA, opt/param_search.h) runs in the client (`piezoid boucwen
// --master`, `piezoid committee --master`) and evaluates its swarms / generations through an
// evaluation session (svcclient/service_evaluator.h); the spec (proto CompleteModelProblem) carries
// the model family, the records and the criterion, so that the workers rebuild the client's
// fitness (the Bouc–Wen benchmark's BwTraining, complete/boucwen_benchmark.h; the records engine's
// RecordFitness and CriterionFitness for any records/families.h family, the committee's included)
// from the spec alone: the same costs bit for bit.
// The master and the workers register the kind from their main(); pz::master cannot depend on
// pz::complete.
#pragma once

#include <memory>
#include <string>

#include "complete/boucwen_benchmark.h"
#include "job/job_kind.h"
#include "job/job_spec.h"
#include "records/criterion.h"
#include "records/fit.h"

namespace pz::complete {

/// The Bouc–Wen benchmark's identification (family BW_OSCILLATOR: its records, sub-steps, input
/// interpolation and period, penalty).
job::CompleteModelProblem CompleteModelProblemOf(const BwTraining& training);
/// `piezoid fit` / `diagnose --records` on the service (family RECORDS): the training records
/// without the part of their leading rest that is not scored (the model is at rest there: the cut
/// changes no cost, bit for bit), the family, effects and data scale, and the family's options
/// (sub-steps, Prandtl–Ishlinskii plays) it was made with. bimorph-fin's bench form
/// (Family::simulates_records): its records whole with their stated sinusoid, the effects in the
/// model's order, bench_form and `options.fin_sim`; InputError when `options` are not a bench
/// form's (the options must be those the family was made with). `residuals`: the polish's spec
/// (CompleteModelProblem::residuals: each result the residual vector of
/// records::RecordResidualFitness); false: the search's, whose bytes and job id are those of a
/// spec made before the field.
job::CompleteModelProblem CompleteModelProblemOf(const records::RecordFitness& fitness,
                                                 const records::FamilyOptions& options,
                                                 bool residuals = false);
/// The committee's fitness (family RECORDS with its criterion and window; the records whole, since
/// the window is in their own time); `options`: the family's (sub-steps, PI plays).
job::CompleteModelProblem CompleteModelProblemOf(const records::CriterionFitness& fitness,
                                                 const records::FamilyOptions& options);

/// A whole session spec (algorithm set by the caller; seed 0; errors and quarantined individuals
/// cost opt::kDefaultErrorCost, as in the local evaluators).
job::JobSpec CompleteModelJobSpec(job::CompleteModelProblem problem, const std::string& name);

/// The fitness a spec describes (what a worker evaluates). InvalidArgument naming the field when
/// the spec is not valid.
Status MakeCompleteModelFitness(const job::JobSpec& spec,
                                std::unique_ptr<opt::FitnessFunction>* out);

job::JobKind CompleteModelJobKind();

}  // namespace pz::complete
