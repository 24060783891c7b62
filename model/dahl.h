// The Dahl-model piezoelectric actuator of seed 001 (spec "dahl-model"):
//
//   m d̈ + ε ḋ + g d = k v(t) − F_h,      F_h = a1 b1 + b0 a2 sgn(ḋ),      d(0) = ḋ(0) = 0
//
// integrated with CVODE's Adams method (as the paper's reference, Mathematica NDSolve with Adams).
//
// The sgn(ḋ) term is a Coulomb-like force c sgn(ḋ), c = b0 a2, discontinuous at ḋ = 0. It is
// handled exactly, event by event: the sign s ∈ {−1, 0, +1} is a discrete state held constant
// between events; a root function stops the integrator where ḋ crosses 0 (while sliding) or where
// the driving force F0 = k v − g d − a1 b1 leaves [−c, c] (while stuck), and the mode is then
// chosen Filippov-style: slide up if F0 > c, down if F0 < −c, else stick (ḋ = 0, d held) until F0
// leaves [−c, c]. With the spec's b0 = 0 the term vanishes, the system is linear and smooth, and no
// events are needed.
#pragma once

#include <functional>
#include <span>
#include <vector>

#include "model/simulation.h"
#include "model/status.h"

namespace pz::model {

/// Parameters of the Dahl plant, defaults from the spec's table.
struct DahlParams {
  double m = 0.1828;         ///< mass [kg], finite, > 0
  double epsilon = 190.154;  ///< ε, damping [N s/m], finite, ≥ 0
  double g = 2.6e4;          ///< stiffness [N/m], finite, ≥ 0
  double k = 0.0336;         ///< input gain [C/m = N/V], finite
  double b1 = 3.09292e5;     ///< Dahl coefficient b1 [N per unit a1], finite
  double b0 = 0.0;           ///< Dahl coefficient b0 [N per unit a2], finite
  double a1 = -0.25886;      ///< [-], finite
  double a2 = 7.0626;        ///< [-], finite
  Status Validate() const;
  /// Coulomb level c = b0 a2 of the sgn(ḋ) term [N].
  double coulomb() const { return b0 * a2; }
};

/// The spec's four input signals v(t) [V], t ∈ [0, 10] s.
enum class DahlSignal : int {
  kSine = 1,          ///< 1: sin(t)
  kOffsetSine = 2,    ///< 2: 50 + 50 sin(π t)
  kChirp = 3,         ///< 3: 5 e^(−0.13 t) (cos(3π t e^(−0.09 t)) − 3.15) + 1
  kDampedCosine = 4,  ///< 4: 5 + 3.4 e^(−0.24 t) cos(2π t)
};

/// v(t) [V] of a spec signal.
double DahlSignalValue(DahlSignal s, double t);
/// v̇(t) [V/s] of a spec signal (analytic).
double DahlSignalRate(DahlSignal s, double t);

/// Any input v(t) [V]; must be finite, and smooth between the caller's breakpoints.
using DahlInput = std::function<double(double)>;
/// The spec signal as a DahlInput.
DahlInput MakeDahlInput(DahlSignal s);

struct DahlOptions {
  double rtol = 1e-12;       ///< CVODE relative tolerance, in (0, 1e-2]
  double atol = 1e-14;       ///< absolute tolerance on d [m] and ḋ [m/s], > 0
  long max_steps = 5000000;  ///< step budget for the run, > 0
  Status Validate() const;
};

/// Outputs at the requested times.
struct DahlTrace {
  std::vector<double> t;      ///< [s]
  std::vector<double> v;      ///< input [V]
  std::vector<double> d;      ///< displacement d
  std::vector<double> d_dot;  ///< ḋ
  SimulationSummary summary;
};

/// The paper's output grid: 0, dt, …, t_end (10,001 points for the defaults).
std::vector<double> DahlGridTimes(double t_end = 10.0, double dt = 1e-3);

/// Simulates from rest at t = 0 (CVODE Adams, Newton iteration with the analytic Jacobian) and
/// samples at times (finite, strictly increasing, ≥ 0). Never throws: invalid input comes back as
/// SimStatus::kInvalidInput, a failed solve as kSolverFailure, each with a message.
DahlTrace SimulateDahl(const DahlParams& params, const DahlInput& input,
                       std::span<const double> times, const DahlOptions& options = {});
/// The same for a spec signal.
DahlTrace SimulateDahl(const DahlParams& params, DahlSignal signal, std::span<const double> times,
                       const DahlOptions& options = {});

}  // namespace pz::model
