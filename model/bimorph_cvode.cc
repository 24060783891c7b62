#include "model/bimorph_cvode.h"

#include <chrono>
#include <cmath>

#include "model/bimorph_ode.h"
#include "model/cvode.h"

namespace pz::model {

BimorphTrace SimulateBimorphOde(const BimorphPlant& plant, const BimorphParams& params,
                                const DriveSignal& drive, const SimulateOptions& options,
                                std::vector<const BimorphExtension*> extensions) {
  const auto start = std::chrono::steady_clock::now();
  BimorphTrace trace;
  trace.t = SampleTimes(drive);
  trace.u = SampleValues(drive);

  BimorphOde ode(plant, params, drive, std::move(extensions));
  CvodeOptions co;
  co.method = OdeMethod::kBdf;
  co.iteration = NonlinearIteration::kNewton;
  co.linear_solver = LinearSolverKind::kReduced;  // q̇ = v eliminated: see BimorphOde
  co.rtol = options.rtol;
  co.atol = options.atol;
  co.max_steps = options.max_steps;
  co.breakpoints = ode.Breakpoints();
  if (ode.piecewise_drive()) {
    // u̇ jumps at every sample: select the next linear piece and restart there.
    co.on_stop = [&ode](const StopEvent& ev, std::span<double>) {
      ode.SelectDrivePieceAt(ev.t);
      return StopAction::kRestart;
    };
  }
  const std::vector<double> y0 = ode.InitialState();
  const OdeSolution sol = IntegrateCvode(ode, trace.t.front(), y0, trace.t, co);
  trace.summary = sol.summary;

  const size_t n_out = sol.t.size();
  trace.t.resize(n_out);
  trace.u.resize(n_out);
  trace.z.resize(n_out);
  trace.w_tip.resize(n_out);
  trace.theta_deg.resize(n_out);
  trace.angle_deg.resize(n_out);
  for (size_t k = 0; k < n_out; ++k) {
    trace.z[k] = sol.at(k, ode.z_index());
    trace.w_tip[k] = sol.at(k, ode.tip_index());
    trace.theta_deg[k] = plant.TipToDegrees(trace.w_tip[k]);
  }
  ApplyBacklash(params.backlash(), trace.theta_deg, trace.angle_deg);
  trace.summary.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return trace;
}

BimorphTrace SimulateCvode(const BimorphPlant& plant, const BimorphParams& params,
                           const DriveSignal& drive, const SimulateOptions& options) {
  return SimulateBimorphOde(plant, params, drive, options);
}

}  // namespace pz::model
