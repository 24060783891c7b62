// The self-contained C99 header of a fitted record model (issue 23, `piezoid export FIT.json`):
// the step kernels of model/kernels/ copied verbatim (embedded at build time, so the header and
// the C++ Stepper run the same source), the model's blocks with every parameter as an exact
// hex-float literal, a state struct of fixed size and
//
//   double NAME_init(NAME_state *s, double u0);            at rest under u0; returns the output
//   double NAME_step(NAME_state *s, double u);             forward: drive -> response
//   double NAME_inverse_step(NAME_state *s, double y_des); compensator: desired response -> drive
//
// Only <math.h>; no allocation, no mutable global (the blocks are a static const table).
#pragma once

#include <string>

#include "records/stepper.h"

namespace pz::controller {

/// The header text for `name` (a C identifier, checked: InputError). `comment` goes into the
/// header's first comment (provenance).
std::string ExportHeader(const records::Stepper& stepper, const std::string& name,
                         const std::string& comment);

}  // namespace pz::controller
