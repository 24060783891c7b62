// A reusable C++ front end to SUNDIALS CVODE (6.x, SUNContext API) for any first-order system
//
//   ẏ = f(t, y),   y(t0) = y0,   y ∈ ℝⁿ
//
// integrated with BDF (stiff) or Adams (non-stiff), Newton iteration with a dense or banded
// analytic (or difference-quotient) Jacobian, or fixed-point iteration. The states are returned at
// a list of output times together with a SimulationSummary (steps, RHS and Jacobian calls, last
// CVODE flag, message). Between outputs the integrator can be stopped exactly at breakpoints (times
// where f is not smooth), at zero crossings of root functions, and a discrete-update hook may
// change the state there.
//
// Guarantees: every SUNDIALS object is owned by an RAII handle and freed on every path; no
// exception crosses a SUNDIALS callback (exceptions become a fatal return and a message); SUNDIALS
// error output is routed into SimulationSummary::message, never to stderr; each call creates its
// own SUNContext, so any number of threads may integrate at once (each with its own OdeSystem
// object, or with a shared one whose const methods are thread-safe).
#pragma once

#include <functional>
#include <span>
#include <vector>

#include "model/simulation.h"
#include "model/status.h"

namespace pz::model {

/// Linear multistep family.
enum class OdeMethod : int {
  kBdf = 0,    ///< backward differentiation formulas, orders 1–5: stiff problems
  kAdams = 1,  ///< Adams–Moulton, orders 1–12: non-stiff problems
};

/// Nonlinear iteration of the corrector.
enum class NonlinearIteration : int {
  kNewton = 0,      ///< modified Newton with a direct linear solver (needed for stiff problems)
  kFixedPoint = 1,  ///< functional iteration, no Jacobian (non-stiff problems only)
};

/// Matrix storage of the Newton linear solver.
enum class LinearSolverKind : int {
  kAuto = 0,    ///< the system's declared structure: banded if it declares a band, else reduced
                ///< dense if it declares kinematic rows, else dense
  kDense = 1,   ///< dense LU
  kBanded = 2,  ///< banded LU with the system's declared bandwidths
  kReduced =
      3,  ///< dense LU after eliminating the declared kinematic rows (JacobianStructure::kinematic)
};

const char* OdeMethodName(OdeMethod m);

/// What a system says about ∂f/∂y.
struct JacobianStructure {
  bool analytic = false;  ///< the system implements OdeSystem::Jacobian()
  bool banded = false;    ///< ∂f_i/∂y_j = 0 whenever j − i > upper or i − j > lower
  int upper = 0;          ///< upper bandwidth, 0 … n−1 (banded only)
  int lower = 0;          ///< lower bandwidth, 0 … n−1 (banded only)
  /// Second-order structure: ẏ_i = y_{k+i} exactly for i < k (k positions, then their velocities).
  /// With k > 0 the dense Newton systems (I − γJ) x = b are solved by eliminating the k position
  /// unknowns, x_i = b_i + γ x_{k+i}: an (n − k)-sized LU instead of n-sized, same solution.
  int kinematic = 0;
};

/// Writable view of a Jacobian J(i, j) = ∂f_i/∂y_j in SUNDIALS dense (column-major) or band
/// storage. The same code can fill either storage: in a banded view, writes outside the band are
/// dropped (a system that declares a band never makes any; one that does not, gets a
/// modified-Newton matrix). The matrix is zero when the system's Jacobian() is called.
class JacobianView {
 public:
  /// Dense, column-major n × n storage (e.g. an Eigen::MatrixXd's data()).
  JacobianView(double* data, int n) : data_(data), n_(n), ldim_(n) {}
  /// SUNDIALS band storage: column j at data + j·ldim, J(i, j) at offset storage_upper + i − j.
  static JacobianView Banded(double* data, int n, int upper, int lower, int storage_upper,
                             int ldim);

  int size() const { return n_; }
  bool banded() const { return banded_; }
  bool InBand(int i, int j) const { return !banded_ || (j - i <= upper_ && i - j <= lower_); }
  void Set(int i, int j, double v) {
    if (InBand(i, j)) Ref(i, j) = v;
  }
  void Add(int i, int j, double v) {
    if (InBand(i, j)) Ref(i, j) += v;
  }
  double Get(int i, int j) const {
    return InBand(i, j) ? const_cast<JacobianView*>(this)->Ref(i, j) : 0.0;
  }

 private:
  JacobianView() = default;
  double& Ref(int i, int j) {
    PZ_CHECK(i >= 0 && i < n_ && j >= 0 && j < n_);
    return data_[static_cast<long>(j) * ldim_ + i + (banded_ ? storage_upper_ - j : 0)];
  }
  double* data_ = nullptr;
  int n_ = 0;
  int ldim_ = 0;
  bool banded_ = false;
  int upper_ = 0, lower_ = 0, storage_upper_ = 0;
};

/// A first-order system ẏ = f(t, y). Return codes of the callbacks follow SUNDIALS: 0 success, > 0
/// recoverable (CVODE retries with a smaller step), < 0 fatal (the integration stops with a
/// status). Callbacks must not throw (an exception is caught at the boundary and treated as fatal).
class OdeSystem {
 public:
  virtual ~OdeSystem() = default;
  /// Number of states n ≥ 1.
  virtual int size() const = 0;
  /// ydot = f(t, y).
  virtual int Rhs(double t, const double* y, double* ydot) const = 0;
  /// Structure of ∂f/∂y; by default no analytic Jacobian (CVODE uses difference quotients) and
  /// dense.
  virtual JacobianStructure jacobian_structure() const { return {}; }
  /// Fills jac with ∂f/∂y at (t, y); fy = f(t, y). Called only if jacobian_structure().analytic.
  virtual int Jacobian(double t, const double* y, const double* fy, JacobianView& jac) const {
    return -1;
  }
  /// Number of root functions g(t, y) whose zero crossings stop the integration (0 = none).
  virtual int num_roots() const { return 0; }
  /// g(t, y) into g[0 … num_roots()−1].
  virtual int Roots(double t, const double* y, double* g) const { return 0; }
};

/// Where and why the integrator stopped before calling the discrete-update hook.
struct StopEvent {
  double t = 0;             ///< [s]
  int output_index = -1;    ///< index into the output times if t is one of them, else −1
  bool breakpoint = false;  ///< t is one of CvodeOptions::breakpoints
  std::span<const int>
      roots;  ///< per root function: 0, or the direction ±1 of its crossing at t; empty if none
};

/// What the hook asks of the integrator.
enum class StopAction : int {
  kContinue = 0,  ///< nothing changed: carry on (y must be left untouched)
  kRestart = 1,   ///< y and/or the right-hand side changed: restart the integrator at (t, y)
  kFail = 2,      ///< stop the integration with SimStatus::kSolverFailure
};

/// Discrete update between outputs: called at every output time (after the output is recorded, so
/// an output holds y(t⁻)), every breakpoint and every root. It may change y (then return kRestart).
using StopHook = std::function<StopAction(const StopEvent& event, std::span<double> y)>;

struct CvodeOptions {
  OdeMethod method = OdeMethod::kBdf;
  NonlinearIteration iteration = NonlinearIteration::kNewton;
  LinearSolverKind linear_solver = LinearSolverKind::kAuto;
  bool use_analytic_jacobian = true;  ///< if the system has one; false: CVODE difference quotients
  double rtol = 1e-8;                 ///< relative tolerance, in (0, 1)
  double atol = 1e-12;              ///< absolute tolerance on every state, > 0 (unless atol_vector)
  std::vector<double> atol_vector;  ///< per-state absolute tolerances (> 0, size n); overrides atol
  long max_steps = 1000000;         ///< step budget for the whole integration (all restarts), > 0
  double max_step = 0;              ///< largest step [s], ≥ 0 (0 = unlimited)
  double initial_step = 0;          ///< first step [s], ≥ 0 (0 = CVODE's estimate)
  int max_order = 0;                ///< ≥ 0 (0 = the method's maximum: BDF 5, Adams 12)
  /// BDF stability limit detection: lowers the order when orders 3–5 go unstable on eigenvalues
  /// near the imaginary axis (lightly damped oscillators). No effect with Adams.
  bool stability_limit_detection = false;
  /// Times where f is not smooth (u̇ jumps, |·| kinks): the integrator stops exactly there (tstop)
  /// and restarts, so no step straddles one. Must be finite; those outside (t0, t_out.back()) are
  /// ignored.
  std::vector<double> breakpoints;
  bool restart_at_outputs = false;  ///< treat every output time as a breakpoint too
  StopHook on_stop;                 ///< optional discrete-update hook (see StopHook)

  /// Checks the options against a system of n states.
  Status Validate(int n) const;
};

/// States at the output times and the run's summary record.
struct OdeSolution {
  int n = 0;              ///< number of states
  std::vector<double> t;  ///< output times reached [s]: all of them when summary.ok()
  std::vector<double> y;  ///< y[k·n + i] = state i at t[k]
  SimulationSummary summary;

  std::span<const double> state(size_t k) const {
    return {y.data() + k * n, static_cast<size_t>(n)};
  }
  double at(size_t k, int i) const { return y[k * n + i]; }
};

/// Integrates system from (t0, y0) and records y at every t_out (finite, strictly increasing, all ≥
/// t0; an output at t0 is y0). Never throws: invalid input comes back as SimStatus::kInvalidInput,
/// a CVODE failure as kSolverFailure with the flag and CVODE's message, a non-finite state as
/// kNonFinite. A BDF run that stops on repeated error-test failures (CV_ERR_FAILURE: a kink of f
/// off the breakpoints) is run once more at order ≤ 2 with the same tolerances; its result is the
/// answer.
OdeSolution IntegrateCvode(const OdeSystem& system, double t0, std::span<const double> y0,
                           std::span<const double> t_out, const CvodeOptions& options);

}  // namespace pz::model
