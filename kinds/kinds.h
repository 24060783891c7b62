// The one list of job kinds. Every process that validates specs or builds fitnesses — the master,
// the workers, the fuzzer, the client (local runs, spec checks before submission) — takes its
// registry from All(), so a kind added here is available everywhere, and nowhere else needs to
// change. Each kind lives with its problem:
//   synthetic       kinds/kinds.cc           tests and benchmarks (null / function cost, sleeps,
//                                            an optional crash prefix)
//   hgann           hgann/hgann_job.h        the paper's bimorph-fin identification
//   complete_model  complete/job_kind.h      complete-model fitness (Bouc–Wen oscillator, stack
//                                            models) of `piezoid boucwen` / `piezoid committee`
#pragma once

#include "job/job_kind.h"

namespace pz::kinds {

/// The process-wide registry with every kind above (built on first use, then read-only).
const job::JobKindRegistry& All();

/// The "synthetic" kind (null / function cost, optional sleep, optional crash prefix).
job::JobKind SyntheticJobKind();

}  // namespace pz::kinds
