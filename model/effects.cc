#include "model/effects.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <sstream>

#include "model/backlash.h"
#include "model/cvode.h"

namespace pz::model {
namespace {

std::vector<EffectInfo> BuildLibrary() {
  std::vector<EffectInfo> lib;
  lib.push_back({EffectKind::kDriverLowpass, "driver-lowpass", "driver (amplifier) first-order low-pass",
                 EffectStage::kDrive, "tau x' = u - x, u_e = x", 0,
                 {{"tau_s", "s", 0.0, 0.2, 0.01, false, "time constant of the amplifier"}}});
  lib.push_back({EffectKind::kCreep, "creep", "piezo creep of the drive (one relaxation)", EffectStage::kDrive,
                 "tau_c x' = k_c u - x, u_e = u + x", 0,
                 {{"k_c", "-", 0.0, 1.0, 0.05, false, "creep gain: long-run extra share of the drive"},
                  {"tau_c_s", "s", 0.05, 50.0, 2.0, true, "creep relaxation time"}}});
  lib.push_back({EffectKind::kHingeFriction, "hinge-friction", "Dahl friction at the fin hinge",
                 EffectStage::kBeam, "F' = sigma w_tip' (1 - F/F_c sgn w_tip'), tip force -F", 0,
                 {{"fc_n", "N", 0.0, 1.0, 0.05, false, "Coulomb level F_c of the friction force"},
                  {"sigma_n_per_m", "N/m", 20.0, 2e5, 2000.0, true, "pre-sliding stiffness sigma"}}});
  lib.push_back({EffectKind::kDelay, "delay", "measurement / transport delay", EffectStage::kDrive,
                 "y(t) = y0(t - tau_d)", 0, {{"tau_d_s", "s", 0.0, 0.1, 0.005, false, "delay"}}});
  lib.push_back({EffectKind::kCubicStiffening, "cubic-stiffening", "cubic stiffening of the beam",
                 EffectStage::kBeam, "tip force -k3 w_tip^3", 0,
                 {{"k3_n_per_m3", "N/m^3", -5e6, 2e7, 1e6, false,
                   "cubic tip stiffness (linear tip stiffness is about 500 N/m)"}}});
  lib.push_back({EffectKind::kQuadraticDrive, "quadratic-drive", "quadratic (electrostrictive) drive term",
                 EffectStage::kDrive, "u_e = u + c2 u^2", 0,
                 {{"c2_per_v", "1/V", -5e-4, 5e-4, 2e-5, false, "quadratic drive coefficient"}}});
  lib.push_back({EffectKind::kOutputDrift, "output-drift", "drift of the angle reading", EffectStage::kOutput,
                 "y_k += r t_k", 0, {{"rate_deg_per_s", "deg/s", -0.2, 0.2, 0.005, false, "drift rate"}}});
  return lib;
}

const EffectInfo& NoneInfo() {
  static const EffectInfo none{EffectKind::kNone, "none", "no unmodelled effect", EffectStage::kOutput, "", -1, {}};
  return none;
}

// ---- CVODE extensions ----------------------------------------------------------------------------

int StateIndex(const BimorphPoint& p, int i) { return static_cast<int>(p.x.data() - p.y.data()) + i; }

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
  void ShapeDriveJacobian(const BimorphPoint& p, std::span<double> du, std::span<double> dud) const override {
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
  void ShapeDriveJacobian(const BimorphPoint& p, std::span<double> du, std::span<double> dud) const override {
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
  void ShapeDriveJacobian(const BimorphPoint& p, std::span<double> du, std::span<double> dud) const override {
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

// The non-identity effects of a list, in stage order.
std::vector<const Effect*> Active(std::span<const Effect> effects, EffectKind kind) {
  std::vector<const Effect*> r;
  for (const Effect& e : effects)
    if (e.kind == kind && !e.IsIdentity()) r.push_back(&e);
  return r;
}

double SumParam(std::span<const Effect> effects, EffectKind kind, int i) {
  double s = 0;
  for (const Effect* e : Active(effects, kind)) s += e->params[i];
  return s;
}

// First-order filter τ ẋ = g v − x with v linear between grid nodes (first-order hold, exact).
struct FohFilter {
  double a = 0, b0 = 0, b1 = 0;  // x_{j+1} = a x_j + b0 v_j + b1 v_{j+1}
  FohFilter(double tau, double gain, double h) {
    a = std::exp(-h / tau);
    const double c = tau * (1.0 - a) / h;  // x(h) = a x + (1−a) v_j + (v_{j+1} − v_j)(1 − c)
    b0 = gain * ((1.0 - a) - (1.0 - c));
    b1 = gain * (1.0 - c);
  }
};

// Per-thread scratch of the fast sampled path.
struct SampledScratch {
  DriveSignal signal = SampledSignal{};
  std::vector<double> t_fine, theta_fine, grid;
  ModalWorkspace ws;
};

SampledScratch& Scratch() {
  thread_local SampledScratch s;
  return s;
}

}  // namespace

const std::vector<EffectInfo>& EffectLibrary() {
  static const std::vector<EffectInfo> lib = BuildLibrary();
  return lib;
}

const EffectInfo& GetEffectInfo(EffectKind kind) {
  for (const EffectInfo& e : EffectLibrary())
    if (e.kind == kind) return e;
  return NoneInfo();
}

const char* EffectName(EffectKind kind) { return GetEffectInfo(kind).name.c_str(); }

std::optional<EffectKind> ParseEffectKind(std::string_view name) {
  if (name == "none") return EffectKind::kNone;
  for (const EffectInfo& e : EffectLibrary())
    if (e.name == name) return e.kind;
  return std::nullopt;
}

Status Effect::Validate() const {
  const EffectInfo& info = GetEffectInfo(kind);
  if (kind != EffectKind::kNone && info.kind == EffectKind::kNone)
    return InvalidArgument(FieldError("effect.kind", static_cast<int>(kind), "unknown effect kind"));
  if (params.size() != info.params.size())
    return InvalidArgument(FieldError(info.name + ".params.size()", params.size(),
                                      "must be " + std::to_string(info.params.size())));
  for (size_t i = 0; i < params.size(); ++i) {
    const EffectParamInfo& p = info.params[i];
    const double v = params[i];
    const std::string field = info.name + "." + p.name;
    if (!std::isfinite(v)) return InvalidArgument(FieldError(field, v, "must be finite"));
    if (v < p.lower || v > p.upper) {
      std::ostringstream r;
      r << "must be in [" << p.lower << ", " << p.upper << "] " << p.unit;
      return InvalidArgument(FieldError(field, v, r.str()));
    }
  }
  return Status::Ok();
}

bool Effect::IsIdentity() const {
  if (kind == EffectKind::kNone) return true;
  const EffectInfo& info = GetEffectInfo(kind);
  return info.magnitude_param >= 0 && static_cast<size_t>(info.magnitude_param) < params.size() &&
         params[info.magnitude_param] == 0.0;
}

std::string Effect::Describe() const {
  const EffectInfo& info = GetEffectInfo(kind);
  std::ostringstream os;
  os.precision(4);
  os << info.name;
  if (info.params.empty()) return os.str();
  os << "(";
  for (size_t i = 0; i < info.params.size(); ++i) {
    os << (i ? ", " : "") << info.params[i].name << " = ";
    if (i < params.size()) os << params[i];
    else os << "?";
    if (info.params[i].unit != "-") os << " " << info.params[i].unit;
  }
  os << ")";
  return os.str();
}

Effect Effect::Zero(EffectKind kind) {
  const EffectInfo& info = GetEffectInfo(kind);
  Effect e{kind, {}};
  for (size_t i = 0; i < info.params.size(); ++i) {
    const EffectParamInfo& p = info.params[i];
    double v = p.log_scale ? std::sqrt(p.lower * p.upper) : 0.5 * (p.lower + p.upper);
    if (static_cast<int>(i) == info.magnitude_param) v = 0.0;
    e.params.push_back(std::clamp(v, p.lower, p.upper));
  }
  return e;
}

bool NeedsCvode(std::span<const Effect> effects) {
  for (const Effect& e : effects)
    if (!e.IsIdentity() && GetEffectInfo(e.kind).stage == EffectStage::kBeam) return true;
  return false;
}

Status EffectSimOptions::Validate() const {
  if (oversample < 1 || oversample > 64)
    return InvalidArgument(FieldError("oversample", oversample, "must be in [1, 64]"));
  if (!(rtol > 0 && rtol <= 1e-2)) return InvalidArgument(FieldError("rtol", rtol, "must be in (0, 1e-2]"));
  if (!(atol > 0 && std::isfinite(atol))) return InvalidArgument(FieldError("atol", atol, "must be finite and > 0"));
  if (max_steps <= 0) return InvalidArgument(FieldError("max_steps", max_steps, "must be > 0"));
  return Status::Ok();
}

std::vector<double> ShapedDrive(std::span<const Effect> effects, const Sinusoid& drive, std::span<const double> t) {
  std::vector<double> out(t.size(), 0.0);
  if (t.empty()) return out;
  const double V = drive.amplitude_v, om = 2 * std::numbers::pi * drive.frequency_hz;
  const auto lowpasses = Active(effects, EffectKind::kDriverLowpass);
  const double c2 = SumParam(effects, EffectKind::kQuadraticDrive, 0);
  const double delay = SumParam(effects, EffectKind::kDelay, 0);
  const auto creeps = Active(effects, EffectKind::kCreep);
  const bool filters = !lowpasses.empty() || !creeps.empty();
  if (!filters) {
    // Pointwise: exact at every time.
    for (size_t j = 0; j < t.size(); ++j) {
      const double te = t[j] - delay;
      if (te <= 0) continue;
      const double u = V * std::sin(om * te);
      out[j] = u + c2 * u * u;
    }
    return out;
  }
  // Internal grid 4 x finer than the spacing of t (its smallest step), from 0 to the last time.
  double hmin = t.back() > 0 ? t.back() : 1.0;
  for (size_t j = 1; j < t.size(); ++j) hmin = std::min(hmin, t[j] - t[j - 1]);
  const double h = hmin / 4;
  const long n = static_cast<long>(std::ceil(std::max(t.back(), 0.0) / h)) + 2;
  std::vector<double> s(n);
  // Low-passes in series, then the quadratic term, then the creep relaxations in series.
  std::vector<FohFilter> lf, cf;
  for (const Effect* e : lowpasses) lf.emplace_back(e->params[0], 1.0, h);
  for (const Effect* e : creeps) cf.emplace_back(e->params[1], e->params[0], h);
  std::vector<double> x_l(lf.size(), 0.0), in_l(lf.size(), 0.0), x_c(cf.size(), 0.0), in_c(cf.size(), 0.0);
  for (long j = 0; j < n; ++j) {
    double v = V * std::sin(om * (j * h));
    for (size_t i = 0; i < lf.size(); ++i) {
      if (j > 0) x_l[i] = lf[i].a * x_l[i] + lf[i].b0 * in_l[i] + lf[i].b1 * v;
      in_l[i] = v;
      v = x_l[i];
    }
    v += c2 * v * v;
    for (size_t i = 0; i < cf.size(); ++i) {  // in series, as the CVODE extensions
      if (j > 0) x_c[i] = cf[i].a * x_c[i] + cf[i].b0 * in_c[i] + cf[i].b1 * v;
      in_c[i] = v;
      v += x_c[i];
    }
    s[j] = v;
  }
  for (size_t j = 0; j < t.size(); ++j) {
    const double te = t[j] - delay;
    if (te <= 0) continue;
    const double r = te / h;
    const long i = std::min(static_cast<long>(r), n - 2);
    const double w = r - i;
    out[j] = (1 - w) * s[i] + w * s[i + 1];
  }
  return out;
}

std::vector<std::unique_ptr<BimorphExtension>> MakeExtensions(std::span<const Effect> effects) {
  std::vector<std::unique_ptr<BimorphExtension>> ext;
  for (const Effect* e : Active(effects, EffectKind::kDriverLowpass))
    ext.push_back(std::make_unique<LowpassExtension>(e->params[0]));
  for (const Effect* e : Active(effects, EffectKind::kQuadraticDrive))
    ext.push_back(std::make_unique<QuadraticExtension>(e->params[0]));
  for (const Effect* e : Active(effects, EffectKind::kCreep))
    ext.push_back(std::make_unique<CreepExtension>(e->params[0], e->params[1]));
  for (const Effect* e : Active(effects, EffectKind::kHingeFriction))
    ext.push_back(std::make_unique<DahlHingeExtension>(e->params[0], e->params[1]));
  for (const Effect* e : Active(effects, EffectKind::kCubicStiffening))
    ext.push_back(std::make_unique<CubicExtension>(e->params[0]));
  return ext;
}

EffectSimulator::EffectSimulator(const BimorphPlant& plant) : plant_(&plant), modal_(plant) {}

SimulationSummary EffectSimulator::SimulateAngle(const BimorphParams& params, std::span<const Effect> effects,
                                                 const Sinusoid& drive, std::span<double> angle_deg,
                                                 const EffectSimOptions& options,
                                                 std::span<double> theta_deg) const {
  const auto start = std::chrono::steady_clock::now();
  SimulationSummary summary;
  auto fail = [&](SimStatus st, std::string msg) {
    summary.status = st;
    summary.message = std::move(msg);
    summary.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return summary;
  };
  if (auto s = params.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  if (auto s = drive.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  if (auto s = options.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  for (const Effect& e : effects)
    if (auto s = e.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  const size_t n_out = static_cast<size_t>(drive.NumSamples());
  if (angle_deg.size() != n_out || (!theta_deg.empty() && theta_deg.size() != n_out))
    return fail(SimStatus::kInvalidInput, "output buffers must have " + std::to_string(n_out) + " samples");
  if (!params.HysteresisBounded()) return fail(SimStatus::kUnboundedHysteresis, "Bouc-Wen loop unbounded");

  bool any_drive = false;
  for (const Effect& e : effects) {
    if (e.IsIdentity()) continue;
    any_drive = any_drive || GetEffectInfo(e.kind).stage == EffectStage::kDrive;
  }
  const double drift = SumParam(effects, EffectKind::kOutputDrift, 0);
  const double delay = SumParam(effects, EffectKind::kDelay, 0);
  const double fs = drive.sample_rate_hz;
  // The linear angle θ on the record's grid goes into `theta` (caller's buffer or scratch).
  thread_local std::vector<double> theta_buf;
  std::span<double> theta = theta_deg;
  if (theta.empty()) {
    theta_buf.resize(n_out);
    theta = theta_buf;
  }
  BimorphParams lin = params;  // identity backlash: the simulators' angle output is θ
  lin.a1 = lin.a2 = 0.0;
  lin.b1 = 1e9;
  lin.b2 = -1e9;

  if (options.force_cvode || NeedsCvode(effects)) {
    auto ext = MakeExtensions(effects);
    std::vector<const BimorphExtension*> ptrs;
    for (auto& e : ext) ptrs.push_back(e.get());
    const DriveSignal sig = drive;
    BimorphOde ode(*plant_, lin, sig, ptrs);
    // Output times shifted by the delay (exact for a time-invariant plant from rest).
    std::vector<double> t_out;
    size_t first = 0;
    for (size_t k = 0; k < n_out; ++k) {
      const double te = static_cast<double>(k) / fs - delay;
      if (te < 0) {
        ++first;
        continue;
      }
      t_out.push_back(te);
    }
    std::fill(theta.begin(), theta.begin() + first, 0.0);
    if (!t_out.empty()) {
      CvodeOptions co;
      co.method = OdeMethod::kBdf;
      co.iteration = NonlinearIteration::kNewton;
      co.linear_solver = LinearSolverKind::kDense;
      co.rtol = options.rtol;
      co.atol = options.atol;
      co.max_steps = options.max_steps;
      co.breakpoints = ode.Breakpoints();
      std::vector<double> y0 = ode.InitialState();
      const OdeSolution sol = IntegrateCvode(ode, 0.0, y0, t_out, co);
      summary = sol.summary;
      if (!summary.ok()) return fail(summary.status, summary.message);
      for (size_t k = 0; k < t_out.size(); ++k)
        theta[first + k] = plant_->TipToDegrees(sol.at(k, ode.tip_index()));
    }
  } else if (any_drive) {
    SampledScratch& sc = Scratch();
    const int m = options.oversample;
    const size_t n_fine = (n_out - 1) * m + 1;
    sc.t_fine.resize(n_fine);
    for (size_t j = 0; j < n_fine; ++j) sc.t_fine[j] = static_cast<double>(j) / (fs * m);
    SampledSignal& sig = std::get<SampledSignal>(sc.signal);
    sig.t = sc.t_fine;
    sig.u = ShapedDrive(effects, drive, sc.t_fine);
    sc.theta_fine.resize(n_fine);
    const SimulationSummary s = modal_.SimulateAngle(lin, sc.signal, sc.theta_fine, sc.ws);
    summary = s;
    if (!summary.ok()) return fail(summary.status, summary.message);
    for (size_t k = 0; k < n_out; ++k) theta[k] = sc.theta_fine[k * m];
  } else {
    SampledScratch& sc = Scratch();
    const SimulationSummary s = modal_.SimulateAngle(lin, drive, theta, sc.ws);
    summary = s;
    if (!summary.ok()) return fail(summary.status, summary.message);
  }
  for (size_t k = 0; k < n_out; ++k)
    if (!std::isfinite(theta[k])) return fail(SimStatus::kNonFinite, "non-finite fin angle at sample " + std::to_string(k));
  ApplyBacklash(params.backlash(), theta, angle_deg);
  if (drift != 0.0)
    for (size_t k = 0; k < n_out; ++k) angle_deg[k] += drift * (static_cast<double>(k) / fs);
  summary.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace pz::model
