// The CVODE path: the wrapper on reference problems with known answers (decay, oscillator, a stiff
// linear system, a banded heat equation, breakpoints, roots), its failure modes as statuses, its
// use from many threads; then the bimorph ODE on it (analytic Jacobian against difference
// quotients, the extension seam, sampled input against the exact first-order-hold solution).
#include <cvode/cvode.h>
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>
#include <thread>
#include <unsupported/Eigen/MatrixFunctions>
#include <vector>

#include "model/bimorph.h"
#include "model/bimorph_cvode.h"
#include "model/bimorph_ode.h"
#include "model/cvode.h"

namespace pz::model {
namespace {

std::vector<double> Linspace(double a, double b, int n) {
  std::vector<double> t(n);
  for (int i = 0; i < n; ++i) t[i] = a + (b - a) * i / (n - 1);
  return t;
}

// ---- reference systems -------------------------------------------------------------------------

// ẏ = −λ y: y = e^{−λt}.
class Decay final : public OdeSystem {
 public:
  explicit Decay(double lambda) : lambda_(lambda) {}
  int size() const override { return 1; }
  int Rhs(double, const double* y, double* ydot) const override {
    ydot[0] = -lambda_ * y[0];
    return 0;
  }
  JacobianStructure jacobian_structure() const override { return {.analytic = true}; }
  int Jacobian(double, const double*, const double*, JacobianView& j) const override {
    j.Set(0, 0, -lambda_);
    return 0;
  }

 private:
  double lambda_;
};

// ẍ = −ω² x as [x, v]: x = cos ωt, v = −ω sin ωt. Optionally declares ẋ = v as a kinematic row.
class Oscillator final : public OdeSystem {
 public:
  explicit Oscillator(double omega, bool kinematic = false)
      : omega_(omega), kinematic_(kinematic) {}
  int size() const override { return 2; }
  int Rhs(double, const double* y, double* ydot) const override {
    ydot[0] = y[1];
    ydot[1] = -omega_ * omega_ * y[0];
    return 0;
  }
  JacobianStructure jacobian_structure() const override {
    return {.analytic = true, .kinematic = kinematic_ ? 1 : 0};
  }
  int Jacobian(double, const double*, const double*, JacobianView& j) const override {
    j.Set(0, 1, 1.0);
    j.Set(1, 0, -omega_ * omega_);
    return 0;
  }

 private:
  double omega_;
  bool kinematic_;
};

// ẏ = A y, A = P diag(−1, −1e3, −1e6) P⁻¹: stiffness ratio 1e6, y = P e^{Dt} P⁻¹ y0.
class StiffLinear final : public OdeSystem {
 public:
  StiffLinear() {
    p_ << 1, 1, 0, 0, 1, 1, 1, 0, 1;
    d_ << -1.0, -1e3, -1e6;
    a_ = p_ * d_.asDiagonal() * p_.inverse();
  }
  int size() const override { return 3; }
  int Rhs(double, const double* y, double* ydot) const override {
    Eigen::Map<Eigen::Vector3d> out(ydot);
    out = a_ * Eigen::Map<const Eigen::Vector3d>(y);
    return 0;
  }
  JacobianStructure jacobian_structure() const override { return {.analytic = true}; }
  int Jacobian(double, const double*, const double*, JacobianView& j) const override {
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 3; ++c) j.Set(r, c, a_(r, c));
    return 0;
  }
  Eigen::Vector3d Exact(double t, const Eigen::Vector3d& y0) const {
    return p_ * (d_.array() * t).exp().matrix().asDiagonal() * p_.inverse() * y0;
  }

 private:
  Eigen::Matrix3d p_, a_;
  Eigen::Vector3d d_;
};

// Heat equation on n interior nodes, ẏ_i = κ (y_{i−1} − 2 y_i + y_{i+1}) + sin(t) (tridiagonal).
class Heat final : public OdeSystem {
 public:
  explicit Heat(int n, double kappa) : n_(n), kappa_(kappa) {}
  int size() const override { return n_; }
  int Rhs(double t, const double* y, double* ydot) const override {
    for (int i = 0; i < n_; ++i) {
      const double l = i > 0 ? y[i - 1] : 0.0, r = i + 1 < n_ ? y[i + 1] : 0.0;
      ydot[i] = kappa_ * (l - 2 * y[i] + r) + std::sin(t);
    }
    return 0;
  }
  JacobianStructure jacobian_structure() const override {
    return {.analytic = true, .banded = true, .upper = 1, .lower = 1};
  }
  int Jacobian(double, const double*, const double*, JacobianView& j) const override {
    for (int i = 0; i < n_; ++i) {
      j.Set(i, i, -2 * kappa_);
      if (i > 0) j.Set(i, i - 1, kappa_);
      if (i + 1 < n_) j.Set(i, i + 1, kappa_);
    }
    return 0;
  }

 private:
  int n_;
  double kappa_;
};

// ẏ = 1 except that Rhs misbehaves after t_bad in the chosen way.
class Faulty final : public OdeSystem {
 public:
  enum Mode { kFatal, kRecoverable, kThrow, kNaN };
  Faulty(Mode mode, double t_bad) : mode_(mode), t_bad_(t_bad) {}
  int size() const override { return 1; }
  int Rhs(double t, const double*, double* ydot) const override {
    ydot[0] = 1.0;
    if (t <= t_bad_) return 0;
    switch (mode_) {
      case kFatal:
        return -1;
      case kRecoverable:
        return 1;
      case kThrow:
        throw std::runtime_error("model blew up");
      case kNaN:
        ydot[0] = std::nan("");
        return 0;
    }
    return 0;
  }

 private:
  Mode mode_;
  double t_bad_;
};

// ---- reference problems ------------------------------------------------------------------------

TEST(CvodeReferenceProblems, ExponentialDecayBdfAndAdams) {
  const Decay sys(2.0);
  const std::vector<double> t = Linspace(0, 5, 11);
  const double y0[] = {1.0};
  for (OdeMethod m : {OdeMethod::kBdf, OdeMethod::kAdams}) {
    CvodeOptions o;
    o.method = m;
    o.rtol = 1e-11;
    o.atol = 1e-14;
    const OdeSolution s = IntegrateCvode(sys, 0.0, y0, t, o);
    ASSERT_TRUE(s.summary.ok()) << s.summary.BriefReport();
    ASSERT_EQ(s.t.size(), t.size());
    EXPECT_EQ(s.at(0, 0), 1.0);  // the output at t0 is y0
    for (size_t k = 0; k < t.size(); ++k)
      EXPECT_NEAR(s.at(k, 0), std::exp(-2.0 * t[k]), 3e-9 * std::exp(-2.0 * t[k]) + 1e-13)
          << OdeMethodName(m) << " t=" << t[k];
    EXPECT_GT(s.summary.steps, 0);
    EXPECT_GT(s.summary.rhs_calls, s.summary.steps);
  }
}

TEST(CvodeReferenceProblems, HarmonicOscillatorTenPeriods) {
  const double w = 2 * std::numbers::pi;
  const Oscillator sys(w);
  const std::vector<double> t = Linspace(0, 10, 41);
  const double y0[] = {1.0, 0.0};
  struct Variant {
    OdeMethod method;
    NonlinearIteration iteration;
  };
  for (Variant v : {Variant{OdeMethod::kAdams, NonlinearIteration::kFixedPoint},
                    Variant{OdeMethod::kAdams, NonlinearIteration::kNewton},
                    Variant{OdeMethod::kBdf, NonlinearIteration::kNewton}}) {
    CvodeOptions o;
    o.method = v.method;
    o.iteration = v.iteration;
    o.rtol = 1e-11;
    o.atol = 1e-13;
    const OdeSolution s = IntegrateCvode(sys, 0.0, y0, t, o);
    ASSERT_TRUE(s.summary.ok()) << s.summary.BriefReport();
    for (size_t k = 0; k < t.size(); ++k) {
      EXPECT_NEAR(s.at(k, 0), std::cos(w * t[k]), 2e-8) << OdeMethodName(v.method) << " t=" << t[k];
      EXPECT_NEAR(s.at(k, 1), -w * std::sin(w * t[k]), 2e-7)
          << OdeMethodName(v.method) << " t=" << t[k];
    }
    if (v.iteration == NonlinearIteration::kFixedPoint) {
      EXPECT_EQ(s.summary.jacobian_calls, 0);
    }
  }
}

TEST(CvodeReferenceProblems, StiffLinearSystemBdfTakesFewSteps) {
  const StiffLinear sys;
  const Eigen::Vector3d y0(1.0, 2.0, -1.0);
  const std::vector<double> t = {0.0, 1e-6, 1e-3, 0.1, 1.0, 5.0};
  CvodeOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-14;
  const OdeSolution s = IntegrateCvode(sys, 0.0, {y0.data(), 3}, t, o);
  ASSERT_TRUE(s.summary.ok()) << s.summary.BriefReport();
  for (size_t k = 0; k < t.size(); ++k) {
    const Eigen::Vector3d exact = sys.Exact(t[k], y0);
    for (int i = 0; i < 3; ++i)
      EXPECT_NEAR(s.at(k, i), exact[i], 1e-8 * (1 + std::abs(exact[i]))) << "t=" << t[k];
  }
  // An explicit method would need ~5e6 steps (|λ| h < 2 over 5 s); BDF follows the slow mode.
  EXPECT_LT(s.summary.steps, 3000) << s.summary.BriefReport();
  EXPECT_GT(s.summary.jacobian_calls, 0);
}

TEST(CvodeReferenceProblems, DenseAndBandedJacobianAgree) {
  const Heat sys(30, 50.0);
  const std::vector<double> y0(30, 0.0);
  const std::vector<double> t = Linspace(0, 4, 9);
  std::vector<OdeSolution> runs;
  for (auto [kind, analytic] :
       {std::pair{LinearSolverKind::kDense, true}, std::pair{LinearSolverKind::kBanded, true},
        std::pair{LinearSolverKind::kDense, false}, std::pair{LinearSolverKind::kBanded, false}}) {
    CvodeOptions o;
    o.linear_solver = kind;
    o.use_analytic_jacobian = analytic;
    o.rtol = 1e-10;
    o.atol = 1e-13;
    runs.push_back(IntegrateCvode(sys, 0.0, y0, t, o));
    ASSERT_TRUE(runs.back().summary.ok()) << runs.back().summary.BriefReport();
  }
  for (size_t r = 1; r < runs.size(); ++r)
    for (size_t i = 0; i < runs[0].y.size(); ++i)
      EXPECT_NEAR(runs[r].y[i], runs[0].y[i], 1e-8) << "run " << r << " entry " << i;
}

TEST(CvodeReferenceProblems, ReducedSolverEliminatesKinematicRowsExactly) {
  // The reduced LU solves the same Newton systems as the dense one: same steps, same answer.
  const Oscillator sys(2 * std::numbers::pi, /*kinematic=*/true);
  const double y0[] = {1.0, 0.0};
  const std::vector<double> t = Linspace(0, 5, 21);
  CvodeOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-13;
  o.linear_solver = LinearSolverKind::kDense;
  const OdeSolution dense = IntegrateCvode(sys, 0.0, y0, t, o);
  o.linear_solver =
      LinearSolverKind::kAuto;  // picks the reduced solver from the declared structure
  const OdeSolution reduced = IntegrateCvode(sys, 0.0, y0, t, o);
  ASSERT_TRUE(dense.summary.ok() && reduced.summary.ok()) << reduced.summary.BriefReport();
  EXPECT_EQ(reduced.summary.steps, dense.summary.steps);
  for (size_t i = 0; i < dense.y.size(); ++i) EXPECT_NEAR(reduced.y[i], dense.y[i], 1e-12) << i;
  for (size_t k = 0; k < t.size(); ++k)
    EXPECT_NEAR(reduced.at(k, 0), std::cos(2 * std::numbers::pi * t[k]), 1e-7);
  // A system that declares no kinematic rows cannot use it.
  o.linear_solver = LinearSolverKind::kReduced;
  const OdeSolution bad = IntegrateCvode(Oscillator(1.0), 0.0, y0, t, o);
  EXPECT_EQ(bad.summary.status, SimStatus::kInvalidInput);
  EXPECT_NE(bad.summary.message.find("kinematic"), std::string::npos) << bad.summary.message;
}

TEST(CvodeJacobianView, BandedViewKeepsOnlyTheBand) {
  // SUNDIALS band storage for n = 4, upper 1, lower 1, stored upper 2: ldim = 4.
  std::vector<double> data(16, 0.0);
  JacobianView v = JacobianView::Banded(data.data(), 4, 1, 1, 2, 4);
  EXPECT_TRUE(v.InBand(1, 2));
  EXPECT_FALSE(v.InBand(0, 2));
  v.Set(0, 2, 5.0);  // outside the band: dropped
  v.Set(2, 1, 3.0);
  v.Add(2, 1, 1.0);
  EXPECT_EQ(v.Get(2, 1), 4.0);
  EXPECT_EQ(v.Get(0, 2), 0.0);
  EXPECT_EQ(data[1 * 4 + 2 + 2 - 1], 4.0);  // column 1 at offset storage_upper + i − j
  double dense[9] = {};
  JacobianView d(dense, 3);
  d.Set(2, 0, 7.0);
  EXPECT_EQ(dense[2], 7.0);  // column-major
}

TEST(CvodeStops, BreakpointsAndHookFollowAPiecewiseSlope) {
  // ẏ = s, where the hook sets s = ±1 at the breakpoints: y is an exact triangle wave.
  struct Slope final : OdeSystem {
    double s = 1.0;
    int size() const override { return 1; }
    int Rhs(double, const double*, double* ydot) const override {
      ydot[0] = s;
      return 0;
    }
  } sys;
  CvodeOptions o;
  o.breakpoints = {1.0, 2.0, 3.0};
  int hook_calls = 0;
  o.on_stop = [&](const StopEvent& ev, std::span<double>) {
    ++hook_calls;
    if (!ev.breakpoint) return StopAction::kContinue;
    sys.s = -sys.s;
    return StopAction::kRestart;
  };
  const std::vector<double> t = {0.0, 0.5, 1.5, 2.0, 2.5, 3.5, 4.0};
  const double y0[] = {0.0};
  const OdeSolution s = IntegrateCvode(sys, 0.0, y0, t, o);
  ASSERT_TRUE(s.summary.ok()) << s.summary.BriefReport();
  const double expected[] = {0.0, 0.5, 0.5, 0.0, 0.5, 0.5, 0.0};
  for (size_t k = 0; k < t.size(); ++k) EXPECT_NEAR(s.at(k, 0), expected[k], 1e-12) << "t=" << t[k];
  EXPECT_EQ(hook_calls, 9);  // 7 outputs + breakpoints 1 and 3 (2 coincides with an output)
}

TEST(CvodeStops, RootResetMakesASawtooth) {
  // ẏ = 1 with a root at y = 0.37; the hook resets y to 0.
  struct Ramp final : OdeSystem {
    int size() const override { return 1; }
    int Rhs(double, const double*, double* ydot) const override {
      ydot[0] = 1.0;
      return 0;
    }
    int num_roots() const override { return 1; }
    int Roots(double, const double* y, double* g) const override {
      g[0] = y[0] - 0.37;
      return 0;
    }
  } sys;
  CvodeOptions o;
  o.rtol = 1e-12;
  o.atol = 1e-14;
  std::vector<double> root_times;
  o.on_stop = [&](const StopEvent& ev, std::span<double> y) {
    if (ev.roots.empty()) return StopAction::kContinue;
    EXPECT_EQ(ev.roots[0], 1);  // rising crossing
    root_times.push_back(ev.t);
    y[0] = 0.0;
    return StopAction::kRestart;
  };
  const std::vector<double> t = Linspace(0, 1, 11);
  const double y0[] = {0.0};
  const OdeSolution s = IntegrateCvode(sys, 0.0, y0, t, o);
  ASSERT_TRUE(s.summary.ok()) << s.summary.BriefReport();
  ASSERT_EQ(root_times.size(), 2u);
  for (size_t i = 0; i < 2; ++i) EXPECT_NEAR(root_times[i], 0.37 * (i + 1), 1e-10);
  for (size_t k = 0; k < t.size(); ++k)
    EXPECT_NEAR(s.at(k, 0), std::fmod(t[k], 0.37), 1e-9) << "t=" << t[k];
}

// ---- failures are statuses, never aborts -------------------------------------------------------

TEST(CvodeFailures, FatalRhsReturnIsASolverFailure) {
  const Faulty sys(Faulty::kFatal, 0.5);
  const double y0[] = {0.0};
  const std::vector<double> t = {0.0, 0.25, 1.0};
  const OdeSolution s = IntegrateCvode(sys, 0.0, y0, t, CvodeOptions{});
  EXPECT_EQ(s.summary.status, SimStatus::kSolverFailure);
  EXPECT_EQ(s.summary.solver_flag, CV_RHSFUNC_FAIL);
  EXPECT_NE(s.summary.message.find("CV_RHSFUNC_FAIL"), std::string::npos) << s.summary.message;
  EXPECT_NE(s.summary.message.find("right-hand side returned -1"), std::string::npos)
      << s.summary.message;
  EXPECT_EQ(s.t.size(), 2u);  // the outputs reached before the failure
}

TEST(CvodeFailures, RecoverableRhsErrorsEndInASolverFailure) {
  const double y0[] = {0.0};
  const std::vector<double> t = {0.0, 1.0};
  // Failing from the first call: CVODE cannot even start.
  OdeSolution s = IntegrateCvode(Faulty(Faulty::kRecoverable, -1.0), 0.0, y0, t, CvodeOptions{});
  EXPECT_EQ(s.summary.status, SimStatus::kSolverFailure);
  EXPECT_EQ(s.summary.solver_flag, CV_FIRST_RHSFUNC_ERR) << s.summary.BriefReport();
  EXPECT_NE(s.summary.message.find("right-hand side returned 1"), std::string::npos)
      << s.summary.message;
  // Failing beyond t = 0.5: the steps shrink towards 0.5 until the budget runs out.
  CvodeOptions o;
  o.max_steps = 2000;
  s = IntegrateCvode(Faulty(Faulty::kRecoverable, 0.5), 0.0, y0, t, o);
  EXPECT_EQ(s.summary.status, SimStatus::kSolverFailure);
  EXPECT_NE(s.summary.message.find("right-hand side returned 1"), std::string::npos)
      << s.summary.message;
}

TEST(CvodeFailures, ExceptionInRhsIsCaughtAtTheBoundary) {
  const Faulty sys(Faulty::kThrow, 0.5);
  const double y0[] = {0.0};
  const std::vector<double> t = {0.0, 1.0};
  const OdeSolution s = IntegrateCvode(sys, 0.0, y0, t, CvodeOptions{});
  EXPECT_EQ(s.summary.status, SimStatus::kSolverFailure);
  EXPECT_NE(s.summary.message.find("model blew up"), std::string::npos) << s.summary.message;
}

TEST(CvodeFailures, NonFiniteRhsIsASolverFailure) {
  const Faulty sys(Faulty::kNaN, 0.5);
  const double y0[] = {0.0};
  const std::vector<double> t = {0.0, 1.0};
  CvodeOptions o;
  o.max_steps =
      2000;  // a non-finite f is recoverable: the steps shrink towards 0.5 until the budget ends
  const OdeSolution s = IntegrateCvode(sys, 0.0, y0, t, o);
  EXPECT_EQ(s.summary.status, SimStatus::kSolverFailure);
  EXPECT_NE(s.summary.message.find("non-finite"), std::string::npos) << s.summary.message;
}

TEST(CvodeFailures, TooSmallStepBudgetReportsFlagAndMessage) {
  const Oscillator sys(2 * std::numbers::pi);
  const double y0[] = {1.0, 0.0};
  const std::vector<double> t = Linspace(0, 10, 11);
  CvodeOptions o;
  o.max_steps = 20;
  const OdeSolution s = IntegrateCvode(sys, 0.0, y0, t, o);
  EXPECT_EQ(s.summary.status, SimStatus::kSolverFailure);
  EXPECT_EQ(s.summary.solver_flag, CV_TOO_MUCH_WORK);
  EXPECT_NE(s.summary.message.find("CV_TOO_MUCH_WORK"), std::string::npos) << s.summary.message;
  EXPECT_NE(s.summary.message.find("max_steps = 20"), std::string::npos) << s.summary.message;
  EXPECT_LE(s.summary.steps, 20);
  EXPECT_LT(s.t.size(), t.size());
}

TEST(CvodeFailures, InvalidInputNamesTheField) {
  const Decay sys(1.0);
  const double y0[] = {1.0};
  const std::vector<double> bad_times = {0.0, 2.0, 1.0};
  OdeSolution s = IntegrateCvode(sys, 0.0, y0, bad_times, CvodeOptions{});
  EXPECT_EQ(s.summary.status, SimStatus::kInvalidInput);
  EXPECT_NE(s.summary.message.find("t_out[2]"), std::string::npos) << s.summary.message;
  CvodeOptions o;
  o.rtol = -1;
  const std::vector<double> t = {0.0, 1.0};
  s = IntegrateCvode(sys, 0.0, y0, t, o);
  EXPECT_EQ(s.summary.status, SimStatus::kInvalidInput);
  EXPECT_NE(s.summary.message.find("rtol = -1"), std::string::npos) << s.summary.message;
  o = CvodeOptions{};
  o.linear_solver = LinearSolverKind::kBanded;  // Decay declares no band
  s = IntegrateCvode(sys, 0.0, y0, t, o);
  EXPECT_EQ(s.summary.status, SimStatus::kInvalidInput);
  const double y0_nan[] = {std::nan("")};
  s = IntegrateCvode(sys, 0.0, y0_nan, t, CvodeOptions{});
  EXPECT_EQ(s.summary.status, SimStatus::kInvalidInput);
  EXPECT_NE(s.summary.message.find("y0[0]"), std::string::npos) << s.summary.message;
}

TEST(CvodeThreads, ConcurrentIntegrationsMatchTheSerialOne) {
  const Oscillator sys(3.0);  // one shared, const system
  const double y0[] = {1.0, 0.0};
  const std::vector<double> t = Linspace(0, 20, 201);
  CvodeOptions o;
  o.rtol = 1e-10;
  const OdeSolution serial = IntegrateCvode(sys, 0.0, y0, t, o);
  ASSERT_TRUE(serial.summary.ok());
  std::vector<OdeSolution> out(8);
  std::vector<std::thread> threads;
  for (size_t i = 0; i < out.size(); ++i)
    threads.emplace_back([&, i] { out[i] = IntegrateCvode(sys, 0.0, y0, t, o); });
  for (auto& th : threads) th.join();
  for (const OdeSolution& s : out) {
    ASSERT_TRUE(s.summary.ok());
    EXPECT_EQ(s.y, serial.y);  // bit for bit
    EXPECT_EQ(s.summary.steps, serial.summary.steps);
  }
}

// ---- the bimorph ODE on the CVODE path ---------------------------------------------------------

BimorphParams Case1Params() {
  BimorphParams p;
  p.mu = 98.65;
  p.delta = 0.312;
  p.a1 = p.a2 = 0.0;
  p.b1 = 1.37;
  p.b2 = -1.5;
  return p;
}

// Central differences of f, column by column. The step is 1e-5: f is linear in q, q̇ and the
// extension states used here, so only rounding limits the quotient, and it shrinks with a larger
// step; a non-zero w_tip (the cubic spring's nonlinearity) gets a relative step of 1e-3.
// rounding(r, c) bounds the rounding error of each quotient: a few ulps of f_r over the step.
Eigen::MatrixXd FiniteDifferenceJacobian(const BimorphOde& sys, double t,
                                         const std::vector<double>& y, Eigen::MatrixXd& rounding) {
  const int n = sys.size();
  Eigen::MatrixXd j(n, n);
  rounding.resize(n, n);
  std::vector<double> yp = y, ym = y, fp(n), fm(n);
  for (int c = 0; c < n; ++c) {
    const double h = (c == sys.tip_index() && y[c] != 0) ? 1e-3 * std::abs(y[c])
                                                         : 1e-5 * std::max(1.0, std::abs(y[c]));
    yp[c] = y[c] + h;
    ym[c] = y[c] - h;
    sys.Rhs(t, yp.data(), fp.data());
    sys.Rhs(t, ym.data(), fm.data());
    for (int r = 0; r < n; ++r) {
      j(r, c) = (fp[r] - fm[r]) / (2 * h);
      rounding(r, c) = 16 * std::numeric_limits<double>::epsilon() *
                       (std::abs(fp[r]) + std::abs(fm[r])) / (2 * h);
    }
    yp[c] = ym[c] = y[c];
  }
  return j;
}

Eigen::MatrixXd AnalyticJacobian(const OdeSystem& sys, double t, const std::vector<double>& y) {
  const int n = sys.size();
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(n, n);
  std::vector<double> f(n);
  sys.Rhs(t, y.data(), f.data());
  JacobianView v(j.data(), n);
  EXPECT_EQ(sys.Jacobian(t, y.data(), f.data(), v), 0);
  return j;
}

// A point away from the kinks of |u̇| and |z|. The beam part of f is linear, so its Jacobian does
// not depend on q, q̇: they are left zero but for a tiny w_tip (for the cubic spring), so that the
// difference quotients are not swamped by rounding in the stiff terms M⁻¹K q.
std::vector<double> SomeState(const BimorphOde& ode) {
  std::vector<double> y = ode.InitialState();
  y[ode.tip_index()] = 1e-6;
  y[ode.z_index()] = 0.05;
  for (int i = ode.z_index() + 1; i < ode.size(); ++i) y[i] = 0.3 + 0.1 * i;
  return y;
}

void ExpectJacobianMatchesDifferences(const BimorphOde& ode, double t) {
  const std::vector<double> y = SomeState(ode);
  Eigen::MatrixXd rounding;
  const Eigen::MatrixXd a = AnalyticJacobian(ode, t, y),
                        fd = FiniteDifferenceJacobian(ode, t, y, rounding);
  for (int r = 0; r < a.rows(); ++r)
    for (int c = 0; c < a.cols(); ++c)
      EXPECT_NEAR(a(r, c), fd(r, c), 1e-6 * (1.0 + std::abs(a(r, c))) + rounding(r, c))
          << "row " << r << " col " << c;
}

TEST(BimorphOde, LayoutOfTheStateVector) {
  const BimorphPlant plant;
  const DriveSignal drive = Sinusoid{};
  const BimorphOde ode(plant, Case1Params(), drive);
  EXPECT_EQ(ode.num_dofs(), 12);
  EXPECT_EQ(ode.size(), 25);  // 2·2n + 1
  EXPECT_EQ(ode.z_index(), 24);
  EXPECT_EQ(ode.tip_index(), plant.geometry().tip_dof());
}

// Difference quotients cannot resolve the μ entries next to δ M⁻¹K (up to ~1e15) in double
// precision, so they check the Jacobian with δ = 0, and the δ blocks are checked against M⁻¹
// directly.
TEST(BimorphOde, AnalyticJacobianMatchesDifferences) {
  const BimorphPlant plant;
  const DriveSignal drive = Sinusoid{};
  BimorphParams p = Case1Params();
  p.delta = 0.0;
  const BimorphOde ode(plant, p, drive);
  ExpectJacobianMatchesDifferences(ode, 0.3);  // u̇ > 0
  ExpectJacobianMatchesDifferences(ode, 2.7);  // u̇ < 0
}

TEST(BimorphOde, BeamBlocksOfTheJacobianAreTheAssembledMatrices) {
  const BimorphPlant plant;
  const DriveSignal drive = Sinusoid{};
  const BimorphParams p = Case1Params();
  const BimorphOde ode(plant, p, drive);
  const int nd = ode.num_dofs();
  const Eigen::MatrixXd a = AnalyticJacobian(ode, 0.3, SomeState(ode));
  const FeModel& fe = plant.fe();
  const Eigen::MatrixXd minv = fe.M.inverse();
  const Eigen::MatrixXd minv_k = minv * fe.K;
  const Eigen::MatrixXd minv_c = minv * (p.mu * fe.M + p.delta * fe.K);
  const double scale = minv_k.cwiseAbs().maxCoeff();
  EXPECT_LT((a.block(0, 0, nd, nd)).norm(), 1e-300);
  EXPECT_LT((a.block(0, nd, nd, nd) - Eigen::MatrixXd::Identity(nd, nd)).norm(), 1e-15);
  EXPECT_LT((a.block(nd, 0, nd, nd) + minv_k).cwiseAbs().maxCoeff(), 1e-10 * scale);
  EXPECT_LT((a.block(nd, nd, nd, nd) + minv_c).cwiseAbs().maxCoeff(), 1e-10 * scale * p.delta);
  EXPECT_LT((a.block(nd, 2 * nd, nd, 1) + minv * fe.e_tip).cwiseAbs().maxCoeff(),
            1e-10 * (minv * fe.e_tip).cwiseAbs().maxCoeff());
}

// Test extensions: an amplifier stage (ẋ = (u − x)/τ, drive (x, (u − x)/τ)) and a cubic tip spring
// (force −k₃ w_tip³), plus a passive state ẋ = −x / τ coupled to nothing.
class Amplifier final : public BimorphExtension {
 public:
  explicit Amplifier(double tau) : tau_(tau) {}
  std::string name() const override { return "amplifier"; }
  int num_states() const override { return 1; }
  bool shapes_drive() const override { return true; }
  int ShapeDrive(const BimorphPoint& p, double& u, double& u_dot) const override {
    u = p.x[0];
    u_dot = (p.u - p.x[0]) / tau_;
    return 0;
  }
  void ShapeDriveJacobian(const BimorphPoint& p, std::span<double> du,
                          std::span<double> dud) const override {
    const int ix = static_cast<int>(p.x.data() - p.y.data());
    std::fill(du.begin(), du.end(), 0.0);
    std::fill(dud.begin(), dud.end(), 0.0);
    du[ix] = 1.0;
    dud[ix] = -1.0 / tau_;
  }
  int Rhs(const BimorphPoint& p, std::span<double> x_dot, std::span<double>) const override {
    x_dot[0] = (p.u - p.x[0]) / tau_;
    return 0;
  }
  void Jacobian(const BimorphPoint& p, ExtensionJacobian& j) const override {
    j.AddState(0, static_cast<int>(p.x.data() - p.y.data()), -1.0 / tau_);
  }

 private:
  double tau_;
};

class CubicTipSpring final : public BimorphExtension {
 public:
  explicit CubicTipSpring(double k3) : k3_(k3) {}
  std::string name() const override { return "cubic tip spring"; }
  int Rhs(const BimorphPoint& p, std::span<double>, std::span<double> force) const override {
    const double w = p.q[p.tip_dof];
    force[p.tip_dof] -= k3_ * w * w * w;
    return 0;
  }
  void Jacobian(const BimorphPoint& p, ExtensionJacobian& j) const override {
    const double w = p.q[p.tip_dof];
    j.AddForce(p.tip_dof, p.tip_dof, -3 * k3_ * w * w);
  }

 private:
  double k3_;
};

class PassiveDecay final : public BimorphExtension {
 public:
  std::string name() const override { return "passive decay"; }
  int num_states() const override { return 1; }
  void InitialState(std::span<double> x) const override { x[0] = 1.0; }
  int Rhs(const BimorphPoint& p, std::span<double> x_dot, std::span<double>) const override {
    x_dot[0] = -p.x[0];
    return 0;
  }
  void Jacobian(const BimorphPoint& p, ExtensionJacobian& j) const override {
    j.AddState(0, static_cast<int>(p.x.data() - p.y.data()), -1.0);
  }
};

TEST(BimorphOde, ReducedAndDenseNewtonSolversAgree) {
  const BimorphPlant plant;
  const DriveSignal drive = Sinusoid{375.0, 1.0, 1.0, 100.0};
  const BimorphOde ode(plant, Case1Params(), drive);
  EXPECT_EQ(ode.jacobian_structure().kinematic, ode.num_dofs());
  const std::vector<double> t = SampleTimes(drive), y0 = ode.InitialState();
  CvodeOptions o;
  o.rtol = 1e-10;
  o.atol = 1e-14;
  o.breakpoints = ode.Breakpoints();
  o.linear_solver = LinearSolverKind::kDense;
  const OdeSolution dense = IntegrateCvode(ode, 0.0, y0, t, o);
  o.linear_solver = LinearSolverKind::kReduced;
  const OdeSolution reduced = IntegrateCvode(ode, 0.0, y0, t, o);
  ASSERT_TRUE(dense.summary.ok() && reduced.summary.ok()) << reduced.summary.BriefReport();
  double w_max = 0;
  for (size_t k = 0; k < t.size(); ++k)
    w_max = std::max(w_max, std::abs(dense.at(k, ode.tip_index())));
  for (size_t k = 0; k < t.size(); ++k)
    EXPECT_NEAR(reduced.at(k, ode.tip_index()), dense.at(k, ode.tip_index()), 1e-9 * w_max)
        << "k=" << k;
}

TEST(BimorphOdeExtensions, JacobianWithStagesAndForcesMatchesDifferences) {
  const BimorphPlant plant;
  const DriveSignal drive = Sinusoid{};
  const Amplifier amp(1e-3);
  const CubicTipSpring spring(1e12);  // with w_tip = 1e-6: ∂f/∂w = −3 N/m
  const PassiveDecay passive;
  BimorphParams p = Case1Params();
  p.delta = 0.0;  // see AnalyticJacobianMatchesDifferences
  const BimorphOde ode(plant, p, drive, {&amp, &spring, &passive});
  EXPECT_EQ(ode.size(), 27);
  EXPECT_EQ(ode.extension_offset(0), 25);
  EXPECT_EQ(ode.extension_offset(2), 26);
  ExpectJacobianMatchesDifferences(ode, 0.3);
}

TEST(BimorphOdeExtensions, DecoupledExtensionLeavesTheBeamUnchanged) {
  const BimorphPlant plant;
  const Sinusoid sin{375.0, 1.0, 1.0, 100.0};
  const DriveSignal drive = sin;
  const SimulateOptions o;
  const PassiveDecay passive;
  const BimorphTrace plain = SimulateBimorphOde(plant, Case1Params(), drive, o);
  const BimorphTrace with = SimulateBimorphOde(plant, Case1Params(), drive, o, {&passive});
  ASSERT_TRUE(plain.summary.ok()) << plain.summary.BriefReport();
  ASSERT_TRUE(with.summary.ok()) << with.summary.BriefReport();
  // Equal up to the integration error (the extra state changes the step sequence).
  for (size_t k = 0; k < plain.theta_deg.size(); ++k)
    EXPECT_NEAR(with.theta_deg[k], plain.theta_deg[k], 1e-7);
}

TEST(BimorphOdeExtensions, FastAmplifierApproachesTheDirectDrive) {
  // With τ → 0 the amplifier passes u through: θ differs by O(τ u̇) from the plain plant.
  const BimorphPlant plant;
  const DriveSignal drive = Sinusoid{375.0, 1.0, 1.0, 100.0};
  const Amplifier amp(1e-6);
  const BimorphTrace plain = SimulateBimorphOde(plant, Case1Params(), drive, SimulateOptions{});
  const BimorphTrace with =
      SimulateBimorphOde(plant, Case1Params(), drive, SimulateOptions{}, {&amp});
  ASSERT_TRUE(with.summary.ok()) << with.summary.BriefReport();
  for (size_t k = 0; k < plain.theta_deg.size(); ++k)
    EXPECT_NEAR(with.theta_deg[k], plain.theta_deg[k], 1e-4);
}

// With α = 0 the plant is linear in u, and each mode obeys η̈ + (μ + δω²) η̇ + ω² η = g u(t). For a
// piecewise-linear u the exact solution over a sample step is the first-order hold
// x_{k+1} = Φ x_k + Γ0 u_k + Γ1 (u_{k+1} − u_k), from the exponential of a 4 × 4 augmented matrix
// per mode.
TEST(BimorphOdeSampledInput, MatchesExactFirstOrderHold) {
  const BimorphPlant plant;
  BimorphParams p = Case1Params();
  p.alpha = 0.0;
  p.delta = 1e-4;  // keeps ‖A h‖ of the fastest mode moderate for the matrix exponential
  const ModalBasis& mb = plant.modal();
  const int modes = static_cast<int>(mb.omega.size());

  SampledSignal s;
  const double h = 0.01;
  for (int k = 0; k <= 60; ++k) {
    s.t.push_back(k * h);
    s.u.push_back(300.0 * std::sin(0.5 * k) + 50.0 * (k % 7));  // rough on purpose
  }
  std::vector<Eigen::Matrix2d> phi(modes);
  std::vector<Eigen::Vector2d> g0(modes), g1(modes);
  for (int i = 0; i < modes; ++i) {
    const double w = mb.omega[i];
    Eigen::Matrix4d big = Eigen::Matrix4d::Zero();  // states [η, η̇, u, Δu]
    big(0, 1) = h;
    big(1, 0) = -w * w * h;
    big(1, 1) = -(p.mu + p.delta * w * w) * h;
    big(1, 2) = mb.gain_u[i] * h;
    big(2, 3) = 1.0;  // u̇ = Δu / h
    const Eigen::Matrix4d e = big.exp();
    phi[i] = e.topLeftCorner<2, 2>();
    g0[i] = e.block<2, 1>(0, 2);
    g1[i] = e.block<2, 1>(0, 3);
  }

  SimulateOptions o;
  o.solver = Solver::kCvode;
  const BimorphTrace tr = Simulate(plant, p, s, o);
  ASSERT_TRUE(tr.summary.ok()) << tr.summary.BriefReport();
  ASSERT_EQ(tr.w_tip.size(), s.t.size());
  std::vector<Eigen::Vector2d> x(modes, Eigen::Vector2d::Zero());
  for (size_t k = 0; k < s.t.size(); ++k) {
    double w_tip = 0;
    for (int i = 0; i < modes; ++i) w_tip += mb.tip[i] * x[i][0];
    EXPECT_NEAR(tr.w_tip[k], w_tip, 1e-12 + 1e-7 * std::abs(w_tip)) << "k=" << k;
    if (k + 1 < s.t.size())
      for (int i = 0; i < modes; ++i)
        x[i] = phi[i] * x[i] + g0[i] * s.u[k] + g1[i] * (s.u[k + 1] - s.u[k]);
  }
}

}  // namespace
}  // namespace pz::model
