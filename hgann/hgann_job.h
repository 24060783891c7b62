// The "hgann" job kind: a job spec's HgannProblem (proto/job.proto) becomes the HGANN fitness of
// hgann/hgann_fitness.h, the same computation as `piezoid identify` on the same case set.
//
//   spec.hgann (cases with their samples, ranges preset + overrides, saturation policy, geometry
//   overrides, spread penalty)
//     → io::CaseSet (t_k = k / fs, as LoadCaseSet would have read it)
//     → HgannConfigFromCaseSet(set, ranges, given)   (each case by io::MakeFinCase: the given
//          saturations or those of the measured extremes; training = role train; normalisation
//          over the training cases)
//     → geometry, spread penalty → HgannFitness.
//
// The genome is the 1415-bit chromosome of model/chromosome.h. Registered in
// kinds::All(), so the master (validation, in-process runs) and every worker have it.
#pragma once

#include <vector>

#include "io/bench_data.h"
#include "hgann/hgann_fitness.h"
#include "job/job_kind.h"
#include "job/job_spec.h"
#include "model/network.h"
#include "model/status.h"

namespace pz::hgann {

/// Every violated rule of an hgann problem, with paths as in the JSON spec, e.g.
/// "hgann.cases[3].angle_deg[17] = nan: must be finite". Empty when the problem builds a fitness.
std::vector<job::FieldViolation> ValidateHgannProblem(const job::HgannProblem& problem);

/// The preset's ranges ("" = "default": spec §3; "paper": the paper's Table 3) with the problem's
/// per-parameter overrides applied. Errors name the field.
Status HgannRanges(const job::HgannProblem& problem, model::ParameterRanges* ranges);

/// The problem's cases as a bench case set: t_k = k / fs, u = the recorded voltage or the stated
/// V sin(2π f t_k), dir = problem.source, file = "case<N>". Requires a valid problem.
io::CaseSet HgannCaseSet(const job::HgannProblem& problem);

/// The fitness configuration of a problem (see the file comment). Errors name the field.
Status HgannConfigFromProblem(const job::HgannProblem& problem, HgannFitnessConfig* config);

/// An HgannProblem holding every case of a loaded set (samples and recorded voltage, roles), with
/// source = set.dir; ranges, saturation, geometry and penalty left at their defaults.
job::HgannProblem HgannProblemFromCaseSet(const io::CaseSet& set);

/// The job kind (name "hgann", layout 1415 bits, describer = the decoded architecture).
job::JobKind HgannJobKind();

}  // namespace pz::hgann
