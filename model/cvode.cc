#include "model/cvode.h"

#include <cvode/cvode.h>
#include <cvode/cvode_ls.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_band.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_band.h>
#include <sunmatrix/sunmatrix_dense.h>
#include <sunnonlinsol/sunnonlinsol_fixedpoint.h>

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <limits>
#include <memory>
#include <new>
#include <string>
#include <type_traits>

namespace pz::model {

const char* OdeMethodName(OdeMethod m) { return m == OdeMethod::kBdf ? "bdf" : "adams"; }

JacobianView JacobianView::Banded(double* data, int n, int upper, int lower, int storage_upper,
                                  int ldim) {
  JacobianView v;
  v.data_ = data;
  v.n_ = n;
  v.ldim_ = ldim;
  v.banded_ = true;
  v.upper_ = upper;
  v.lower_ = lower;
  v.storage_upper_ = storage_upper;
  return v;
}

Status CvodeOptions::Validate(int n) const {
  if (!(rtol > 0 && rtol < 1))
    return InvalidArgument(FieldError("rtol", rtol, "must be in (0, 1)"));
  if (atol_vector.empty()) {
    if (!(atol > 0 && std::isfinite(atol)))
      return InvalidArgument(FieldError("atol", atol, "must be finite and > 0"));
  } else {
    if (static_cast<int>(atol_vector.size()) != n)
      return InvalidArgument(FieldError("atol_vector.size()", atol_vector.size(),
                                        "must equal the number of states " + std::to_string(n)));
    for (size_t i = 0; i < atol_vector.size(); ++i)
      if (!(atol_vector[i] > 0 && std::isfinite(atol_vector[i])))
        return InvalidArgument(FieldError("atol_vector[" + std::to_string(i) + "]", atol_vector[i],
                                          "must be finite and > 0"));
  }
  if (max_steps <= 0) return InvalidArgument(FieldError("max_steps", max_steps, "must be > 0"));
  if (!(max_step >= 0 && std::isfinite(max_step)))
    return InvalidArgument(FieldError("max_step", max_step, "must be finite and >= 0 [s]"));
  if (!(initial_step >= 0 && std::isfinite(initial_step)))
    return InvalidArgument(FieldError("initial_step", initial_step, "must be finite and >= 0 [s]"));
  const int order_cap = method == OdeMethod::kBdf ? 5 : 12;
  if (max_order < 0 || max_order > order_cap)
    return InvalidArgument(FieldError(
        "max_order", max_order,
        "must be in [0, " + std::to_string(order_cap) + "] for " + OdeMethodName(method)));
  for (size_t i = 0; i < breakpoints.size(); ++i)
    if (!std::isfinite(breakpoints[i]))
      return InvalidArgument(
          FieldError("breakpoints[" + std::to_string(i) + "]", breakpoints[i], "must be finite"));
  return Status::Ok();
}

namespace {

// ---- RAII handles for the SUNDIALS objects
// -------------------------------------------------------
struct ContextFree {
  void operator()(SUNContext c) const { SUNContext_Free(&c); }
};
struct VectorFree {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
struct MatrixFree {
  void operator()(SUNMatrix m) const { SUNMatDestroy(m); }
};
struct LinearSolverFree {
  void operator()(SUNLinearSolver s) const { SUNLinSolFree(s); }
};
struct NonlinearSolverFree {
  void operator()(SUNNonlinearSolver s) const { SUNNonlinSolFree(s); }
};
struct CvodeFree {
  void operator()(void* mem) const { CVodeFree(&mem); }
};
using ContextPtr = std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextFree>;
using VectorPtr = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorFree>;
using MatrixPtr = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixFree>;
using LinearSolverPtr = std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, LinearSolverFree>;
using NonlinearSolverPtr =
    std::unique_ptr<std::remove_pointer_t<SUNNonlinearSolver>, NonlinearSolverFree>;
using CvodePtr = std::unique_ptr<void, CvodeFree>;

std::string FlagName(int flag) {
  char* name = CVodeGetReturnFlagName(flag);
  std::string s = name ? name : "CV_UNKNOWN";
  std::free(name);
  return s;
}

std::string Num(double v) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.10g", v);
  return buf;
}

// ---- callback data and trampolines (no exception leaves them) -----------------------------------
struct RunData {
  const OdeSystem* system = nullptr;
  int n = 0;
  std::string cvode_message;  // last message from CVODE's error handler
  std::string callback_note;  // last problem a callback reported (kept even if CVODE recovered)

  void Note(std::string s) { callback_note = std::move(s); }
};

// Runs a user callback with no exception escaping into SUNDIALS: a throw becomes a fatal −1, and
// any non-zero return is noted with the callback's name and t for the summary message.
template <typename Body>
int Guarded(RunData* d, const char* what, double t, Body&& body) {
  try {
    const int r = body();
    if (r != 0) d->Note(std::string(what) + " returned " + std::to_string(r) + " at t = " + Num(t));
    return r;
  } catch (const std::exception& e) {
    d->Note(std::string("exception in ") + what + " at t = " + Num(t) + ": " + e.what());
  } catch (...) {
    d->Note(std::string("unknown exception in ") + what + " at t = " + Num(t));
  }
  return -1;
}

int RhsCallback(sunrealtype t, N_Vector y, N_Vector ydot, void* user_data) {
  auto* d = static_cast<RunData*>(user_data);
  double* f = N_VGetArrayPointer(ydot);
  if (const int r = Guarded(d, "right-hand side", t,
                            [&] { return d->system->Rhs(t, N_VGetArrayPointer(y), f); });
      r != 0)
    return r;
  for (int i = 0; i < d->n; ++i) {
    if (!std::isfinite(f[i])) {
      d->Note("right-hand side non-finite in state " + std::to_string(i) + " at t = " + Num(t));
      return 1;  // recoverable: CVODE retries with a smaller step
    }
  }
  return 0;
}

int JacobianCallback(sunrealtype t, N_Vector y, N_Vector fy, SUNMatrix jac, void* user_data,
                     N_Vector, N_Vector, N_Vector) {
  auto* d = static_cast<RunData*>(user_data);
  return Guarded(d, "Jacobian", t, [&] {
    SUNMatZero(jac);
    const int n = d->n;
    JacobianView view =
        SUNMatGetID(jac) == SUNMATRIX_BAND
            ? JacobianView::Banded(SUNBandMatrix_Data(jac), n,
                                   static_cast<int>(SUNBandMatrix_UpperBandwidth(jac)),
                                   static_cast<int>(SUNBandMatrix_LowerBandwidth(jac)),
                                   static_cast<int>(SUNBandMatrix_StoredUpperBandwidth(jac)),
                                   static_cast<int>(SUNBandMatrix_LDim(jac)))
            : JacobianView(SUNDenseMatrix_Data(jac), n);
    return d->system->Jacobian(t, N_VGetArrayPointer(y), N_VGetArrayPointer(fy), view);
  });
}

int RootCallback(sunrealtype t, N_Vector y, sunrealtype* g, void* user_data) {
  auto* d = static_cast<RunData*>(user_data);
  return Guarded(d, "root functions", t,
                 [&] { return d->system->Roots(t, N_VGetArrayPointer(y), g); });
}

void ErrorHandler(int error_code, const char* module, const char* function, char* msg,
                  void* user_data) {
  auto* d = static_cast<RunData*>(user_data);
  try {
    d->cvode_message = std::string(module ? module : "") + "/" + (function ? function : "") + ": " +
                       (msg ? msg : "");
  } catch (...) {
  }
}

// ---- reduced dense linear solver for systems with kinematic rows --------------------------------
// CVODE hands a matrix-based solver A = I − γJ. When rows i < k of J are exactly e_{k+i} (ẏ_i =
// y_{k+i}), rows i < k of A x = b read x_i − γ x_{k+i} = b_i, so x_i = b_i + γ x_{k+i};
// substituting into the other rows leaves S x_r = b_r − A_rq b_q with S = A_rr plus γ A_rq added to
// its first k columns.
struct ReducedContent {
  int n = 0, k = 0;
  void* cvode_mem = nullptr;  // for γ: the one CVODE formed A with
  double gamma = 0;
  Eigen::MatrixXd a_rq;                     // (n − k) × k block of A
  Eigen::PartialPivLU<Eigen::MatrixXd> lu;  // of S
  Eigen::VectorXd rhs, xr, xq;              // scratch, sized once
  int last_flag = 0;
};

ReducedContent* Reduced(SUNLinearSolver s) { return static_cast<ReducedContent*>(s->content); }

int ReducedSetup(SUNLinearSolver s, SUNMatrix a) {
  ReducedContent* c = Reduced(s);
  const int n = c->n, k = c->k, m = n - k;
  const Eigen::Map<const Eigen::MatrixXd> am(SUNDenseMatrix_Data(a), n, n);
  if (CVodeGetCurrentGamma(c->cvode_mem, &c->gamma) != CV_SUCCESS)
    return c->last_flag = SUNLS_MEM_NULL;
  c->a_rq = am.bottomLeftCorner(m, k);
  Eigen::MatrixXd reduced = am.bottomRightCorner(m, m);
  reduced.leftCols(k) += c->gamma * c->a_rq;
  c->lu.compute(reduced);
  // PartialPivLU does not report singularity: look for a zero pivot (recoverable, as
  // SUNLinSol_Dense).
  const Eigen::VectorXd pivots = c->lu.matrixLU().diagonal();
  for (int i = 0; i < m; ++i) {
    if (pivots[i] == 0.0 || !std::isfinite(pivots[i])) return c->last_flag = SUNLS_LUFACT_FAIL;
  }
  return c->last_flag = SUNLS_SUCCESS;
}

int ReducedSolve(SUNLinearSolver s, SUNMatrix, N_Vector x, N_Vector b, sunrealtype) {
  ReducedContent* c = Reduced(s);
  const int n = c->n, k = c->k, m = n - k;
  const Eigen::Map<const Eigen::VectorXd> bv(N_VGetArrayPointer(b), n);
  c->rhs.noalias() = bv.tail(m) - c->a_rq * bv.head(k);
  c->xr = c->lu.solve(c->rhs);
  c->xq = bv.head(k) + c->gamma * c->xr.head(k);  // before writing x: b may alias x
  Eigen::Map<Eigen::VectorXd> xv(N_VGetArrayPointer(x), n);
  xv.tail(m) = c->xr;
  xv.head(k) = c->xq;
  return c->last_flag = SUNLS_SUCCESS;
}

SUNLinearSolver NewReducedSolver(int n, int k, void* cvode_mem, SUNContext ctx) {
  SUNLinearSolver s = SUNLinSolNewEmpty(ctx);
  if (!s) return nullptr;
  auto* c = new (std::nothrow) ReducedContent;
  if (!c) {
    SUNLinSolFreeEmpty(s);
    return nullptr;
  }
  c->n = n;
  c->k = k;
  c->cvode_mem = cvode_mem;
  c->rhs.resize(n - k);
  c->xr.resize(n - k);
  c->xq.resize(k);
  s->content = c;
  s->ops->gettype = [](SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; };
  s->ops->getid = [](SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; };
  s->ops->initialize = [](SUNLinearSolver) { return static_cast<int>(SUNLS_SUCCESS); };
  s->ops->setup = ReducedSetup;
  s->ops->solve = ReducedSolve;
  s->ops->lastflag = [](SUNLinearSolver ls) {
    return static_cast<sunindextype>(Reduced(ls)->last_flag);
  };
  s->ops->free = [](SUNLinearSolver ls) {
    if (ls == nullptr) return static_cast<int>(SUNLS_SUCCESS);
    delete Reduced(ls);
    ls->content = nullptr;
    SUNLinSolFreeEmpty(ls);
    return static_cast<int>(SUNLS_SUCCESS);
  };
  return s;
}

// ---- stops: output times and breakpoints merged
// --------------------------------------------------
struct Stop {
  double t = 0;
  int first_output = -1;  // outputs [first_output, last_output] are recorded here
  int last_output = -1;
  bool breakpoint = false;
};

std::vector<Stop> MergeStops(double t0, std::span<const double> t_out,
                             const std::vector<double>& breakpoints) {
  const double t_end = t_out.back();
  const double tol = 64 * std::numeric_limits<double>::epsilon() *
                     std::max({std::abs(t0), std::abs(t_end), t_end - t0});
  struct Item {
    double t;
    int output;
  };
  std::vector<Item> items;
  items.reserve(t_out.size() + breakpoints.size() + 1);
  items.push_back({t0, -2});  // the start
  for (size_t k = 0; k < t_out.size(); ++k) items.push_back({t_out[k], static_cast<int>(k)});
  for (double b : breakpoints)
    if (b > t0 && b < t_end + tol) items.push_back({b, -1});
  std::stable_sort(items.begin(), items.end(),
                   [](const Item& a, const Item& b) { return a.t < b.t; });
  std::vector<Stop> stops;
  for (size_t i = 0; i < items.size();) {
    Stop s;
    s.t = items[i].t;
    bool has_output = false, is_start = false;
    size_t j = i;
    for (; j < items.size() && items[j].t - items[i].t <= tol; ++j) {
      const Item& it = items[j];
      if (it.output == -2) {
        is_start = true;
      } else if (it.output >= 0) {
        if (!has_output) s.first_output = it.output;
        s.last_output = it.output;
        if (!has_output && !is_start)
          s.t = it.t;  // an output time wins over a breakpoint close to it
        has_output = true;
      } else {
        s.breakpoint = true;
      }
    }
    if (is_start) {
      s.t = t0;
      s.breakpoint = false;  // nothing to stop at: the integration starts here
    }
    stops.push_back(s);
    i = j;
  }
  return stops;
}

struct Counters {
  long steps = 0, rhs = 0, jac = 0;
};

OdeSolution IntegrateOnce(const OdeSystem& system, double t0, std::span<const double> y0,
                          std::span<const double> t_out, const CvodeOptions& options);

}  // namespace

OdeSolution IntegrateCvode(const OdeSystem& system, double t0, std::span<const double> y0,
                           std::span<const double> t_out, const CvodeOptions& options) {
  OdeSolution sol = IntegrateOnce(system, t0, y0, t_out, options);
  // BDF at high order can stall at a kink of f that is not a breakpoint (repeated error-test
  // failures with h at its minimum, e.g. a Bouc–Wen |z| crossing zero): once more at order ≤ 2,
  // which steps through it, with the same tolerances. A run that succeeded is untouched.
  if (sol.summary.status == SimStatus::kSolverFailure &&
      sol.summary.solver_flag == CV_ERR_FAILURE && options.method == OdeMethod::kBdf &&
      (options.max_order == 0 || options.max_order > 2)) {
    CvodeOptions low = options;
    low.max_order = 2;
    sol = IntegrateOnce(system, t0, y0, t_out, low);
  }
  return sol;
}

namespace {

// One integration: the output, the SUNDIALS objects (declared in creation order, destroyed in
// reverse), the counters that survive restarts and the stops. IntegrateOnce() runs it; each step
// below that returns a bool fills the summary and returns false when the run must end (Run()
// then returns Finish()).
class CvodeRun {
 public:
  CvodeRun(const OdeSystem& system, double t0, std::span<const double> y0,
           std::span<const double> t_out, const CvodeOptions& options)
      : system_(system), t0_(t0), y0_(y0), t_out_(t_out), options_(options), n_(system.size()) {
    sol_.n = n_;
  }

  OdeSolution Run();

 private:
  OdeSolution Finish() {
    sum_.wall_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start_).count();
    return std::move(sol_);
  }
  bool Invalid(std::string msg) {
    sum_.status = SimStatus::kInvalidInput;
    sum_.message = std::move(msg);
    return false;
  }
  bool Validate();
  // Fills the summary with a solver failure.
  void SetFailure(int flag, const std::string& what) {
    sum_.status = SimStatus::kSolverFailure;
    sum_.solver_flag = flag;
    sum_.message = what;
    if (!data_.cvode_message.empty()) sum_.message += ": " + data_.cvode_message;
    if (!data_.callback_note.empty())
      sum_.message += " (last callback problem: " + data_.callback_note + ")";
  }
  bool Fail(int flag, const std::string& what) {
    SetFailure(flag, what);
    return false;
  }
  bool Check(int flag, const char* call) {
    if (flag >= 0) return true;
    SetFailure(flag, std::string(call) + " failed with " + FlagName(flag));
    return false;
  }
  bool CreateSolver();
  bool ConfigureSolver();
  Counters Current() const;
  void Publish() {
    const Counters c = Current();
    sum_.steps = done_.steps + c.steps;
    sum_.rhs_calls = done_.rhs + c.rhs;
    sum_.jacobian_calls = done_.jac + c.jac;
  }
  bool Stopping(const Stop& s) const {
    return s.breakpoint || (options_.restart_at_outputs && s.first_output >= 0);
  }
  bool ArmTstop(double t_now);
  bool Restart(double t_now);
  bool Record(const Stop& s);
  bool CallHook(const StopEvent& ev, bool& restart_needed);
  bool AdvanceTo(const Stop& s);
  void Integrate();

  const std::chrono::steady_clock::time_point wall_start_ = std::chrono::steady_clock::now();
  const OdeSystem& system_;
  const double t0_;
  const std::span<const double> y0_, t_out_;
  const CvodeOptions& options_;
  const int n_;
  OdeSolution sol_;
  SimulationSummary& sum_ = sol_.summary;
  JacobianStructure js_;
  bool newton_ = false, banded_ = false, reduced_ = false;
  int n_roots_ = 0;
  RunData data_;
  ContextPtr ctx_;
  VectorPtr y_;
  double* yd_ = nullptr;
  MatrixPtr matrix_;
  LinearSolverPtr linear_solver_;
  NonlinearSolverPtr nonlinear_solver_;
  CvodePtr mem_;
  void* cv_ = nullptr;
  Counters done_;  // counters of the runs before the last restart (CVodeReInit zeroes CVODE's)
  std::vector<Stop> stops_;
  size_t next_tstop_ = 0;  // index of the next stop where the integrator must halt exactly
  std::vector<int> root_info_;
};

OdeSolution CvodeRun::Run() {
  if (!Validate()) return Finish();
  sol_.t.reserve(t_out_.size());
  sol_.y.reserve(t_out_.size() * static_cast<size_t>(n_));
  if (t_out_.empty()) return Finish();
  if (!CreateSolver() || !ConfigureSolver()) return Finish();
  stops_ = MergeStops(t0_, t_out_, options_.breakpoints);
  root_info_.resize(static_cast<size_t>(n_roots_));
  Integrate();
  return Finish();
}

bool CvodeRun::Validate() {
  const int n = n_;
  if (n < 1) return Invalid(FieldError("system.size()", n, "must be >= 1"));
  if (auto s = options_.Validate(n); !s.ok()) return Invalid(s.message());
  if (static_cast<int>(y0_.size()) != n)
    return Invalid(FieldError("y0.size()", y0_.size(),
                              "must equal the number of states " + std::to_string(n)));
  if (!std::isfinite(t0_)) return Invalid(FieldError("t0", t0_, "must be finite"));
  for (int i = 0; i < n; ++i)
    if (!std::isfinite(y0_[i]))
      return Invalid(FieldError("y0[" + std::to_string(i) + "]", y0_[i], "must be finite"));
  for (size_t k = 0; k < t_out_.size(); ++k) {
    if (!std::isfinite(t_out_[k]))
      return Invalid(FieldError("t_out[" + std::to_string(k) + "]", t_out_[k], "must be finite"));
    if (t_out_[k] < t0_)
      return Invalid(
          FieldError("t_out[" + std::to_string(k) + "]", t_out_[k], "must be >= t0 = " + Num(t0_)));
    if (k > 0 && !(t_out_[k] > t_out_[k - 1]))
      return Invalid(FieldError("t_out[" + std::to_string(k) + "]", t_out_[k],
                                "output times must be strictly increasing"));
  }
  js_ = system_.jacobian_structure();
  const JacobianStructure& js = js_;
  newton_ = options_.iteration == NonlinearIteration::kNewton;
  banded_ = newton_ && (options_.linear_solver == LinearSolverKind::kBanded ||
                        (options_.linear_solver == LinearSolverKind::kAuto && js.banded));
  reduced_ = newton_ && !banded_ &&
             (options_.linear_solver == LinearSolverKind::kReduced ||
              (options_.linear_solver == LinearSolverKind::kAuto && js.kinematic > 0));
  if (reduced_ && !(js.kinematic > 0 && 2 * js.kinematic <= n))
    return Invalid(FieldError("system kinematic rows", js.kinematic,
                              "must be in [1, n/2] for linear_solver = reduced"));
  if (banded_) {
    if (!js.banded) return Invalid("linear_solver = banded but the system declares no band");
    if (js.upper < 0 || js.upper >= n || js.lower < 0 || js.lower >= n)
      return Invalid("system bandwidths (upper " + std::to_string(js.upper) + ", lower " +
                     std::to_string(js.lower) + ") must be in [0, n-1]");
  }
  n_roots_ = system_.num_roots();
  if (n_roots_ < 0) return Invalid(FieldError("system.num_roots()", n_roots_, "must be >= 0"));
  return true;
}

// The context, the state vector and the CVODE memory with its right-hand side and tolerances.
bool CvodeRun::CreateSolver() {
  data_.system = &system_;
  data_.n = n_;
  SUNContext raw_ctx = nullptr;
  if (SUNContext_Create(nullptr, &raw_ctx) != 0 || raw_ctx == nullptr)
    return Fail(-1, "SUNContext_Create failed");
  ctx_.reset(raw_ctx);
  y_.reset(N_VNew_Serial(n_, ctx_.get()));
  if (!y_) return Fail(CV_MEM_FAIL, "N_VNew_Serial failed");
  yd_ = N_VGetArrayPointer(y_.get());
  std::copy(y0_.begin(), y0_.end(), yd_);
  mem_.reset(CVodeCreate(options_.method == OdeMethod::kBdf ? CV_BDF : CV_ADAMS, ctx_.get()));
  if (!mem_) return Fail(CV_MEM_FAIL, "CVodeCreate failed");
  cv_ = mem_.get();
  CVodeSetErrHandlerFn(cv_, ErrorHandler, &data_);
  if (!Check(CVodeInit(cv_, RhsCallback, t0_, y_.get()), "CVodeInit")) return false;
  if (!Check(CVodeSetUserData(cv_, &data_), "CVodeSetUserData")) return false;
  if (options_.atol_vector.empty())
    return Check(CVodeSStolerances(cv_, options_.rtol, options_.atol), "CVodeSStolerances");
  VectorPtr abstol(N_VNew_Serial(n_, ctx_.get()));
  if (!abstol) return Fail(CV_MEM_FAIL, "N_VNew_Serial failed");
  std::copy(options_.atol_vector.begin(), options_.atol_vector.end(),
            N_VGetArrayPointer(abstol.get()));
  return Check(CVodeSVtolerances(cv_, options_.rtol, abstol.get()), "CVodeSVtolerances");
}

// The (non)linear solvers, the step and order options and the root functions.
bool CvodeRun::ConfigureSolver() {
  void* cv = cv_;
  const CvodeOptions& options = options_;
  if (newton_) {
    matrix_.reset(banded_ ? SUNBandMatrix(n_, js_.upper, js_.lower, ctx_.get())
                          : SUNDenseMatrix(n_, n_, ctx_.get()));
    if (!matrix_) return Fail(CV_MEM_FAIL, "SUNMatrix creation failed");
    linear_solver_.reset(banded_    ? SUNLinSol_Band(y_.get(), matrix_.get(), ctx_.get())
                         : reduced_ ? NewReducedSolver(n_, js_.kinematic, cv, ctx_.get())
                                    : SUNLinSol_Dense(y_.get(), matrix_.get(), ctx_.get()));
    if (!linear_solver_) return Fail(CV_MEM_FAIL, "SUNLinearSolver creation failed");
    if (!Check(CVodeSetLinearSolver(cv, linear_solver_.get(), matrix_.get()),
               "CVodeSetLinearSolver"))
      return false;
    if (js_.analytic && options.use_analytic_jacobian)
      if (!Check(CVodeSetJacFn(cv, JacobianCallback), "CVodeSetJacFn")) return false;
  } else {
    nonlinear_solver_.reset(SUNNonlinSol_FixedPoint(y_.get(), 0, ctx_.get()));
    if (!nonlinear_solver_) return Fail(CV_MEM_FAIL, "SUNNonlinSol_FixedPoint failed");
    if (!Check(CVodeSetNonlinearSolver(cv, nonlinear_solver_.get()), "CVodeSetNonlinearSolver"))
      return false;
  }
  if (options.max_step > 0 && !Check(CVodeSetMaxStep(cv, options.max_step), "CVodeSetMaxStep"))
    return false;
  if (options.initial_step > 0 &&
      !Check(CVodeSetInitStep(cv, options.initial_step), "CVodeSetInitStep"))
    return false;
  if (options.max_order > 0 && !Check(CVodeSetMaxOrd(cv, options.max_order), "CVodeSetMaxOrd"))
    return false;
  if (options.stability_limit_detection && options.method == OdeMethod::kBdf &&
      !Check(CVodeSetStabLimDet(cv, SUNTRUE), "CVodeSetStabLimDet"))
    return false;
  if (n_roots_ > 0) {
    if (!Check(CVodeRootInit(cv, n_roots_, RootCallback), "CVodeRootInit")) return false;
    CVodeSetNoInactiveRootWarn(cv);
  }
  return true;
}

// CVODE's counters since the last (re)start.
Counters CvodeRun::Current() const {
  Counters c;
  long v = 0;
  if (CVodeGetNumSteps(cv_, &v) == CV_SUCCESS) c.steps = v;
  if (CVodeGetNumRhsEvals(cv_, &v) == CV_SUCCESS) c.rhs = v;
  if (newton_) {
    if (CVodeGetNumLinRhsEvals(cv_, &v) == CV_SUCCESS) c.rhs += v;
    if (CVodeGetNumJacEvals(cv_, &v) == CV_SUCCESS) c.jac = v;
  }
  return c;
}

bool CvodeRun::ArmTstop(double t_now) {
  while (next_tstop_ < stops_.size() &&
         !(stops_[next_tstop_].t > t_now && Stopping(stops_[next_tstop_])))
    ++next_tstop_;
  if (next_tstop_ < stops_.size())
    return Check(CVodeSetStopTime(cv_, stops_[next_tstop_].t), "CVodeSetStopTime");
  // SUNDIALS 6.4 cannot clear a stop time, and one reached by a CV_SUCCESS return (not
  // CV_TSTOP_RETURN) stays armed: move it beyond the last output, where it never acts.
  const double t_end = stops_.back().t;
  return Check(CVodeSetStopTime(cv_, t_end + std::max(1.0, t_end - t0_)), "CVodeSetStopTime");
}

bool CvodeRun::Restart(double t_now) {
  const Counters c = Current();
  done_.steps += c.steps;
  done_.rhs += c.rhs;
  done_.jac += c.jac;
  if (!Check(CVodeReInit(cv_, t_now, y_.get()), "CVodeReInit")) return false;
  return ArmTstop(t_now);
}

// Appends the outputs of stop s; false (with the summary filled) if the state is non-finite.
bool CvodeRun::Record(const Stop& s) {
  for (int k = s.first_output; k >= 0 && k <= s.last_output; ++k) {
    sol_.t.push_back(t_out_[k]);
    sol_.y.insert(sol_.y.end(), yd_, yd_ + n_);
  }
  for (int i = 0; i < n_ && s.first_output >= 0; ++i) {
    if (!std::isfinite(yd_[i])) {
      sum_.status = SimStatus::kNonFinite;
      sum_.message = "state " + std::to_string(i) + " non-finite at t = " + Num(s.t);
      return false;
    }
  }
  return true;
}

// Calls the hook; returns false (with the summary filled) if it asks to fail.
bool CvodeRun::CallHook(const StopEvent& ev, bool& restart_needed) {
  if (!options_.on_stop) return true;
  StopAction a;
  try {
    a = options_.on_stop(ev, std::span<double>(yd_, static_cast<size_t>(n_)));
  } catch (const std::exception& e) {
    data_.Note(std::string("exception in discrete-update hook: ") + e.what());
    a = StopAction::kFail;
  }
  if (a == StopAction::kFail) {
    SetFailure(CV_ILL_INPUT, "discrete-update hook stopped the integration at t = " + Num(ev.t));
    return false;
  }
  if (a == StopAction::kRestart) restart_needed = true;
  return true;
}

// Integrates up to stop s (s.t > t0), through the roots met on the way.
bool CvodeRun::AdvanceTo(const Stop& s) {
  for (;;) {
    Publish();
    const long remaining = options_.max_steps - sum_.steps;  // CVODE's mxstep counts per CVode()
    if (remaining <= 0) {
      const int flag = CV_TOO_MUCH_WORK;
      sum_.solver_flag = flag;
      double tc = t0_;
      CVodeGetCurrentTime(cv_, &tc);
      return Fail(flag, "CVODE CV_TOO_MUCH_WORK at t = " + Num(tc) + ": step budget max_steps = " +
                            std::to_string(options_.max_steps) + " used up before t = " + Num(s.t));
    }
    CVodeSetMaxNumSteps(cv_, remaining);
    double tret = s.t;
    const int flag = CVode(cv_, s.t, y_.get(), &tret, CV_NORMAL);
    sum_.solver_flag = flag;
    if (flag < 0) {
      Publish();
      double tc = tret;
      CVodeGetCurrentTime(cv_, &tc);
      std::string what = "CVODE " + FlagName(flag) + " at t = " + Num(tc);
      if (flag == CV_TOO_MUCH_WORK)
        what += " (step budget max_steps = " + std::to_string(options_.max_steps) + ")";
      return Fail(flag, what);
    }
    if (flag != CV_ROOT_RETURN) return true;
    // A root function crossed zero at tret < s.t: discrete update, maybe restart, then go on.
    CVodeGetRootInfo(cv_, root_info_.data());
    StopEvent ev;
    ev.t = tret;
    ev.roots = root_info_;
    bool need_restart = false;
    if (!CallHook(ev, need_restart)) return false;
    if (need_restart && !Restart(tret)) return false;
    if (s.t - tret <= 64 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(s.t)))
      return true;
  }
}

// Goes through the stops: integrates to each, records its outputs, calls the hook, restarts.
void CvodeRun::Integrate() {
  if (!ArmTstop(t0_)) return;
  for (const Stop& s : stops_) {
    if (s.t > t0_ && !AdvanceTo(s)) return;
    if (!Record(s)) {
      Publish();
      return;
    }
    StopEvent ev;
    ev.t = s.t;
    ev.output_index = s.last_output;
    ev.breakpoint = s.breakpoint;
    bool need_restart = s.t > t0_ && Stopping(s);
    if (!CallHook(ev, need_restart)) return;
    if (need_restart && &s != &stops_.back() && !Restart(s.t)) return;
  }
  Publish();
}

OdeSolution IntegrateOnce(const OdeSystem& system, double t0, std::span<const double> y0,
                          std::span<const double> t_out, const CvodeOptions& options) {
  return CvodeRun(system, t0, y0, t_out, options).Run();
}

}  // namespace

}  // namespace pz::model
