// General path of the bimorph plant: the full FE system integrated with SUNDIALS CVODE (BDF,
// analytic Jacobian). Any plant extension that couples to the beam state runs on this path.
#pragma once

#include "model/bimorph.h"

namespace pz::model {

/// Simulates the spec'd plant with CVODE BDF. Assumes params/drive/options validated and the loop
/// bounded (Simulate() in bimorph.h does that); never throws.
BimorphTrace SimulateCvode(const BimorphPlant& plant, const BimorphParams& params,
                           const DriveSignal& drive, const SimulateOptions& options);

}  // namespace pz::model
