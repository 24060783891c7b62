// Summary records returned by every simulation (conventions: a run returns a record, never throws
// for an expected runtime failure such as an unbounded Bouc–Wen loop or a failed solve).
#pragma once

#include <string>

namespace pz::model {

enum class SimStatus : int {
  kOk = 0,
  kUnboundedHysteresis = 1,  ///< the Bouc–Wen loop diverges (α ≠ 0 and not (β+γ > 0 and β−γ ≥ 0))
  kSolverFailure = 2,  ///< the integrator failed (flag in solver_flag)
  kNonFinite = 3,      ///< a state or output became NaN / inf
  kInvalidInput = 4,   ///< parameters or signal failed validation
};

const char* SimStatusName(SimStatus s);

struct SimulationSummary {
  SimStatus status = SimStatus::kOk;
  std::string message;      ///< empty on success, else what went wrong and where
  long steps = 0;           ///< integrator steps (or discrete steps of the fast path)
  long rhs_calls = 0;       ///< right-hand-side evaluations (CVODE path)
  long jacobian_calls = 0;  ///< Jacobian evaluations (CVODE path)
  int solver_flag = 0;      ///< last SUNDIALS return flag (CVODE path)
  double wall_time_s = 0;   ///< wall time of the simulation [s]

  bool ok() const { return status == SimStatus::kOk; }
  std::string BriefReport() const;
};

}  // namespace pz::model
