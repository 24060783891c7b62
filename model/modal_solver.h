// Fast path of the bimorph plant: modal decomposition of (K, M) once per geometry, exact
// discretisation of each modal oscillator  η̈ + (μ + δ ω²) η̇ + ω² η = g_u u(t) − g_z z(t),
// with the Bouc–Wen force z(t) integrated accurately (it depends on u alone).
#pragma once

#include "model/bimorph.h"

namespace pz::model {

/// Simulates the spec'd plant on the fast path. Assumes params/drive validated and the loop bounded
/// (Simulate() in bimorph.h does that); never throws.
BimorphTrace SimulateModal(const BimorphPlant& plant, const BimorphParams& params,
                           const DriveSignal& drive);

}  // namespace pz::model
