// The step kernels of piezoid (issue 23; one home since issue 38): a model's per-sample
// arithmetic, forward and inverse, as plain C99 over double arrays. The one source of a step:
// compiled into the C++ side here, in namespace pz::pzk (records/stepper.h runs the chain of a
// fitted model; the effects' and families' registrations take their ids), and copied verbatim, in
// the order of the includes below, into every header `piezoid export` writes
// (model/kernels/kernel_text.h: the build embeds the files this header lists,
// model/CMakeLists.txt). A new kernel file: its include line here, nothing else.
#pragma once

#include <math.h>  // NOLINT: the kernels are C99 and call the C library's functions

#include <cmath>

// The table of kinds (chain.h pzk_kinds) names in each entry only the operations the kind has, as
// C99 designated initialisers do; C++ warns of the others (zero, as in C).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
namespace pz::pzk {
#include "model/kernels/common.h"
#include "model/kernels/effects.h"
#include "model/kernels/stack_models.h"
#include "model/kernels/play_operators.h"
#include "model/kernels/bw_oscillator.h"
#include "model/kernels/fin_modal.h"
#include "model/kernels/bimorph_fin.h"
#include "model/kernels/chain.h"
}  // namespace pz::pzk
#pragma GCC diagnostic pop
