#include "model/dahl.h"

#include <chrono>
#include <cmath>
#include <exception>
#include <numbers>
#include <string>

#include "model/cvode.h"

namespace pz::model {

Status DahlParams::Validate() const {
  const std::pair<const char*, double> all[] = {
      {"m", m},   {"epsilon", epsilon}, {"g", g},   {"k", k},
      {"b1", b1}, {"b0", b0},           {"a1", a1}, {"a2", a2}};
  for (auto [name, v] : all)
    if (!std::isfinite(v)) return InvalidArgument(FieldError(name, v, "must be finite"));
  if (!(m > 0)) return InvalidArgument(FieldError("m", m, "must be > 0 [kg]"));
  if (epsilon < 0) return InvalidArgument(FieldError("epsilon", epsilon, "must be >= 0 [N s/m]"));
  if (g < 0) return InvalidArgument(FieldError("g", g, "must be >= 0 [N/m]"));
  return Status::Ok();
}

Status DahlOptions::Validate() const {
  if (!(rtol > 0 && rtol <= 1e-2))
    return InvalidArgument(FieldError("rtol", rtol, "must be in (0, 1e-2]"));
  if (!(atol > 0 && std::isfinite(atol)))
    return InvalidArgument(FieldError("atol", atol, "must be finite and > 0"));
  if (max_steps <= 0) return InvalidArgument(FieldError("max_steps", max_steps, "must be > 0"));
  return Status::Ok();
}

double DahlSignalValue(DahlSignal s, double t) {
  constexpr double pi = std::numbers::pi;
  switch (s) {
    case DahlSignal::kSine:
      return std::sin(t);
    case DahlSignal::kOffsetSine:
      return 50.0 + 50.0 * std::sin(pi * t);
    case DahlSignal::kChirp:
      return 5.0 * std::exp(-0.13 * t) * (std::cos(3.0 * pi * t * std::exp(-0.09 * t)) - 3.15) +
             1.0;
    case DahlSignal::kDampedCosine:
      return 5.0 + 3.4 * std::exp(-0.24 * t) * std::cos(2.0 * pi * t);
  }
  return 0.0;
}

double DahlSignalRate(DahlSignal s, double t) {
  constexpr double pi = std::numbers::pi;
  switch (s) {
    case DahlSignal::kSine:
      return std::cos(t);
    case DahlSignal::kOffsetSine:
      return 50.0 * pi * std::cos(pi * t);
    case DahlSignal::kChirp: {
      const double decay = std::exp(-0.13 * t);
      const double phase = 3.0 * pi * t * std::exp(-0.09 * t);
      const double phase_rate = 3.0 * pi * std::exp(-0.09 * t) * (1.0 - 0.09 * t);
      return 5.0 * decay * (-0.13 * (std::cos(phase) - 3.15) - std::sin(phase) * phase_rate);
    }
    case DahlSignal::kDampedCosine: {
      const double decay = std::exp(-0.24 * t);
      return 3.4 * decay * (-0.24 * std::cos(2.0 * pi * t) - 2.0 * pi * std::sin(2.0 * pi * t));
    }
  }
  return 0.0;
}

DahlInput MakeDahlInput(DahlSignal s) {
  return [s](double t) { return DahlSignalValue(s, t); };
}

std::vector<double> DahlGridTimes(double t_end, double dt) {
  const long n = std::lround(t_end / dt);
  std::vector<double> t(static_cast<size_t>(std::max(n, 0L) + 1));
  for (size_t i = 0; i < t.size(); ++i) t[i] = static_cast<double>(i) * dt;
  return t;
}

namespace {

// y = [d, ḋ]. The sign mode of the Coulomb term is a discrete state of the run (see dahl.h).
class DahlOde final : public OdeSystem {
 public:
  DahlOde(const DahlParams& p, const DahlInput& input) : p_(p), input_(input), c_(p.coulomb()) {}

  int size() const override { return 2; }
  JacobianStructure jacobian_structure() const override { return {.analytic = true}; }
  int num_roots() const override { return c_ == 0.0 ? 0 : 2; }

  int Rhs(double t, const double* y, double* ydot) const override {
    if (mode_ == 0) {  // stuck: d held
      ydot[0] = ydot[1] = 0.0;
      return 0;
    }
    ydot[0] = y[1];
    ydot[1] = (DrivingForce(t, y[0]) - p_.epsilon * y[1] - c_ * mode_) / p_.m;
    return 0;
  }

  int Jacobian(double, const double*, const double*, JacobianView& jac) const override {
    if (mode_ == 0) return 0;
    jac.Set(0, 1, 1.0);
    jac.Set(1, 0, -p_.g / p_.m);
    jac.Set(1, 1, -p_.epsilon / p_.m);
    return 0;
  }

  // Sliding: ḋ = 0 ends the phase. Stuck: F0 = ±c ends it.
  int Roots(double t, const double* y, double* g) const override {
    if (mode_ != 0) {
      g[0] = y[1];
      g[1] = 1.0;
    } else {
      const double f0 = DrivingForce(t, y[0]);
      g[0] = f0 - c_;
      g[1] = f0 + c_;
    }
    return 0;
  }

  // Filippov choice of the mode at a point with ḋ = 0 (see dahl.h); stuck zeroes ḋ.
  void ChooseMode(double t, std::span<double> y) {
    const double f0 = DrivingForce(t, y[0]);
    const bool up = f0 - c_ > 0, down = f0 + c_ < 0;
    if (up && down) {
      mode_ = f0 >= 0 ? 1 : -1;
    } else if (up) {
      mode_ = 1;
    } else if (down) {
      mode_ = -1;
    } else {
      mode_ = 0;
      y[1] = 0.0;
    }
  }
  int mode() const { return mode_; }

 private:
  // k v − g d − a1 b1: every force but damping and the Coulomb term [N].
  double DrivingForce(double t, double d) const {
    return p_.k * input_(t) - p_.g * d - p_.a1 * p_.b1;
  }

  DahlParams p_;
  const DahlInput& input_;
  double c_;
  int mode_ = 1;
};

}  // namespace

DahlTrace SimulateDahl(const DahlParams& params, const DahlInput& input,
                       std::span<const double> times, const DahlOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  DahlTrace trace;
  auto fail = [&](SimStatus st, std::string msg) {
    trace.summary.status = st;
    trace.summary.message = std::move(msg);
    trace.summary.wall_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return trace;
  };
  if (auto s = params.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  if (auto s = options.Validate(); !s.ok()) return fail(SimStatus::kInvalidInput, s.message());
  if (!input) return fail(SimStatus::kInvalidInput, "input: no signal given");
  for (size_t k = 0; k < times.size(); ++k) {
    if (!(std::isfinite(times[k]) && times[k] >= 0))
      return fail(SimStatus::kInvalidInput, FieldError("times[" + std::to_string(k) + "]", times[k],
                                                       "must be finite and >= 0"));
  }
  try {
    DahlOde ode(params, input);
    std::vector<double> y0 = {0.0, 0.0};
    if (params.coulomb() != 0.0) ode.ChooseMode(0.0, y0);
    CvodeOptions co;
    co.method = OdeMethod::kAdams;
    co.iteration = NonlinearIteration::kNewton;
    co.rtol = options.rtol;
    co.atol = options.atol;
    co.max_steps = options.max_steps;
    co.on_stop = [&ode](const StopEvent& ev, std::span<double> y) {
      if (ev.roots.empty()) return StopAction::kContinue;
      ode.ChooseMode(ev.t, y);
      return StopAction::kRestart;
    };
    const OdeSolution sol = IntegrateCvode(ode, 0.0, y0, times, co);
    trace.summary = sol.summary;
    trace.t = sol.t;
    for (size_t k = 0; k < sol.t.size(); ++k) {
      trace.v.push_back(input(sol.t[k]));
      trace.d.push_back(sol.at(k, 0));
      trace.d_dot.push_back(sol.at(k, 1));
    }
  } catch (const std::exception& e) {  // the input function threw outside a CVODE callback
    return fail(SimStatus::kInvalidInput, std::string("input: ") + e.what());
  }
  trace.summary.wall_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return trace;
}

DahlTrace SimulateDahl(const DahlParams& params, DahlSignal signal, std::span<const double> times,
                       const DahlOptions& options) {
  return SimulateDahl(params, MakeDahlInput(signal), times, options);
}

}  // namespace pz::model
