#include "model/effect_library.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <ostream>
#include <stdexcept>

#include "model/bimorph_ode.h"
#include "model/kernels/pzk.h"
#include "model/status.h"

namespace pz::model {
namespace {

// ---- shared arithmetic
// ----------------------------------------------------------------------------

/// The block of an effect's step kernel (model/kernels/effects.h) on the parameters p: the one
/// home of the effects' per-sample arithmetic, which ApplyDrive / ApplyOutput run over a record.
pzk::pzk_block EffectBlock(int kind, std::span<const double> p, double dt) {
  pzk::pzk_block b{};
  b.kind = kind;
  b.dt = dt;
  b.p = p.data();
  b.np = static_cast<int>(p.size());
  return b;
}

// ---- CVODE extensions (the continuous-time forms)
// ------------------------------------------------

int StateIndex(const BimorphPoint& p, int i) {
  return static_cast<int>(p.x.data() - p.y.data()) + i;
}

// τ ẋ = u − x; drive out (x, (u − x)/τ).
class LowpassExtension final : public BimorphExtension {
 public:
  explicit LowpassExtension(double tau) : tau_(tau) {}
  std::string name() const override { return "driver-lowpass"; }
  int num_states() const override { return 1; }
  bool shapes_drive() const override { return true; }
  int ShapeDrive(const BimorphPoint& p, double& u, double& u_dot) const override {
    u_dot = (p.u - p.x[0]) / tau_;
    u = p.x[0];
    return 0;
  }
  void ShapeDriveJacobian(const BimorphPoint& p, std::span<double> du,
                          std::span<double> dud) const override {
    const int ix = StateIndex(p, 0);
    for (size_t j = 0; j < du.size(); ++j) {
      dud[j] = du[j] / tau_;
      du[j] = 0.0;
    }
    du[ix] = 1.0;
    dud[ix] -= 1.0 / tau_;
  }
  int Rhs(const BimorphPoint& p, std::span<double> x_dot, std::span<double>) const override {
    x_dot[0] = (p.u - p.x[0]) / tau_;
    return 0;
  }
  void Jacobian(const BimorphPoint& p, ExtensionJacobian& jac) const override {
    for (size_t j = 0; j < p.du_dy.size(); ++j)
      if (p.du_dy[j] != 0.0) jac.AddState(0, static_cast<int>(j), p.du_dy[j] / tau_);
    jac.AddState(0, StateIndex(p, 0), -1.0 / tau_);
  }

 private:
  double tau_;
};

// u_e = u + c u²: no state.
class QuadraticExtension final : public BimorphExtension {
 public:
  explicit QuadraticExtension(double c) : c_(c) {}
  std::string name() const override { return "quadratic-drive"; }
  bool shapes_drive() const override { return true; }
  int ShapeDrive(const BimorphPoint& p, double& u, double& u_dot) const override {
    u = p.u + c_ * p.u * p.u;
    u_dot = p.u_dot * (1.0 + 2.0 * c_ * p.u);
    return 0;
  }
  void ShapeDriveJacobian(const BimorphPoint& p, std::span<double> du,
                          std::span<double> dud) const override {
    const double g = 1.0 + 2.0 * c_ * p.u;
    for (size_t j = 0; j < du.size(); ++j) {
      dud[j] = dud[j] * g + 2.0 * c_ * p.u_dot * du[j];
      du[j] *= g;
    }
  }
  int Rhs(const BimorphPoint&, std::span<double>, std::span<double>) const override { return 0; }
  void Jacobian(const BimorphPoint&, ExtensionJacobian&) const override {}

 private:
  double c_;
};

// τ_c ẋ = k u − x; drive out (u + x, u̇ + (k u − x)/τ_c).
class CreepExtension final : public BimorphExtension {
 public:
  CreepExtension(double k, double tau) : k_(k), tau_(tau) {}
  std::string name() const override { return "creep"; }
  int num_states() const override { return 1; }
  bool shapes_drive() const override { return true; }
  int ShapeDrive(const BimorphPoint& p, double& u, double& u_dot) const override {
    u = p.u + p.x[0];
    u_dot = p.u_dot + (k_ * p.u - p.x[0]) / tau_;
    return 0;
  }
  void ShapeDriveJacobian(const BimorphPoint& p, std::span<double> du,
                          std::span<double> dud) const override {
    const int ix = StateIndex(p, 0);
    for (size_t j = 0; j < du.size(); ++j) dud[j] += k_ * du[j] / tau_;
    dud[ix] -= 1.0 / tau_;
    du[ix] += 1.0;
  }
  int Rhs(const BimorphPoint& p, std::span<double> x_dot, std::span<double>) const override {
    x_dot[0] = (k_ * p.u - p.x[0]) / tau_;
    return 0;
  }
  void Jacobian(const BimorphPoint& p, ExtensionJacobian& jac) const override {
    for (size_t j = 0; j < p.du_dy.size(); ++j)
      if (p.du_dy[j] != 0.0) jac.AddState(0, static_cast<int>(j), k_ * p.du_dy[j] / tau_);
    jac.AddState(0, StateIndex(p, 0), -1.0 / tau_);
  }

 private:
  double k_, tau_;
};

// Dahl: Ḟ = σ v (1 − F/F_c sgn v), v = ẇ_tip; tip force −F.
class DahlHingeExtension final : public BimorphExtension {
 public:
  DahlHingeExtension(double fc, double sigma) : fc_(fc), sigma_(sigma) {}
  std::string name() const override { return "hinge-friction"; }
  int num_states() const override { return 1; }
  int Rhs(const BimorphPoint& p, std::span<double> x_dot, std::span<double> force) const override {
    const double v = p.q_dot[p.tip_dof], f = p.x[0];
    x_dot[0] = sigma_ * (v - std::abs(v) * f / fc_);
    force[p.tip_dof] -= f;
    return 0;
  }
  void Jacobian(const BimorphPoint& p, ExtensionJacobian& jac) const override {
    const double v = p.q_dot[p.tip_dof], f = p.x[0];
    const double sv = (v > 0) - (v < 0);
    const int ix = StateIndex(p, 0);
    const int iv = static_cast<int>(p.q_dot.data() - p.y.data()) + p.tip_dof;
    jac.AddState(0, iv, sigma_ * (1.0 - sv * f / fc_));
    jac.AddState(0, ix, -sigma_ * std::abs(v) / fc_);
    jac.AddForce(p.tip_dof, ix, -1.0);
  }

 private:
  double fc_, sigma_;
};

// Tip force −k3 w³.
class CubicExtension final : public BimorphExtension {
 public:
  explicit CubicExtension(double k3) : k3_(k3) {}
  std::string name() const override { return "cubic-stiffening"; }
  int Rhs(const BimorphPoint& p, std::span<double>, std::span<double> force) const override {
    const double w = p.q[p.tip_dof];
    force[p.tip_dof] -= k3_ * w * w * w;
    return 0;
  }
  void Jacobian(const BimorphPoint& p, ExtensionJacobian& jac) const override {
    const double w = p.q[p.tip_dof];
    const int iw = static_cast<int>(p.q.data() - p.y.data()) + p.tip_dof;
    jac.AddForce(p.tip_dof, iw, -3.0 * k3_ * w * w);
  }

 private:
  double k3_;
};

// ---- the effects
// ----------------------------------------------------------------------------------

class DriverLowpass final : public EffectDef {
 public:
  const char* name() const override { return "driver-lowpass"; }
  const char* title() const override { return "driver (amplifier) first-order low-pass"; }
  const char* equation() const override { return "tau u_e' = u - u_e"; }
  EffectStage stage() const override { return EffectStage::kDrive; }
  int kernel() const override { return pzk::PZK_LOWPASS; }
  std::vector<ParamInfo> Params(const DataScale& s) const override {
    const double dt = 1 / s.fs;
    const double tau_hi = std::max(0.5 / (2 * std::numbers::pi * s.f_dom), 20 * dt);
    return {{"tau_s", "s", dt / 100, tau_hi, true}};
  }
  void ApplyDrive(std::span<const double> p, double dt, std::span<double> u) const override {
    if (u.empty()) return;
    const pzk::pzk_block b = EffectBlock(kernel(), p, dt);
    double c[3] = {}, d[2];
    pzk::pzk_driver_lowpass_init(&b, c, d, u[0], u[0]);
    for (size_t k = 1; k < u.size(); ++k) u[k] = pzk::pzk_driver_lowpass_step(c, d, d, u[k]);
  }
  std::unique_ptr<BimorphExtension> MakeExtension(std::span<const double> p) const override {
    return std::make_unique<LowpassExtension>(p[0]);
  }
};

class QuadraticDrive final : public EffectDef {
 public:
  const char* name() const override { return "quadratic-drive"; }
  const char* title() const override { return "quadratic (electrostrictive) drive term"; }
  const char* equation() const override { return "u_e = u + c2 u^2"; }
  EffectStage stage() const override { return EffectStage::kDrive; }
  int kernel() const override { return pzk::PZK_QUADRATIC; }
  std::vector<ParamInfo> Params(const DataScale& s) const override {
    const double umax = std::max(std::abs(s.u_min), std::abs(s.u_max));
    return {{"c2", "1/V", -0.3 / umax, 0.3 / umax, false}};
  }
  void ApplyDrive(std::span<const double> p, double dt, std::span<double> u) const override {
    const pzk::pzk_block b = EffectBlock(kernel(), p, dt);
    for (double& v : u) v = pzk::pzk_quadratic_step(&b, v);
  }
  bool memoryless() const override { return true; }
  std::unique_ptr<BimorphExtension> MakeExtension(std::span<const double> p) const override {
    return std::make_unique<QuadraticExtension>(p[0]);
  }
};

class Creep final : public EffectDef {
 public:
  const char* name() const override { return "creep"; }
  const char* title() const override { return "piezo creep of the drive (one relaxation)"; }
  const char* equation() const override { return "tau_c x' = k_c (u - u0) - x, u_e = u + x"; }
  EffectStage stage() const override { return EffectStage::kDrive; }
  int kernel() const override { return pzk::PZK_CREEP; }
  std::vector<ParamInfo> Params(const DataScale& s) const override {
    const double lo = 0.5 / s.f_dom, hi = std::max(10 * s.duration, 2 * lo);
    return {{"k_c", "-", -0.3, 0.3, false}, {"tau_c_s", "s", lo, hi, true}};
  }
  void ApplyDrive(std::span<const double> p, double dt, std::span<double> u) const override {
    if (p[0] == 0 || u.empty()) return;
    // u += the low-pass of k (u − u0), at rest at u0 = u[0].
    const pzk::pzk_block b = EffectBlock(kernel(), p, dt);
    double c[5] = {}, d[2];
    pzk::pzk_creep_init(&b, c, d, u[0]);
    for (size_t k = 1; k < u.size(); ++k) u[k] = pzk::pzk_creep_step(&b, c, d, d, u[k]);
  }
  std::unique_ptr<BimorphExtension> MakeExtension(std::span<const double> p) const override {
    return std::make_unique<CreepExtension>(p[0], p[1]);
  }
};

class Delay final : public EffectDef {
 public:
  const char* name() const override { return "delay"; }
  const char* title() const override { return "measurement / transport delay"; }
  const char* equation() const override { return "u_e(t) = u(t - tau_d)"; }
  EffectStage stage() const override { return EffectStage::kDrive; }
  int kernel() const override { return pzk::PZK_DELAY; }
  std::vector<ParamInfo> Params(const DataScale& s) const override {
    const double dt = 1 / s.fs;
    return {{"tau_d_s", "s", 0, std::max(std::min(0.25 / s.f_dom, 500 * dt), 2 * dt), false}};
  }
  void ApplyDrive(std::span<const double> p, double dt, std::span<double> u) const override {
    const double shift = p[0] / dt;
    if (!(shift > 0) || u.empty()) return;
    // The arithmetic of the kernel's pzk_delay_step (model/kernels/effects.h), on the whole record
    // rather than its ring of the last inputs: the ring's two divisions a sample made the fits of a
    // stack with a delay 1.24× slower (bench_record_fit).
    const std::vector<double> src(u.begin(), u.end());
    for (size_t k = 0; k < u.size(); ++k) {
      const double pos = static_cast<double>(k) - shift;
      if (pos <= 0) {
        u[k] = src[0];
      } else {
        const size_t j = static_cast<size_t>(pos);
        const double f = pos - static_cast<double>(j);
        u[k] = j + 1 < src.size() ? src[j] + f * (src[j + 1] - src[j]) : src[j];
      }
    }
  }
  double TimeShift(std::span<const double> p) const override { return p[0]; }
};

// Rate dependence (issue 22): the loop widens with the drive rate, and the widening saturates. In
// the rate-dependent Prandtl–Ishlinskii model (Al Janaideh & Krejčí) every play's threshold grows
// with the drive rate, r_j(u̇) = r_j + λ(u̇); the part λ common to every threshold is, for any
// family, a play of half-width λ(u̇) ahead of it: the drive the hysteresis sees lags the applied
// one
// by λ in the direction of motion, and holds at a reversal (never beyond the drive's extremes).
// Measured stacks show the loop width growing with frequency sub-linearly, towards a bound (domain
// walls cannot switch faster than their mobility allows), so λ saturates:
//   u_e = play_λ[u] = max(u − λ, min(u + λ, u_e⁻)),   λ = r_m tanh(τ_r |u̇| / r_m),
// with the rate u̇ at t_k estimated by the second-order backward difference (3u_k − 4u_{k−1} +
// u_{k−2}) / 2dt (exact for a drive quadratic over the last two samples; at rest at u[0] before
// it). A reversal between two samples (the estimate changes sign) passes the vertex of the drive
// there, u_k − u̇_k² dt / 2(u̇_k − u̇_{k−1}) (the parabola through the two rates), where λ = 0: the
// play waits at the drive's extreme, not at the sample nearest it (at 8 Hz and 200 Hz they differ
// by up to 0.4 % of the swing, and λ at that sample can be many times more). Below the knee rate
// r_m/τ_r the lag is τ_r u̇ — what a driver low-pass or a delay of τ_r gives to first order —,
// above
// it the lag tends to r_m whatever the rate: a loop that stops widening with frequency, which
// neither a low-pass (whose lag grows with the rate and whose gain falls) nor a delay (a phase
// growing with frequency) can give. So records at several rates that reach the knee tell it apart;
// records at one rate do not (records/excitation.h, the rate span).
class RateDependence final : public EffectDef {
 public:
  const char* name() const override { return "rate-dependence"; }
  const char* title() const override {
    return "rate-dependent lag of the drive, saturating (loop width grows with rate)";
  }
  const char* equation() const override {
    return "u_e = play_lambda[u], lambda = r_m tanh(tau_r |u'| / r_m), u' = (3u_k - 4u_k-1 + "
           "u_k-2)/(2 dt)";
  }
  EffectStage stage() const override { return EffectStage::kDrive; }
  int kernel() const override { return pzk::PZK_RATE_DEPENDENCE; }
  std::vector<ParamInfo> Params(const DataScale& s) const override {
    const double dt = 1 / s.fs;
    const double tau_hi = std::max(0.5 / (2 * std::numbers::pi * s.f_dom), 20 * dt);
    return {{"r_m", "drive", 0, 0.3 * s.u_half, false}, {"tau_r_s", "s", dt / 100, tau_hi, true}};
  }
  void ApplyDrive(std::span<const double> p, double dt, std::span<double> u) const override {
    if (!(p[0] > 0) || u.empty()) return;
    // At rest at u[0] before it; the first sample is stepped too.
    const pzk::pzk_block b = EffectBlock(kernel(), p, dt);
    double d[4];
    pzk::pzk_rate_dependence_init(d, u[0]);
    for (double& v : u) v = pzk::pzk_rate_dependence_step(&b, d, d, v);
  }
};

class HingeFriction final : public EffectDef {
 public:
  const char* name() const override { return "hinge-friction"; }
  const char* title() const override { return "Dahl friction at the fin hinge"; }
  const char* equation() const override {
    return "F' = sigma w_tip' (1 - F/F_c sgn w_tip'), tip force -F";
  }
  EffectStage stage() const override { return EffectStage::kBeam; }
  std::vector<ParamInfo> Params(const DataScale&) const override {  // physical: the beam's units
    return {{"fc_n", "N", 0.0, 1.0, false}, {"sigma_n_per_m", "N/m", 20.0, 2e5, true}};
  }
  std::unique_ptr<BimorphExtension> MakeExtension(std::span<const double> p) const override {
    return std::make_unique<DahlHingeExtension>(p[0], p[1]);
  }
};

class CubicStiffening final : public EffectDef {
 public:
  const char* name() const override { return "cubic-stiffening"; }
  const char* title() const override { return "cubic stiffening of the beam"; }
  const char* equation() const override { return "tip force -k3 w_tip^3"; }
  EffectStage stage() const override { return EffectStage::kBeam; }
  std::vector<ParamInfo> Params(const DataScale&) const override {
    return {{"k3_n_per_m3", "N/m^3", -5e6, 2e7, false}};
  }
  std::unique_ptr<BimorphExtension> MakeExtension(std::span<const double> p) const override {
    return std::make_unique<CubicExtension>(p[0]);
  }
};

// Creep over decades (issue 22): relaxations at fixed log-spaced times from 0.05 s up to the data's
// longest scored window T, two per decade (both ends included), each a first-order relaxation of
// the plant's output with a non-negative weight w_i (a share of the output):
//   y_e = y − Σ w_i (y − x_i),   τ_i ẋ_i = y − x_i,   at rest at y[0].
// A step of the output then creeps up as 1 − Σ w_i e^{−t/τ_i}: equal weights are log creep over the
// span, free weights any monotone creep spectrum. It acts on the output (after the hysteresis),
// the Hammerstein structure of the stack-creep literature (hysteresis, then a linear creep
// operator): the polarisation that the hysteresis sets relaxes, whatever drive set it. It is linear
// in y, so a linear family (preisach, asymmetric-pi) takes it on each regressor and its weights
// stay solved exactly (records::RecordFitness). Discretised exactly for an output linear between
// samples (the driver low-pass's first-order hold), on deviations from the rest output (exactly
// zero at rest).
class CreepSpectrum final : public EffectDef {
 public:
  static constexpr double kTauMin = 0.05;     ///< [s] the fastest relaxation
  static constexpr double kPerDecade = 2;     ///< relaxations per decade of time
  static constexpr double kMaxWeight = 0.05;  ///< per relaxation: 10 % of the output per decade

  const char* name() const override { return "creep-spectrum"; }
  const char* title() const override {
    return "creep over decades (relaxations from 0.05 s to the window's length)";
  }
  const char* equation() const override {
    return "y_e = y - sum_i w_i (y - x_i), tau_i x_i' = y - x_i, w_i >= 0, tau_i = 0.05 s .. T "
           "log-spaced";
  }
  EffectStage stage() const override { return EffectStage::kOutput; }
  std::vector<ParamInfo> Params(const DataScale& s) const override {
    std::vector<ParamInfo> out;
    for (double tau : Times(s.duration)) {
      char name[32];
      std::snprintf(name, sizeof name, "w_%.3gs", tau);
      out.push_back({name, "-", 0.0, kMaxWeight, false});
    }
    return out;
  }
  void ApplyOutput(std::span<const double> p, const OutputFrame& f,
                   std::span<double> y) const override {
    if (y.empty()) return;
    const std::vector<double> taus =
        Times(f.duration);  // p holds these weights first (then later effects')
    const size_t n = taus.size();
    if (p.size() < n) throw std::logic_error("creep-spectrum: fewer weights than relaxations");
    pzk::pzk_block b = EffectBlock(kernel(), p.first(n), f.dt);
    b.n = static_cast<int>(n);
    b.w = taus.data();
    b.nw = static_cast<int>(n);
    std::vector<double> c(1 + 2 * n), d(1 + n);
    pzk::pzk_creep_spectrum_init(&b, c.data(), d.data(), y[0]);
    for (size_t k = 1; k < y.size(); ++k)
      y[k] = pzk::pzk_creep_spectrum_step(&b, c.data(), d.data(), d.data(), y[k]);
  }
  bool linear_output() const override { return true; }
  std::vector<double> KernelData(const DataScale& s) const override { return Times(s.duration); }
  int kernel() const override { return pzk::PZK_CREEP_SPECTRUM; }

 private:
  /// The relaxation times for a window of T seconds; throws InputError when T is under a decade.
  static std::vector<double> Times(double T) {
    if (!(std::isfinite(T) && T >= 10 * kTauMin)) {
      char msg[400];
      std::snprintf(
          msg, sizeof msg,
          "effect 'creep-spectrum' needs a scored window of at least %g s (relaxations from %g s "
          "up to "
          "the window's length, one decade at least); the longest training window is %g s: record "
          "longer, or use 'creep' (one relaxation)",
          10 * kTauMin, kTauMin, T);
      throw InputError(msg);
    }
    const size_t count =
        static_cast<size_t>(std::ceil(kPerDecade * std::log10(T / kTauMin) - 1e-9)) + 1;
    std::vector<double> taus(count, kTauMin);
    for (size_t i = 1; i < count; ++i)
      taus[i] =
          kTauMin * std::pow(T / kTauMin, static_cast<double>(i) / static_cast<double>(count - 1));
    return taus;
  }
};

// A mechanical mode after the hysteresis (issue 45): the stack and its flexure ring after a step
// (≈ 740 Hz on a 35 µm stack at 10 kHz) and on a drive with content there, and no other effect is a
// mode. Hammerstein, as the creep spectrum: the hysteresis's output v drives a second-order mode
// of unit gain at DC, of which a share a reaches the output,
//   y = (1 − a) v + a q,   q̈ + 2ζω q̇ + ω² q = ω² v,   ω = 2π f_n,
// so the hysteresis keeps its meaning at rest and slowly (a = 1: the whole output through the
// mode; a < 1: a part of the reading that does not ring, e.g. a sensor on the frame). Discretised
// exactly for an input linear between samples (the first-order hold of the library's low-passes:
// the closed form of the free oscillator's exp(A dt) over the deviation from the quasi-static
// ramp, model/kernels/effects.h pzk_resonance_consts), so that f_n near Nyquist is no
// approximation; not ZOH, which would hold the hysteresis's output as a staircase the plant never
// saw, nor Tustin, whose warp is exact at one frequency only. Linear and homogeneous in y, at rest
// at y[0]: a linear family takes it on each regressor (its weights solved for the output through
// the mode). Its start values come from the data, not from the box: a fit places f_n and ζ at the
// dominant band of the residual (records/fit.cc; model/effect_library_resonance.h), or at the
// ringing of a rest that follows a step.
class Resonance final : public EffectDef {
 public:
  const char* name() const override { return "resonance"; }
  const char* title() const override {
    return "a second-order mode after the hysteresis (structure, flexure)";
  }
  const char* equation() const override {
    return "y_e = (1 - a) y + a q, q'' + 2 zeta w q' + w^2 q = w^2 y, w = 2 pi f_n";
  }
  EffectStage stage() const override { return EffectStage::kOutput; }
  int kernel() const override { return pzk::PZK_RESONANCE; }
  /// f_n from twice the drive's dominant frequency (at most fs/20) to 0.45 fs: a mode the data's
  /// sampling resolves, above the drive's own band.
  std::vector<ParamInfo> Params(const DataScale& s) const override {
    const double f_lo = std::min(2 * s.f_dom, 0.05 * s.fs);
    return {{"share", "-", 0.0, 1.0, false},
            {"f_n_hz", "Hz", f_lo, 0.45 * s.fs, true},
            {"zeta", "-", 0.003, 0.7, true}};
  }
  void ApplyOutput(std::span<const double> p, const OutputFrame& f,
                   std::span<double> y) const override {
    if (y.empty() || p[0] == 0) return;
    const pzk::pzk_block b = EffectBlock(kernel(), p.first(3), f.dt);
    double c[10], d[3];
    pzk::pzk_resonance_init(&b, c, d, y[0]);
    for (size_t k = 1; k < y.size(); ++k) y[k] = pzk::pzk_resonance_step(c, d, d, y[k]);
  }
  bool linear_output() const override { return true; }
};

class Friction final : public EffectDef {
 public:
  const char* name() const override { return "friction"; }
  const char* title() const override { return "friction dead band at the output"; }
  const char* equation() const override { return "y_e = play_r[y]"; }
  EffectStage stage() const override { return EffectStage::kOutput; }
  int kernel() const override { return pzk::PZK_FRICTION; }
  std::vector<ParamInfo> Params(const DataScale& s) const override {
    return {{"r", "y", 0, 0.2 * s.y_half, false}};
  }
  void ApplyOutput(std::span<const double> p, const OutputFrame& f,
                   std::span<double> y) const override {
    if (y.empty()) return;
    const pzk::pzk_block b = EffectBlock(kernel(), p, f.dt);
    double d[1];
    pzk::pzk_friction_init(d, y[0]);
    for (double& v : y) v = pzk::pzk_friction_step(&b, d, d, v);
  }
};

class Stiffening final : public EffectDef {
 public:
  const char* name() const override { return "stiffening"; }
  const char* title() const override { return "cubic stiffening"; }
  const char* equation() const override { return "y_e = y - k3 Y ((y - y0)/Y)^3"; }
  EffectStage stage() const override { return EffectStage::kOutput; }
  int kernel() const override { return pzk::PZK_STIFFENING; }
  std::vector<ParamInfo> Params(const DataScale&) const override {
    return {{"k3", "-", -0.3, 0.3, false}};
  }
  void ApplyOutput(std::span<const double> p, const OutputFrame& f,
                   std::span<double> y) const override {
    if (y.empty()) return;
    pzk::pzk_block b = EffectBlock(kernel(), p, f.dt);
    b.y_half = f.y_half;
    const double c[1] = {y[0]};  // the output at rest
    for (double& v : y) v = pzk::pzk_stiffening_step(&b, c, v);
  }
};

class Drift final : public EffectDef {
 public:
  const char* name() const override { return "drift"; }
  const char* title() const override { return "drift of the reading"; }
  const char* equation() const override { return "y_e = y + rate (t - t_window)"; }
  EffectStage stage() const override { return EffectStage::kOutput; }
  int kernel() const override { return pzk::PZK_DRIFT; }
  const char* former_name() const override {
    return "output-drift";
  }  // its name before the one library
  std::vector<ParamInfo> Params(const DataScale& s) const override {
    return {{"rate", "y/s", -s.y_half / s.duration, s.y_half / s.duration, false}};
  }
  void ApplyOutput(std::span<const double> p, const OutputFrame& f,
                   std::span<double> y) const override {
    // The kernel's clock counts the samples from the frame's origin (a whole sample: exact).
    const pzk::pzk_block b = EffectBlock(kernel(), p, f.dt);
    double d[1] = {-f.origin - 1};
    for (double& v : y) v = pzk::pzk_drift_step(&b, d, d, v);
  }
};

// The registry: one line per effect, in chain order.
const DriverLowpass kDriverLowpass;
const QuadraticDrive kQuadraticDrive;
const Creep kCreep;
const Delay kDelay;
const RateDependence kRateDependence;
const HingeFriction kHingeFriction;
const CubicStiffening kCubicStiffening;
const CreepSpectrum kCreepSpectrum;
const Resonance kResonance;
const Friction kFriction;
const Stiffening kStiffening;
const Drift kDrift;

}  // namespace

const std::vector<const EffectDef*>& Effects() {
  static const std::vector<const EffectDef*> all = {
      &kDriverLowpass,  &kQuadraticDrive, &kCreep,           &kDelay,
      &kRateDependence, &kHingeFriction,  &kCubicStiffening, &kCreepSpectrum,
      &kResonance,      &kFriction,       &kStiffening,      &kDrift};
  return all;
}

const EffectDef* FindEffect(std::string_view name) {
  for (const EffectDef* e : Effects())
    if (name == e->name() || (e->former_name() != nullptr && name == e->former_name())) return e;
  return nullptr;
}

EffectKind EffectKind::Named(std::string_view name) {
  const EffectDef* def = FindEffect(name);
  if (def == nullptr)
    throw std::logic_error("no effect named '" + std::string(name) + "' in model::Effects()");
  return *def;
}

const char* EffectKind::name() const { return def_ == nullptr ? "none" : def_->name(); }

std::strong_ordering operator<=>(EffectKind a, EffectKind b) {
  if (a.def_ == b.def_) return std::strong_ordering::equal;
  if (a.def_ == nullptr) return std::strong_ordering::less;
  if (b.def_ == nullptr) return std::strong_ordering::greater;
  return EffectIndex(*a.def_) <=> EffectIndex(*b.def_);
}

std::ostream& operator<<(std::ostream& os, EffectKind kind) { return os << kind.name(); }

size_t EffectIndex(const EffectDef& effect) {
  const auto& all = Effects();
  for (size_t i = 0; i < all.size(); ++i)
    if (all[i] == &effect) return i;
  throw std::logic_error(std::string("effect '") + effect.name() +
                         "' is not registered in model::Effects()");
}

const char* StageName(EffectStage stage) {
  switch (stage) {
    case EffectStage::kDrive:
      return "drive";
    case EffectStage::kBeam:
      return "beam";
    case EffectStage::kOutput:
      return "output";
  }
  return "?";
}

void EffectDef::ApplyDrive(std::span<const double>, double, std::span<double>) const {}
void EffectDef::ApplyOutput(std::span<const double>, const OutputFrame&, std::span<double>) const {}
std::unique_ptr<BimorphExtension> EffectDef::MakeExtension(std::span<const double>) const {
  return nullptr;
}

}  // namespace pz::model
