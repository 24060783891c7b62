// The bimorph-fin actuator plant (spec "bimorph-fin model"):
//
//   M q̈ + C q̇ + K q = B_u u(t) − e* z(t),        C = μ M + δ K
//   ż = α u̇ − β |u̇| z − γ u̇ |z|                  (Bouc–Wen, exponent 1, z(0) = 0)
//   θ(t) = atan(w_tip / L) [deg],   y_k = Backlash_{a1,a2,b1,b2}(θ_k)
//
// A BimorphPlant is immutable (geometry, FE matrices and modal basis computed once) and can serve
// any number of threads; every simulation returns a BimorphTrace with a SimulationSummary.
#pragma once

#include <vector>

#include "model/backlash.h"
#include "model/beam.h"
#include "model/signal.h"
#include "model/simulation.h"

namespace pz::model {

/// The nine parameters of one case. Damping and hysteresis are identified; a1, a2 too; b1, b2 are
/// fitted from the measured extremes (paper Appendix B).
struct BimorphParams {
  double mu = 95.0;       ///< μ, mass coefficient of the Rayleigh damping [1/s], finite, ≥ 0
  double delta = 0.1;     ///< δ, stiffness coefficient of the Rayleigh damping [s], finite, ≥ 0
  double alpha = 2.5e-3;  ///< α, Bouc–Wen input gain [N/V], finite
  double beta = 6e-3;     ///< β [1/V], finite
  double gamma = 4e-3;    ///< γ [1/V], finite
  double a1 = 0.1;        ///< rising backlash threshold [deg], finite, ≥ 0
  double a2 = 0.15;       ///< falling backlash threshold [deg], finite, ≥ 0
  double b1 = 1.0;        ///< upper saturation [deg], finite, > 0
  double b2 = -1.0;       ///< lower saturation [deg], finite, < 0

  /// Field-named error for non-finite values or broken ranges. An unbounded Bouc–Wen loop is NOT a
  /// validation error (it is a runtime outcome, see HysteresisBounded()).
  Status Validate() const;
  /// True iff the Bouc–Wen loop stays bounded: α = 0, or β + γ > 0 and β − γ ≥ 0.
  bool HysteresisBounded() const;
  BacklashParams backlash() const { return {a1, a2, b1, b2}; }
};

/// Outputs on the signal's sample grid.
struct BimorphTrace {
  std::vector<double> t;          ///< [s]
  std::vector<double> u;          ///< drive [V]
  std::vector<double> z;          ///< Bouc–Wen force [N]
  std::vector<double> w_tip;      ///< tip deflection [m]
  std::vector<double> theta_deg;  ///< linear fin angle atan(w_tip/L) [deg]
  std::vector<double> angle_deg;  ///< backlash output y [deg]
  SimulationSummary summary;
};

class BimorphPlant {
 public:
  /// Assembles the FE model and its modal basis. Throws InputError on an invalid geometry.
  explicit BimorphPlant(const BeamGeometry& geometry = {});

  const BeamGeometry& geometry() const { return geometry_; }
  const FeModel& fe() const { return fe_; }
  const ModalBasis& modal() const { return modal_; }
  /// Fin angle [deg] for a tip deflection [m]: atan(w / L).
  double TipToDegrees(double w_tip) const;

 private:
  BeamGeometry geometry_;
  FeModel fe_;
  ModalBasis modal_;
};

enum class Solver : int {
  kModal = 0,  ///< fast path: modal decomposition + exact discretisation (spec'd plant only)
  kCvode = 1,  ///< general path: SUNDIALS CVODE BDF with an analytic Jacobian
};

const char* SolverName(Solver s);

struct SimulateOptions {
  Solver solver = Solver::kModal;
  double rtol = 1e-10;        ///< CVODE relative tolerance, in (0, 1e-2]
  double atol = 1e-14;        ///< CVODE absolute tolerance on the states, > 0
  long max_steps = 10000000;  ///< CVODE step budget for the whole run, > 0
  Status Validate() const;
};
/// The checks of a CVODE run's rtol, atol and max_steps (SimulateOptions's, and every caller that
/// carries the three), naming the failing field.
Status ValidateCvodeSettings(double rtol, double atol, long max_steps);

/// Simulates the plant. Never throws for a parameter set that is merely bad physics: an unbounded
/// hysteresis loop, a failed solve or a non-finite state come back in trace.summary.
/// Invalid parameters or signals come back as SimStatus::kInvalidInput with the field named.
BimorphTrace Simulate(const BimorphPlant& plant, const BimorphParams& params,
                      const DriveSignal& drive, const SimulateOptions& options = {});

}  // namespace pz::model
