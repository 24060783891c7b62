// PLACEHOLDER — being replaced by the CVODE-path implementation.
#include "model/bimorph_cvode.h"
namespace pz::model {
BimorphTrace SimulateCvode(const BimorphPlant&, const BimorphParams&, const DriveSignal&, const SimulateOptions&) {
  BimorphTrace t;
  t.summary.status = SimStatus::kSolverFailure;
  t.summary.message = "cvode solver not built yet";
  return t;
}
}  // namespace pz::model
