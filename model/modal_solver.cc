// PLACEHOLDER — being replaced by the fast-path implementation.
#include "model/modal_solver.h"
namespace pz::model {
BimorphTrace SimulateModal(const BimorphPlant&, const BimorphParams&, const DriveSignal&) {
  BimorphTrace t;
  t.summary.status = SimStatus::kSolverFailure;
  t.summary.message = "modal solver not built yet";
  return t;
}
}  // namespace pz::model
