#include "model/bimorph.h"

#include <chrono>
#include <cmath>
#include <numbers>

#include "model/bimorph_cvode.h"
#include "model/modal_solver.h"

namespace pz::model {

Status BimorphParams::Validate() const {
  const std::pair<const char*, double> all[] = {{"mu", mu},     {"delta", delta}, {"alpha", alpha},
                                                {"beta", beta}, {"gamma", gamma}, {"a1", a1},
                                                {"a2", a2},     {"b1", b1},       {"b2", b2}};
  for (auto [name, v] : all)
    if (!std::isfinite(v)) return InvalidArgument(FieldError(name, v, "must be finite"));
  if (mu < 0) return InvalidArgument(FieldError("mu", mu, "must be >= 0 [1/s]"));
  if (delta < 0) return InvalidArgument(FieldError("delta", delta, "must be >= 0 [s]"));
  if (a1 < 0) return InvalidArgument(FieldError("a1", a1, "must be >= 0 [deg]"));
  if (a2 < 0) return InvalidArgument(FieldError("a2", a2, "must be >= 0 [deg]"));
  if (!(b1 > 0)) return InvalidArgument(FieldError("b1", b1, "must be > 0 [deg]"));
  if (!(b2 < 0)) return InvalidArgument(FieldError("b2", b2, "must be < 0 [deg]"));
  return Status::Ok();
}

bool BimorphParams::HysteresisBounded() const {
  return alpha == 0.0 || (beta + gamma > 0.0 && beta - gamma >= 0.0);
}

BimorphPlant::BimorphPlant(const BeamGeometry& geometry)
    : geometry_(geometry), fe_(AssembleBeam(geometry)), modal_(ComputeModalBasis(fe_)) {}

double BimorphPlant::TipToDegrees(double w_tip) const {
  return std::atan(w_tip / geometry_.TotalLength()) * (180.0 / std::numbers::pi);
}

const char* SolverName(Solver s) { return s == Solver::kModal ? "modal" : "cvode"; }

Status SimulateOptions::Validate() const { return ValidateCvodeSettings(rtol, atol, max_steps); }

Status ValidateCvodeSettings(double rtol, double atol, long max_steps) {
  if (!(rtol > 0 && rtol <= 1e-2))
    return InvalidArgument(FieldError("rtol", rtol, "must be in (0, 1e-2]"));
  if (!(atol > 0 && std::isfinite(atol)))
    return InvalidArgument(FieldError("atol", atol, "must be finite and > 0"));
  if (max_steps <= 0) return InvalidArgument(FieldError("max_steps", max_steps, "must be > 0"));
  return Status::Ok();
}

BimorphTrace Simulate(const BimorphPlant& plant, const BimorphParams& params,
                      const DriveSignal& drive, const SimulateOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  BimorphTrace trace;
  auto fail = [&](SimStatus st, std::string msg) {
    trace.summary.status = st;
    trace.summary.message = std::move(msg);
    trace.summary.wall_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return trace;
  };
  if (auto s = params.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  if (auto s = Validate(drive); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  if (auto s = options.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  if (!params.HysteresisBounded()) {
    return fail(
        SimStatus::kUnboundedHysteresis,
        FieldError(
            "(alpha, beta, gamma)",
            "(" + std::to_string(params.alpha) + ", " + std::to_string(params.beta) + ", " +
                std::to_string(params.gamma) + ")",
            "Bouc-Wen loop unbounded: needs alpha = 0, or beta + gamma > 0 and beta - gamma >= 0"));
  }
  trace = options.solver == Solver::kModal ? SimulateModal(plant, params, drive)
                                           : SimulateCvode(plant, params, drive, options);
  if (trace.summary.ok()) {
    for (size_t k = 0; k < trace.angle_deg.size(); ++k) {
      if (!std::isfinite(trace.angle_deg[k]) || !std::isfinite(trace.theta_deg[k])) {
        trace.summary.status = SimStatus::kNonFinite;
        trace.summary.message = "non-finite fin angle at sample " + std::to_string(k);
        break;
      }
    }
  }
  trace.summary.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return trace;
}

}  // namespace pz::model
