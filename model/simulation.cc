#include "model/simulation.h"

#include <cstdio>

namespace pz::model {

const char* SimStatusName(SimStatus s) {
  switch (s) {
    case SimStatus::kOk:
      return "ok";
    case SimStatus::kUnboundedHysteresis:
      return "unbounded_hysteresis";
    case SimStatus::kSolverFailure:
      return "solver_failure";
    case SimStatus::kNonFinite:
      return "non_finite";
    case SimStatus::kInvalidInput:
      return "invalid_input";
  }
  return "unknown";
}

std::string SimulationSummary::BriefReport() const {
  char buf[256];
  std::snprintf(buf, sizeof buf, "%s: steps %ld, rhs %ld, jac %ld, flag %d, %.3g s",
                SimStatusName(status), steps, rhs_calls, jacobian_calls, solver_flag, wall_time_s);
  std::string r = buf;
  if (!message.empty()) r += " (" + message + ")";
  return r;
}

}  // namespace pz::model
