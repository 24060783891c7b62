#include "model/modal_solver.h"

#include "model/modal_simulator.h"

namespace pz::model {

BimorphTrace SimulateModal(const BimorphPlant& plant, const BimorphParams& params,
                           const DriveSignal& drive) {
  const ModalSimulator sim(plant);
  ModalWorkspace ws;
  BimorphTrace trace;
  sim.Simulate(params, drive, trace, ws);
  return trace;
}

}  // namespace pz::model
