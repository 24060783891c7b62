// `piezoid export --plant`: the bimorph-fin plant (model/modal_simulator.h, sampled-drive path) as
// a per-sample C recursion, appended to the network header of controller/export_c.h so that a
// controller computes the fin angle for any drive and the drive for a desired angle:
//
//   int    NAME_params(amplitude_v, frequency_hz, p)       the network, with a range check
//   int    NAME_init(&state, p, b1, b2, u0)                 zero state at drive u0
//   double NAME_step(&state, u)                             forward: the angle at the next sample
//   double NAME_inverse_step(&state, angle_desired)         inverse: the drive, and the step taken
//
// The recursion is ModalSimulator::RunSampled's for one sample of a uniform grid: the C step
// kernel's (model/kernels/fin_modal.h: the poles and exact discretisation of each mode, the
// sub-steps, the closed-form Bouc–Wen branches and zero-crossing splits, the quintic Hermite hold,
// atan series and backlash step — the records bimorph-fin kernel's too), copied into the header
// before the plant, controller/fin_plant.h (C99, embedded by the build). The plant's modal data
// (ω_i², tip gains, L) and the sample period are computed here by the library and written as exact
// hex-float literals; μ, δ (hence the discretisation), α, β, γ, a1, a2 come from the network at
// run time (NAME_init).
#pragma once

#include <string>

#include "controller/export_c.h"
#include "model/modal_simulator.h"
#include "model/status.h"

namespace pz::controller {

/// The plant part (types, NAME_params, NAME_init, NAME_step, NAME_inverse_step) for `sim`'s plant,
/// to follow the network's function in the header. kInvalidArgument naming the flag on a bad
/// sample rate or drive limit.
Status FinPlantToC(const model::ModalSimulator& sim, const model::Network& network,
                   const FinPlantExport& options, const std::string& name, std::string* text);

}  // namespace pz::controller
