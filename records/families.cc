#include "records/families.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <optional>

#include "io/csv.h"
#include "model/bimorph.h"
#include "model/bw_oscillator.h"
#include "model/duhem.h"
#include "model/kernels/pzk.h"
#include "model/modal_simulator.h"
#include "model/prandtl_ishlinskii.h"
#include "model/saturation.h"
#include "model/stack_models.h"

namespace pz::records {
namespace {

constexpr double kTwoPi = 2 * std::numbers::pi;

template <class F>
std::unique_ptr<Family> Make(const DataScale& scale, const FamilyOptions& options) {
  return std::make_unique<F>(scale, options);
}
KernelShape Substeps(const FamilyOptions& o, std::span<const double>) {
  return KernelSizes(o.substeps);
}
KernelShape Plays(const FamilyOptions& o, std::span<const double>) {
  return KernelSizes(o.pi_operators);
}
KernelShape NoShape(const FamilyOptions&, std::span<const double>) { return {}; }

class StackBoucWenFamily final : public Family {
 public:
  StackBoucWenFamily(const DataScale& s, const FamilyOptions& o)
      : sim_{.substeps = o.substeps},
        start_(o.initial_state),
        range_(2 * s.u_half),
        u_min_(s.u_min),
        u_max_(s.u_max) {
    ThrowIfError(sim_.Validate());
    const double a = s.u_half, g = s.gain;
    params_ = {{"alpha", "-", 0.01, 1.5, false},
               {"beta", "1/V", 0.02 / a, 50 / a, true},
               {"gamma", "1/V", -50 / a, 50 / a, false},
               {"d", "y/V", 0.3 * g, 10 * g, true},
               {"fc_Hz", "Hz", std::min(2 * s.f_dom, 0.04 * s.fs), 0.45 * s.fs, true}};
  }
  std::string name() const override { return kStackBoucWenFamily.name; }
  std::string title() const override { return "Bouc–Wen stack with driver filter"; }
  std::string equation() const override {
    return "y = LPF_fc[d (u - h)], dh/dt = alpha du/dt - beta |du/dt| h - gamma du/dt |h|";
  }
  const std::vector<ParamInfo>& params() const override { return params_; }
  void Simulate(std::span<const double> p, std::span<const double> u, double dt,
                std::span<double> y) const override {
    const model::StackBoucWenParams b = model::BoucWenFromVector(p);
    model::StackSimOptions sim = sim_;
    sim.rest_state =
        model::StackRestState(b, range_, model::ResolveInitialState(start_, u[0], u_min_, u_max_));
    model::SimulateStackBoucWen(b, u, dt, y, sim);
  }
  std::vector<std::string> excluded_effects() const override { return {"driver-lowpass"}; }
  model::InitialState initial_state() const override { return start_; }
  std::vector<double> CheckNominal() const override { return {0.3, 0.018, 0.006, 0.12, 40}; }

 private:
  model::StackSimOptions sim_;
  model::InitialState start_;
  double range_;          ///< the rise and fall of the rest state: the data's full drive range
  double u_min_, u_max_;  ///< the data's drive range (kAuto)
  std::vector<ParamInfo> params_;
};

}  // namespace

const FamilyDef kStackBoucWenFamily = {
    .name = "stack-bouc-wen",
    .takes_initial_state = true,
    .linear = false,
    .auto_grid = true,
    .kernel = pzk::PZK_STACK_BOUC_WEN,
    .make = Make<StackBoucWenFamily>,
    .kernel_shape = Substeps,
};

namespace {

class BacklashLikeFamily final : public Family {
 public:
  // kAuto is centred for this family (docs/records.md "The initial state at rest": started
  // descended at a rest at the bottom of the range, its fits on real-like stacks predict the minor
  // loops worse, the reversal records by up to 1.8 ×); descended and ascended are taken as given.
  BacklashLikeFamily(const DataScale& s, const FamilyOptions& o)
      : start_(o.initial_state == model::InitialState::kAuto ? model::InitialState::kCentred
                                                             : o.initial_state),
        range_(2 * s.u_half),
        u_min_(s.u_min),
        u_max_(s.u_max) {
    const double a = s.u_half, g = s.gain;
    params_ = {{"alpha", "1/V", 0.01 / a, 100 / a, true},
               {"c", "y/V", 0.3 * g, 3 * g, true},
               {"B1", "y/V", -3 * g, 5 * g, false}};
  }
  std::string name() const override { return kBacklashLikeFamily.name; }
  std::string title() const override { return "backlash-like (Coleman–Hodgdon)"; }
  std::string equation() const override { return "dy/dt = alpha |du/dt| (c u - y) + B1 du/dt"; }
  const std::vector<ParamInfo>& params() const override { return params_; }
  void Simulate(std::span<const double> p, std::span<const double> u, double,
                std::span<double> y) const override {
    const model::BacklashLikeParams b = model::BacklashLikeFromVector(p);
    model::SimulateBacklashLike(
        b, u, y,
        model::StackRestState(b, range_, model::ResolveInitialState(start_, u[0], u_min_, u_max_)));
  }
  model::InitialState initial_state() const override { return start_; }
  std::vector<double> CheckNominal() const override { return {0.02, 0.1, 0.05}; }

 private:
  model::InitialState start_;
  double range_, u_min_, u_max_;
  std::vector<ParamInfo> params_;
};

}  // namespace

const FamilyDef kBacklashLikeFamily = {
    .name = "backlash-like",
    .takes_initial_state = true,
    .linear = false,
    .auto_grid = true,
    .kernel = pzk::PZK_BACKLASH_LIKE,
    .make = Make<BacklashLikeFamily>,
    .kernel_shape = NoShape,
};

namespace {

class DuhemFamily final : public Family {
 public:
  DuhemFamily(const DataScale& s, const FamilyOptions&) {
    const double a = s.u_half, g = s.gain;
    params_ = {{"alpha", "1/V", 0.01 / a, 100 / a, true},
               {"c", "y/V", 0.3 * g, 3 * g, true},
               {"c3", "y/V^3", -0.5 * g / (a * a), 0.5 * g / (a * a), false},
               {"b", "y/V", -3 * g, 5 * g, false},
               {"lambda", "1/s", 0, 10 * kTwoPi * s.f_dom, false}};
  }
  std::string name() const override { return kDuhemFamily.name; }
  std::string title() const override { return "Duhem-type (cubic curve, relaxation)"; }
  std::string equation() const override {
    return "dy/dt = alpha |du/dt| (f(u) - y) + b du/dt + lambda (f(u) - y), f(u) = c u + c3 u^3";
  }
  const std::vector<ParamInfo>& params() const override { return params_; }
  void Simulate(std::span<const double> p, std::span<const double> u, double dt,
                std::span<double> y) const override {
    model::SimulateDuhem(model::DuhemFromVector(p), u, dt, y);
  }
  std::vector<std::string> excluded_effects() const override { return {"creep"}; }
  std::vector<double> CheckNominal() const override { return {0.02, 0.1, -2e-6, 0.05, 2.0}; }

 private:
  std::vector<ParamInfo> params_;
};

}  // namespace

const FamilyDef kDuhemFamily = {
    .name = "duhem",
    .takes_initial_state = false,
    .linear = false,
    .auto_grid = true,
    .kernel = pzk::PZK_DUHEM,
    .make = Make<DuhemFamily>,
    .kernel_shape = NoShape,
};

namespace {

class PrandtlIshlinskiiFamily final : public Family {
 public:
  PrandtlIshlinskiiFamily(const DataScale& s, const FamilyOptions& o)
      : thresholds_(model::PiThresholds(o.pi_operators, s.u_half)),
        start_(o.initial_state),
        u_min_(s.u_min),
        u_max_(s.u_max) {}
  std::string name() const override { return kPrandtlIshlinskiiFamily.name; }
  std::string title() const override { return "Prandtl–Ishlinskii operator"; }
  std::string equation() const override { return "y = w0 u + sum_i w_i play_{r_i}[u], w >= 0"; }
  const std::vector<ParamInfo>& params() const override { return params_; }
  bool linear() const override { return true; }
  size_t regressors() const override { return thresholds_.size() + 1; }
  void Simulate(std::span<const double> p, std::span<const double> u, double,
                std::span<double> y) const override {
    if (p.size() != regressors()) {
      throw InputError("prandtl-ishlinskii: " + std::to_string(p.size()) + " weights given, " +
                       std::to_string(regressors()) + " expected");
    }
    model::PiOperator op{p[0], thresholds_, std::vector<double>(p.begin() + 1, p.end()), Start(u)};
    model::ApplyPi(op, u, y);
  }
  void Regressors(std::span<const double> u, std::span<double> out) const override {
    const size_t n = thresholds_.size(), m = n + 1;
    if (out.size() != u.size() * m) throw InputError("prandtl-ishlinskii: regressor size mismatch");
    std::vector<double> plays(u.size() * n);
    model::PiPlayOutputs(thresholds_, u, plays, Start(u));
    for (size_t k = 0; k < u.size(); ++k) {
      out[k * m] = u[k];
      std::copy_n(plays.data() + k * n, n, out.data() + k * m + 1);
    }
  }
  std::vector<std::string> weight_names() const override {
    std::vector<std::string> names = {"w0"};
    for (size_t i = 0; i < thresholds_.size(); ++i) {
      names.push_back("w" + std::to_string(i + 1) + "(r=" + io::FormatNumber(thresholds_[i]) + ")");
    }
    return names;
  }
  std::vector<std::string> excluded_effects() const override { return {"friction"}; }
  model::InitialState initial_state() const override { return start_; }
  const std::vector<double>& thresholds() const { return thresholds_; }

 private:
  model::InitialState Start(std::span<const double> u) const {
    return u.empty() ? start_ : model::ResolveInitialState(start_, u[0], u_min_, u_max_);
  }
  std::vector<double> thresholds_;
  model::InitialState start_;
  double u_min_, u_max_;
  std::vector<ParamInfo> params_;
};

}  // namespace

const FamilyDef kPrandtlIshlinskiiFamily = {
    .name = "prandtl-ishlinskii",
    .takes_initial_state = true,
    .linear = true,
    .auto_grid = true,
    .kernel = pzk::PZK_PRANDTL_ISHLINSKII,
    .make = Make<PrandtlIshlinskiiFamily>,
    .kernel_shape = Plays,
};

namespace {

class BwOscillatorFamily final : public Family {
 public:
  BwOscillatorFamily(const DataScale& s, const FamilyOptions& o)
      : osc_(o.oscillator),
        substeps_(o.oscillator.rk4_steps > 0 ? o.oscillator.rk4_steps : 2 * o.substeps) {
    if (substeps_ < 1 || substeps_ > 1000)
      throw InputError(FieldError("bw-oscillator: rk4_steps", substeps_, "must be 1 … 1000"));
    if (osc_.physical) {
      const auto& names = model::BwIdentifiableNames();
      params_ = {{names[0], "u s^2/y", 0.2, 20, true}, {names[1], "u s/y", 0.1, 1e3, true},
                 {names[2], "u/y", 1e3, 1e6, true},    {names[3], "u/y", 1e3, 1e6, true},
                 {names[4], "1/y", 1, 1e5, true},      {names[5], "1/y", -1e4, 1e4, false}};
      return;
    }
    const double g = s.gain, y = s.y_half;
    const double fn_lo = std::min(3 * s.f_dom, 0.05 * s.fs),
                 fn_hi = std::max(fn_lo * 2, 0.3 * s.fs);
    params_ = {{"K", "y/V", 0.3 * g, 3 * g, true},
               {"fn_Hz", "Hz", fn_lo, fn_hi, true},
               {"zeta", "-", 0.02, 3, true},
               {"share", "-", 0.0, 0.95, false},
               {"beta_gamma", "1/y", 0.01 / y, 100 / y, true},
               {"beta_delta", "1/y", -100 / y, 100 / y, false}};
  }
  std::string name() const override { return kBwOscillatorFamily.name; }
  std::string title() const override { return "Bouc–Wen hysteretic oscillator"; }
  std::string equation() const override {
    if (osc_.physical)
      return "m y'' + c y' + k y + z = u, z' = alpha y' - beta_gamma |y'| z - beta_delta y' |z|";
    return "m y'' + c y' + k y + z = u, z' = alpha y' - beta_gamma |y'| z - beta_delta y' |z| (k = "
           "(1-share)/K, "
           "alpha = share/K, m = (k+alpha)/(2 pi fn)^2, c = 2 zeta sqrt((k+alpha) m))";
  }
  const std::vector<ParamInfo>& params() const override { return params_; }
  void Simulate(std::span<const double> p, std::span<const double> u, double dt,
                std::span<double> y) const override {
    SimulatePrepared(nullptr, p, u, dt, y);
  }
  // The input table (model::BwInput: the drive at every half RK4 step) depends on the drive alone.
  struct Input final : Prepared {
    model::BwInput input;
  };
  std::shared_ptr<const Prepared> Prepare(std::span<const double> u, double dt) const override {
    auto in = std::make_shared<Input>();
    in->input = model::BwInput(u, InputOptions(dt));
    return in;
  }
  void SimulatePrepared(const Prepared* prepared, std::span<const double> p,
                        std::span<const double> u, double dt, std::span<double> y) const override {
    if (p.size() != 6) throw InputError("bw-oscillator: 6 parameters expected");
    const model::BwParams b = osc_.physical ? model::BwFromIdentifiable(p) : Scaled(p);
    if (!b.Validate().ok()) return Nan(y);  // outside any box (m <= 0, a non-finite value)
    // Unprepared (a drive effect's drive): the table in this thread's storage, made anew.
    thread_local model::BwInput own;
    const auto* in = dynamic_cast<const Input*>(prepared);
    if (!in) own.Assign(u, InputOptions(dt));
    const model::BwInput& input = in ? in->input : own;
    model::BwState state = Rest(b, u[0]);
    const Status st = model::SimulateBw(b, input, y, &state);
    if (!st.ok()) Nan(y);
  }
  // Four parameter sets side by side (model::SimulateBwMany): the RK4 loop is a chain of dependent
  // operations, and two chains of two-lane vector operations in one thread take about the time of
  // one. On the prepared drive, or (a model with drive effects) each on its own.
  int lanes() const override { return 4; }
  void SimulatePreparedMany(const Prepared* prepared, std::span<const std::span<const double>> ps,
                            std::span<const double> u, double dt,
                            std::span<const std::span<double>> ys) const override {
    const auto* in = dynamic_cast<const Input*>(prepared);
    std::vector<model::BwParams> b;
    if (!in || !ManyParams(ps, b)) return Family::SimulatePreparedMany(prepared, ps, u, dt, ys);
    const std::vector<const model::BwInput*> inputs(ps.size(), &in->input);
    Many(b, inputs, std::vector<double>(ps.size(), u[0]), ys);
  }
  void SimulateMany(std::span<const std::span<const double>> ps,
                    std::span<const std::span<const double>> us, double dt,
                    std::span<const std::span<double>> ys) const override {
    std::vector<model::BwParams> b;
    bool many = us.size() == ps.size();
    for (const std::span<const double> u : us) many = many && u.size() == us[0].size();
    if (!many || !ManyParams(ps, b)) return Family::SimulateMany(ps, us, dt, ys);
    thread_local std::vector<model::BwInput> in;  // each lane's table, in this thread's storage
    if (in.size() < us.size()) in.resize(us.size());
    std::vector<const model::BwInput*> inputs(us.size());
    std::vector<double> u0(us.size());
    for (size_t l = 0; l < us.size(); ++l) {
      in[l].Assign(us[l], InputOptions(dt));
      inputs[l] = &in[l];
      u0[l] = us[l][0];
    }
    Many(b, inputs, u0, ys);
  }

 private:
  static void Nan(std::span<double> y) {
    std::fill(y.begin(), y.end(), std::numeric_limits<double>::quiet_NaN());
  }
  // b[l] of two or more parameter sets, false unless every one is valid (SimulatePrepared's NaN:
  // each alone).
  bool ManyParams(std::span<const std::span<const double>> ps,
                  std::vector<model::BwParams>& b) const {
    if (ps.size() < 2) return false;
    b.resize(ps.size());
    for (size_t l = 0; l < ps.size(); ++l) {
      if (ps[l].size() != 6) throw InputError("bw-oscillator: 6 parameters expected");
      b[l] = osc_.physical ? model::BwFromIdentifiable(ps[l]) : Scaled(ps[l]);
      if (!b[l].Validate().ok()) return false;
    }
    return true;
  }
  // SimulatePrepared's simulation for every lane at once, each from rest at its drive's u_0.
  void Many(const std::vector<model::BwParams>& b, const std::vector<const model::BwInput*>& inputs,
            const std::vector<double>& u0, std::span<const std::span<double>> ys) const {
    std::vector<model::BwState> states(b.size());
    for (size_t l = 0; l < b.size(); ++l) states[l] = Rest(b[l], u0[l]);
    const std::vector<Status> st = model::SimulateBwMany(b, inputs, ys, states);
    for (size_t l = 0; l < b.size(); ++l)
      if (!st[l].ok()) Nan(ys[l]);
  }
  // At rest at u_0: k y = u_0 with no hysteretic force (a virgin state); or the zero state.
  model::BwState Rest(const model::BwParams& b, double u0) const {
    return {!osc_.from_zero_state && b.k != 0 ? u0 / b.k : 0.0, 0, 0};
  }
  model::BwInputOptions InputOptions(double dt) const {
    model::BwInputOptions io;
    io.sample_rate_hz = 1.0 / dt;
    io.substeps = substeps_;
    io.interpolation = osc_.interpolation;
    io.period_samples = osc_.period_samples;
    return io;
  }
  static model::BwParams Scaled(std::span<const double> p) {
    const double ktot = 1.0 / p[0], wn = kTwoPi * p[1];
    model::BwParams b;
    b.k = (1 - p[3]) * ktot;
    b.alpha = p[3] * ktot;
    b.m = ktot / (wn * wn);
    b.c = 2 * p[2] * std::sqrt(ktot * b.m);
    b.beta = 1;
    b.gamma = p[4];
    b.delta = p[5];
    b.nu = 1;
    return b;
  }
  OscillatorOptions osc_;
  int substeps_;
  std::vector<ParamInfo> params_;
};

}  // namespace

// RK4 steps per sample: OscillatorOptions' default of the fit (2 × substeps).
const FamilyDef kBwOscillatorFamily = {
    .name = "bw-oscillator",
    .takes_initial_state = false,
    .linear = false,
    .auto_grid = true,
    .kernel = pzk::PZK_BW_OSCILLATOR,
    .make = Make<BwOscillatorFamily>,
    .kernel_shape = [](const FamilyOptions& o,
                       std::span<const double>) { return KernelSizes(2 * o.substeps); },
};

namespace {

class BimorphFinFamily final : public Family {
 public:
  BimorphFinFamily(const DataScale& s, const FamilyOptions& o)
      : geometry_(o.geometry),
        plant_(o.geometry),
        bench_(o.bench_form),
        sim_(plant_),
        sim_options_(o.fin_sim) {
    if (bench_) {
      ThrowIfError(o.fin_sim.Validate());
      // The fin bench's box and typical scales (the former fin engine's, issue 38), in volts and
      // degrees: γ searched as g = γ/β ∈ [−0.98, 1] (β + γ > 0 with margin, β − γ ≥ 0).
      params_ = {{"mu", "1/s", 0.0, 400.0, false},    {"delta", "s", 0.0, 1.0, false},
                 {"alpha", "N/V", 0.0, 0.02, false},  {"beta", "1/V", 1e-5, 0.05, true},
                 {"gamma", "1/V", -0.98, 1.0, false}, {"a1", "deg", 0.0, 1.0, false},
                 {"a2", "deg", 0.0, 1.0, false}};
      forms_ = {{-1, 50.0}, {-1, 0.05}, {-1, 1e-3}, {-1, 2e-3}, {3, 2e-3}, {-1, 0.05}, {-1, 0.05}};
      return;
    }
    // The spec's ranges (model/network.h) are for drives up to 375 V; α scales with 1/drive.
    const double a = 375.0 / s.u_half, g = s.y_half;  // gain: output units per degree
    const double lp = o.geometry.active_length_m, le = o.geometry.tip_length_m;
    params_ = {{"mu", "1/s", 0, 300, false},
               {"delta", "s", 1e-5, 1, true},
               {"alpha", "N/V", 1e-5 * a, 0.02 * a, true},
               {"beta", "1/V", 0, 0.02 * a, false},
               {"gamma", "1/V", -0.02 * a, 0.02 * a, false},
               {"a1", "deg", 0, 2, false},
               {"a2", "deg", 0, 2, false},
               {"b1", "deg", 0.05, 60, true},
               {"b2_abs", "deg", 0.05, 60, true},
               {"gain", "y/deg", 0.01 * g, 100 * g, true},
               // The beam's geometry: the active (MFC) and passive tip lengths set the modes.
               {"active_length", "m", 0.5 * lp, 2 * lp, true}};
    if (le > 0 && o.geometry.n_tip > 0)
      params_.push_back({"tip_length", "m", 0.25 * le, 3 * le, true});
  }
  std::string name() const override { return kBimorphFinFamily.name; }
  std::string title() const override {
    return "bimorph fin (FE beam, Rayleigh damping, Bouc–Wen, backlash)";
  }
  std::string equation() const override {
    if (bench_)
      return "M q'' + C q' + K q = B u - e* z, z' = alpha u' - beta |u'| z - gamma u' |z|, "
             "y = Backlash_{a1, a2, b1, b2}(atan(w_tip/L)) [deg], b1 b2 per record";
    return "M(L_p, L_e) q'' + C q' + K(L_p, L_e) q = B u - e* z, z' = alpha u' - beta |u'| z - "
           "gamma u' |z|, "
           "y = gain * Backlash(atan(w_tip/L))";
  }
  /// The step's modal data for the fitted geometry (p[10] = L_p, p[11] = L_e when fitted):
  /// {1/L, omega_i^2, tip_i g_u,i, tip_i g_z,i} of the modes the library simulates, their number
  /// in n. The library's FE assembly and eigen-decomposition (model::BimorphPlant,
  /// model::ModalSimulator), as Simulate does; the kernel discretises from these.
  static KernelShape Kernel(const FamilyOptions& o, std::span<const double> p) {
    if (o.bench_form)
      throw InputError(
          "model.family_options: bimorph-fin's bench form (per-record saturations, "
          "a stated sinusoid) has no step for a controller: fit the family itself");
    model::BeamGeometry geo = o.geometry;
    geo.active_length_m = p[10];
    const bool tip = p.size() > 11;
    if (tip) geo.tip_length_m = p[11];
    if (Status s = geo.Validate(); !s.ok()) {
      throw InputError("model.params[" +
                       std::string(tip ? "active_length, tip_length" : "active_length") +
                       "]: " + s.message());
    }
    const model::BimorphParams b{p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], -p[8]};
    if (Status s = b.Validate(); !s.ok())
      throw InputError("model.params (bimorph-fin): " + s.message());
    if (!b.HysteresisBounded()) {
      throw InputError("model.params[alpha, beta, gamma] = [" + io::FormatNumber(p[2]) + ", " +
                       io::FormatNumber(p[3]) + ", " + io::FormatNumber(p[4]) +
                       "]: the Bouc-Wen loop is unbounded (needs alpha = 0, or beta + gamma > 0 "
                       "and beta - gamma >= 0)");
    }
    const model::BimorphPlant plant(geo);
    const model::ModalSimulator sim(plant);
    KernelShape shape = KernelSizes(sim.num_modes());
    shape.data = {1.0 / sim.length_m()};
    for (auto part : {sim.omega2(), sim.tip_gain_u(), sim.tip_gain_z()})
      shape.data.insert(shape.data.end(), part.begin(), part.end());
    return shape;
  }
  const std::vector<ParamInfo>& params() const override { return params_; }
  std::vector<SearchForm> search_forms() const override { return forms_; }
  void CheckTraining(const std::vector<const io::Record*>& train) const override {
    if (!bench_) return;
    for (const io::Record* r : train) {
      if (!r->sinusoid.stated())
        throw InputError(r->Label() +
                         ": bimorph-fin's bench form needs each record's stated sinusoid (a fin "
                         "bench read as records by io::RecordsFromCaseSet)");
      try {
        model::SaturationFromExtremes(r->y);
      } catch (const InputError& e) {
        throw InputError(r->Label() + ": cannot fit the saturations b1, b2: " + e.what());
      }
    }
  }
  bool simulates_records() const override { return bench_; }
  bool sums_errors() const override { return bench_; }
  std::vector<ParamInfo> EffectBox(model::EffectKind e,
                                   std::vector<SearchForm>* forms) const override {
    if (!bench_) return Family::EffectBox(e, forms);
    if (e.none() || !IsFinEffect(e))
      throw InputError("bimorph-fin's bench form: effect '" + std::string(e.name()) +
                       "': " + FinEffectError(e.name()));
    std::vector<ParamInfo> box;
    for (const EffectParamInfo& q : GetFinEffectInfo(e).params) {
      box.push_back({q.name, q.unit, q.lower, q.upper, q.log_scale});
      if (forms) forms->push_back({-1, q.scale});
    }
    return box;
  }
  void SimulateRecord(const io::Record& r, std::span<const double> p,
                      std::span<const model::EffectKind> effects, std::span<const double> ep,
                      size_t end, std::span<double> y) const override {
    if (!bench_) return Family::SimulateRecord(r, p, effects, ep, end, y);
    const io::Record::StatedSinusoid& st = r.sinusoid;
    if (!st.stated())
      throw InputError(r.Label() +
                       ": bimorph-fin's bench form simulates a bench case's stated sinusoid; the "
                       "record states none (a fin bench read as records by io::RecordsFromCaseSet "
                       "has it)");
    const model::Sinusoid drive{st.amplitude_v, st.frequency_hz, st.cycles, st.sample_rate_hz};
    const size_t n = static_cast<size_t>(std::max(0, drive.NumSamples()));
    if (n != r.size() || end > n || y.size() < end || p.size() != params_.size())
      throw InputError(r.Label() + ": its stated sinusoid has " + std::to_string(n) +
                       " samples, the record " + std::to_string(r.size()));
    model::SaturationPair sat;
    try {  // the fin's rule: b1, b2 the record's measured extremes
      sat = model::SaturationFromExtremes(r.y);
    } catch (const InputError& e) {
      throw InputError(r.Label() + ": cannot fit the saturations b1, b2: " + e.what());
    }
    const model::BimorphParams b{p[0], p[1], p[2], p[3], p[4], p[5], p[6], sat.b1, sat.b2};
    thread_local std::vector<Effect> fx;
    thread_local std::vector<double> angle;
    fx.resize(effects.size());
    size_t at = 0;
    for (size_t i = 0; i < effects.size(); ++i) {
      const size_t m = GetFinEffectInfo(effects[i]).params.size();
      if (at + m > ep.size()) throw InputError(r.Label() + ": too few effect parameters");
      fx[i].kind = effects[i];
      fx[i].params.assign(ep.begin() + static_cast<std::ptrdiff_t>(at),
                          ep.begin() + static_cast<std::ptrdiff_t>(at + m));
      at += m;
    }
    angle.resize(n);
    if (!sim_.SimulateAngle(b, fx, drive, angle, sim_options_).ok()) {
      std::fill(y.begin(), y.begin() + static_cast<std::ptrdiff_t>(end),
                std::numeric_limits<double>::quiet_NaN());
      return;
    }
    std::copy(angle.begin(), angle.begin() + static_cast<std::ptrdiff_t>(end), y.begin());
  }
  void Simulate(std::span<const double> p, std::span<const double> u, double dt,
                std::span<double> y) const override {
    if (bench_)
      throw InputError(
          "bimorph-fin's bench form simulates records with a stated sinusoid "
          "(RecordModel::Simulate), not a bare drive");
    if (p.size() != params_.size())
      throw InputError("bimorph-fin: " + std::to_string(params_.size()) + " parameters expected");
    model::BimorphParams b{p[0], p[1], p[2], p[3], p[4], p[5], p[6], p[7], -p[8]};
    // The drive, the modal workspace and the angle are kept per thread: a search's evaluations then
    // allocate nothing of the record's size (fresh pages of that size cost more than the modes).
    thread_local model::DriveSignal drive = model::SampledSignal{};
    thread_local model::ModalWorkspace ws;
    thread_local std::vector<double> angle;
    auto& sig = std::get<model::SampledSignal>(drive);
    thread_local double grid_dt = 0;  // the time grid depends on the size and the step alone
    if (sig.t.size() != u.size() || grid_dt != dt) {
      sig.t.resize(u.size());
      for (size_t k = 0; k < u.size(); ++k) sig.t[k] = static_cast<double>(k) * dt;
      grid_dt = dt;
    }
    sig.u.assign(u.begin(), u.end());
    angle.resize(u.size());
    model::BeamGeometry geo = geometry_;
    geo.active_length_m = p[10];
    if (params_.size() > 11) geo.tip_length_m = p[11];
    auto nan = [&] { std::fill(y.begin(), y.end(), std::numeric_limits<double>::quiet_NaN()); };
    if (!geo.Validate().ok()) return nan();
    // The nominal geometry's plant is assembled once; another geometry costs one FE assembly and
    // eigen-decomposition of 2 (n_active + n_tip) DOFs, small against the simulation.
    const bool nominal = geo.active_length_m == geometry_.active_length_m &&
                         geo.tip_length_m == geometry_.tip_length_m;
    std::optional<model::BimorphPlant> other;
    if (!nominal) other.emplace(geo);
    // The fast path's angle alone (model::Simulate's modal path without the full trace): the same
    // values; a failure (invalid or unbounded parameters, a non-finite angle) gives NaN.
    const model::ModalSimulator sim(nominal ? plant_ : *other);
    if (!sim.SimulateAngle(b, drive, angle, ws).ok()) return nan();
    for (size_t k = 0; k < u.size(); ++k) y[k] = p[9] * angle[k];
  }

 private:
  model::BeamGeometry geometry_;
  model::BimorphPlant plant_;
  bool bench_ = false;
  EffectSimulator sim_;  ///< on plant_ (bench form)
  EffectSimOptions sim_options_;
  std::vector<ParamInfo> params_;
  std::vector<SearchForm> forms_;
};

}  // namespace

// Not in the `--family auto` grid: the fin's bench has its own geometry and protocol.
const FamilyDef kBimorphFinFamily = {
    .name = "bimorph-fin",
    .takes_initial_state = false,
    .linear = false,
    .auto_grid = false,
    .kernel = pzk::PZK_BIMORPH_FIN,
    .make = Make<BimorphFinFamily>,
    .kernel_shape = BimorphFinFamily::Kernel,
};

void Family::SimulateRecord(const io::Record& r, std::span<const double>,
                            std::span<const model::EffectKind>, std::span<const double>, size_t,
                            std::span<double>) const {
  throw InputError(name() + " simulates a drive, not a record (" + r.name + ")");
}

std::vector<ParamInfo> Family::EffectBox(model::EffectKind e, std::vector<SearchForm>*) const {
  throw InputError("effect '" + std::string(e.name()) + "' is not an effect " + name() +
                   " simulates itself");
}

bool Family::AddNormalEquations(const io::Record&, size_t, std::span<const double>, int,
                                NormalEquationsBuilder&) const {
  return false;
}

void Family::Regressors(std::span<const double>, std::span<double>) const {
  throw InputError(name() + " is not linear in its parameters");
}

std::shared_ptr<const Family::Prepared> Family::Prepare(std::span<const double>, double) const {
  return nullptr;
}

void Family::SimulatePrepared(const Prepared*, std::span<const double> p, std::span<const double> u,
                              double dt, std::span<double> y) const {
  Simulate(p, u, dt, y);
}

void Family::SimulatePreparedMany(const Prepared* prepared,
                                  std::span<const std::span<const double>> ps,
                                  std::span<const double> u, double dt,
                                  std::span<const std::span<double>> ys) const {
  for (size_t l = 0; l < ps.size(); ++l) SimulatePrepared(prepared, ps[l], u, dt, ys[l]);
}

void Family::SimulateMany(std::span<const std::span<const double>> ps,
                          std::span<const std::span<const double>> us, double dt,
                          std::span<const std::span<double>> ys) const {
  for (size_t l = 0; l < ps.size(); ++l) Simulate(ps[l], us[l], dt, ys[l]);
}

DataScale MeasureScale(const std::vector<const io::Record*>& records) {
  if (records.empty()) throw InputError("no training records to identify on");
  DataScale s;
  s.u_min = std::numeric_limits<double>::infinity();
  s.u_max = -s.u_min;
  s.duration = 0;  // the longest window, measured (a default of 1 s hid windows shorter than that)
  double ymin = s.u_min, ymax = -s.u_min;
  double su = 0, sy = 0, suu = 0, suy = 0, n = 0, reversals = 0, excited = 0;
  for (const io::Record* r : records) {
    for (size_t k = r->first_scored; k < r->end_scored; ++k) {
      s.u_min = std::min(s.u_min, r->u[k]);
      s.u_max = std::max(s.u_max, r->u[k]);
      ymin = std::min(ymin, r->y[k]);
      ymax = std::max(ymax, r->y[k]);
      su += r->u[k];
      sy += r->y[k];
      suu += r->u[k] * r->u[k];
      suy += r->u[k] * r->y[k];
      n += 1;
    }
    s.fs = r->sample_rate_hz();
    s.duration = std::max(s.duration, r->t[r->end_scored - 1] - r->t[r->first_scored]);
  }
  s.duration = std::max(s.duration, 1 / s.fs);  // one sample at least (a range is divided by it)
  s.u_half = (s.u_max - s.u_min) / 2;
  if (!(s.u_half > 0)) {
    std::string names;
    for (const io::Record* r : records) names += (names.empty() ? "" : ", ") + r->name;
    throw InputError("the drive is constant over the scored samples of " + names +
                     ": nothing to identify");
  }
  s.y_half = std::max((ymax - ymin) / 2, 1e-300);
  const double var = suu - su * su / n, cov = suy - su * sy / n;
  const double slope = var > 0 ? cov / var : 0;
  s.polarity = slope < 0 ? -1 : 1;
  s.gain = std::abs(slope) > 0 ? std::abs(slope) : s.y_half / s.u_half;
  // Dominant frequency: reversals of the drive by more than 10 % of its half range, over the scored
  // time.
  for (const io::Record* r : records) {
    const double thr = 0.1 * s.u_half;
    double hi = r->u[r->first_scored], lo = hi;
    int dir = 0;  // +1 rising, −1 falling, 0 not yet known
    for (size_t k = r->first_scored; k < r->end_scored; ++k) {
      const double v = r->u[k];
      hi = std::max(hi, v);
      lo = std::min(lo, v);
      if (dir >= 0 && v < hi - thr) {  // a maximum passed
        if (dir > 0) ++reversals;
        dir = -1;
        lo = v;
      } else if (dir <= 0 && v > lo + thr) {  // a minimum passed
        if (dir < 0) ++reversals;
        dir = 1;
        hi = v;
      }
    }
    excited += r->t[r->end_scored - 1] - r->t[r->first_scored];
  }
  s.f_dom = reversals > 0 ? reversals / (2 * excited) : 1.0 / std::max(excited, 1e-9);
  return s;
}

}  // namespace pz::records
