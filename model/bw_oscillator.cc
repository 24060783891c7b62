#include "model/bw_oscillator.h"

#include <algorithm>
#include <boost/math/interpolators/cardinal_cubic_b_spline.hpp>
#include <cmath>
#include <complex>
#include <sstream>
#include <unsupported/Eigen/FFT>

#include "model/kernels/pzk.h"

namespace pz::model {
namespace {

Status Bad(const char* field, double value, const char* rule) {
  return InvalidArgument(FieldError(std::string("bw.") + field, value, rule));
}

std::string Num(double v) {
  std::ostringstream os;
  os.precision(17);
  os << v;
  return os.str();
}

// Trigonometric interpolation of one period u[0 … n) to `factor` points per sample.
std::vector<double> FourierUpsample(std::span<const double> u, size_t factor) {
  const size_t n = u.size(), m = n * factor;
  Eigen::FFT<double> fft;
  std::vector<std::complex<double>> x(n), X, Y(m, 0.0), out;
  for (size_t i = 0; i < n; ++i) x[i] = u[i];
  fft.fwd(X, x);
  const double scale = static_cast<double>(factor);
  const size_t half = (n - 1) / 2;  // bins 1 … half have a distinct negative partner
  Y[0] = X[0] * scale;
  for (size_t f = 1; f <= half; ++f) {
    Y[f] = X[f] * scale;
    Y[m - f] = X[n - f] * scale;
  }
  if (n % 2 == 0) {  // the Nyquist bin, split between +n/2 and −n/2
    Y[n / 2] = X[n / 2] * (0.5 * scale);
    Y[m - n / 2] = X[n / 2] * (0.5 * scale);
  }
  fft.inv(out, Y);
  std::vector<double> r(m);
  for (size_t i = 0; i < m; ++i) r[i] = out[i].real();
  return r;
}

// One RK4 step for ν ≠ 1 (|z|^(ν−1) in ż), which no kernel has: the exported oscillator is ν = 1,
// whose step is the kernel's pzk_bw_osc_rk4.
void Rk4General(const double* c, double nu1, double h, double h2, double h6, const double* u,
                double* st) {
  const double inv_m = c[0], cc = c[1], k = c[2], alpha = c[3], bg = c[4], bd = c[5];
  auto zdot = [&](double v, double z) {
    const double az = std::abs(z);
    const double pw = az > 0 ? std::pow(az, nu1) : (nu1 == 0 ? 1.0 : 0.0);
    return alpha * v - pw * (bg * std::abs(v) * z + bd * v * az);
  };
  const double Y = st[0], V = st[1], Z = st[2], u0 = u[0], u1 = u[1], u2 = u[2];
  const double a1 = (u0 - cc * V - k * Y - Z) * inv_m, z1 = zdot(V, Z);
  const double y2 = Y + h2 * V, v2 = V + h2 * a1, w2 = Z + h2 * z1;
  const double a2 = (u1 - cc * v2 - k * y2 - w2) * inv_m, z2 = zdot(v2, w2);
  const double y3 = Y + h2 * v2, v3 = V + h2 * a2, w3 = Z + h2 * z2;
  const double a3 = (u1 - cc * v3 - k * y3 - w3) * inv_m, z3 = zdot(v3, w3);
  const double y4 = Y + h * v3, v4 = V + h * a3, w4 = Z + h * z3;
  const double a4 = (u2 - cc * v4 - k * y4 - w4) * inv_m, z4 = zdot(v4, w4);
  st[0] = Y + h6 * (V + 2 * (v2 + v3) + v4);
  st[1] = V + h6 * (a1 + 2 * (a2 + a3) + a4);
  st[2] = Z + h6 * (z1 + 2 * (z2 + z3) + z4);
}

template <bool kNuOne>
Status Integrate(const BwParams& p, const BwInput& in, std::span<double> y, BwState* state) {
  const size_t n = in.samples();
  const int S = in.substeps();
  const double h = 1.0 / (in.sample_rate_hz() * S), h2 = 0.5 * h, h6 = h / 6.0;
  // The kernel's constants (model/kernels/bw_oscillator.h pzk_bw_osc_params).
  const double c[6] = {1.0 / p.m, p.c, p.k, p.alpha, p.beta * p.gamma, p.beta * p.delta};
  const double nu1 = p.nu - 1.0;
  const double* u = in.half_steps().data();
  const BwState s0 = state ? *state : BwState{};
  double st[3] = {s0.y, s0.v, s0.z};
  y[0] = st[0];
  size_t j = 0;
  for (size_t i = 1; i < n; ++i) {
    for (int s = 0; s < S; ++s, j += 2) {
      if constexpr (kNuOne)
        pzk::pzk_bw_osc_rk4(c, h, h2, h6, u[j], u[j + 1], u[j + 2], st);  // the kernel's step
      else
        Rk4General(c, nu1, h, h2, h6, u + j, st);
    }
    const double Y = st[0], V = st[1], Z = st[2];
    y[i] = Y;
    // |x| ≤ bound is false for NaN too.
    if (!(std::abs(Y) <= 1e3 && std::abs(Z) <= 1e12 && std::abs(V) <= 1e9)) {
      std::fill(y.begin() + static_cast<std::ptrdiff_t>(i), y.end(), 0.0);
      if (state) *state = BwState{Y, V, Z};
      return OutOfRange("bw: the simulation diverged at sample " + std::to_string(i) +
                        " (t = " + Num(static_cast<double>(i) / in.sample_rate_hz()) +
                        " s): y = " + Num(Y) + " m, z = " + Num(Z) + " N");
    }
  }
  if (state) *state = BwState{st[0], st[1], st[2]};
  return Status::Ok();
}

// The kernel's step (pzk_bw_osc_rk4), kept here in vectors: the kernel's step in a loop over
// four lanes, vectorised by GCC, made the fits' four-lane evaluation 1.06x and pairs 1.2x slower
// (docs/architecture.md "One home for a step"). Integrate<true>'s loop for 2 NV parameter sets at
// once, lanes 2v and 2v + 1 in the two halves of SSE2 vectors (GCC vector extensions): every
// operation of a lane is the scalar loop's, in the same order (packed multiplies, adds and
// subtractions round each half as the scalar ones do; |x| clears the sign bit as fabs does; no
// reassociation, no FMA), so each lane's values are its bits. NV = 2 runs two independent chains of
// vector operations, four parameter sets in about the time of one (the loop is bound by the latency
// of its chain, not by throughput). Returns false, leaving y and the states undefined, as soon as a
// lane leaves the scalar loop's bounds (the caller then runs each alone, for the scalar loop's
// exact output and message). Each lane reads its own input (the same table for every lane that
// shares a drive); the inputs have the same samples, sub-steps and rate (checked by the caller).
typedef double V2 __attribute__((vector_size(16)));
typedef long long V2i __attribute__((vector_size(16)));

inline V2 Abs(V2 x) { return (V2)((V2i)x & (V2i){0x7fffffffffffffffLL, 0x7fffffffffffffffLL}); }
inline V2 Splat(double x) { return (V2){x, x}; }

template <int NV>
bool IntegrateLanes(const BwParams* p, const BwInput* const* in, const std::span<double>* y,
                    BwState* st) {
  constexpr int L = 2 * NV;
  const size_t n = in[0]->samples();
  const int S = in[0]->substeps();
  const double hs = 1.0 / (in[0]->sample_rate_hz() * S);
  const V2 h = Splat(hs), h2 = Splat(0.5 * hs), h6 = Splat(hs / 6.0), two = Splat(2.0);
  V2 inv_m[NV], c[NV], k[NV], alpha[NV], bg[NV], bd[NV], Y[NV], V[NV], Z[NV];
  const double* u[L];
  for (int v = 0; v < NV; ++v) {
    const BwParams &a = p[2 * v], &b = p[2 * v + 1];
    inv_m[v] = (V2){1.0 / a.m, 1.0 / b.m};
    c[v] = (V2){a.c, b.c};
    k[v] = (V2){a.k, b.k};
    alpha[v] = (V2){a.alpha, b.alpha};
    bg[v] = (V2){a.beta * a.gamma, b.beta * b.gamma};
    bd[v] = (V2){a.beta * a.delta, b.beta * b.delta};
    Y[v] = (V2){st[2 * v].y, st[2 * v + 1].y};
    V[v] = (V2){st[2 * v].v, st[2 * v + 1].v};
    Z[v] = (V2){st[2 * v].z, st[2 * v + 1].z};
  }
  for (int l = 0; l < L; ++l) {
    y[l][0] = st[l].y;
    u[l] = in[l]->half_steps().data();
  }
  size_t j = 0;
  for (size_t i = 1; i < n; ++i) {
    for (int s = 0; s < S; ++s, j += 2) {
      for (int v = 0; v < NV; ++v) {
        const double *ua = u[2 * v], *ub = u[2 * v + 1];
        const V2 u0 = {ua[j], ub[j]}, u1 = {ua[j + 1], ub[j + 1]}, u2 = {ua[j + 2], ub[j + 2]};
        auto zdot = [&](V2 x, V2 z) {
          return alpha[v] * x - bg[v] * Abs(x) * z - bd[v] * x * Abs(z);
        };
        const V2 a1 = (u0 - c[v] * V[v] - k[v] * Y[v] - Z[v]) * inv_m[v], z1 = zdot(V[v], Z[v]);
        const V2 y2 = Y[v] + h2 * V[v], v2 = V[v] + h2 * a1, w2 = Z[v] + h2 * z1;
        const V2 a2 = (u1 - c[v] * v2 - k[v] * y2 - w2) * inv_m[v], z2 = zdot(v2, w2);
        const V2 y3 = Y[v] + h2 * v2, v3 = V[v] + h2 * a2, w3 = Z[v] + h2 * z2;
        const V2 a3 = (u1 - c[v] * v3 - k[v] * y3 - w3) * inv_m[v], z3 = zdot(v3, w3);
        const V2 y4 = Y[v] + h * v3, v4 = V[v] + h * a3, w4 = Z[v] + h * z3;
        const V2 a4 = (u2 - c[v] * v4 - k[v] * y4 - w4) * inv_m[v], z4 = zdot(v4, w4);
        Y[v] += h6 * (V[v] + two * (v2 + v3) + v4);
        V[v] += h6 * (a1 + two * (a2 + a3) + a4);
        Z[v] += h6 * (z1 + two * (z2 + z3) + z4);
      }
    }
    bool ok = true;
    for (int v = 0; v < NV; ++v) {
      for (int e = 0; e < 2; ++e) {
        y[2 * v + e][i] = Y[v][e];
        ok &= std::abs(Y[v][e]) <= 1e3 && std::abs(Z[v][e]) <= 1e12 &&
              std::abs(V[v][e]) <= 1e9;  // false for NaN too
      }
    }
    if (!ok) return false;
  }
  for (int v = 0; v < NV; ++v)
    for (int e = 0; e < 2; ++e) st[2 * v + e] = BwState{Y[v][e], V[v][e], Z[v][e]};
  return true;
}

}  // namespace

Status BwParams::Validate() const {
  if (!(std::isfinite(m) && m > 0)) return Bad("m", m, "must be finite and > 0");
  const std::pair<const char*, double> finite[] = {
      {"c", c}, {"k", k}, {"alpha", alpha}, {"beta", beta}, {"gamma", gamma}, {"delta", delta}};
  for (const auto& [name, v] : finite) {
    if (!std::isfinite(v)) return Bad(name, v, "must be finite");
  }
  if (!(std::isfinite(nu) && nu >= 1)) return Bad("nu", nu, "must be finite and >= 1");
  return Status::Ok();
}

const char* InputInterpolationName(InputInterpolation i) {
  switch (i) {
    case InputInterpolation::kZeroOrderHold:
      return "zoh";
    case InputInterpolation::kLinear:
      return "linear";
    case InputInterpolation::kCubicSpline:
      return "spline";
    case InputInterpolation::kPeriodicFourier:
      return "fourier";
  }
  return "unknown";
}

InputInterpolation ParseInputInterpolation(const std::string& name) {
  for (InputInterpolation i :
       {InputInterpolation::kZeroOrderHold, InputInterpolation::kLinear,
        InputInterpolation::kCubicSpline, InputInterpolation::kPeriodicFourier}) {
    if (name == InputInterpolationName(i)) return i;
  }
  throw InputError("interpolation = " + name + ": must be zoh, linear, spline or fourier");
}

Status BwInputOptions::Validate() const {
  if (!(std::isfinite(sample_rate_hz) && sample_rate_hz > 0)) {
    return Bad("input.sample_rate_hz", sample_rate_hz, "must be finite and > 0");
  }
  if (substeps < 1 || substeps > 1000)
    return Bad("input.substeps", substeps, "must be in 1 … 1000");
  return Status::Ok();
}

BwInput::BwInput(std::span<const double> u, const BwInputOptions& options) { Assign(u, options); }

void BwInput::Assign(std::span<const double> u, const BwInputOptions& options) {
  samples_ = 0;  // empty until the table is made (an error leaves it so)
  ThrowIfError(options.Validate());
  const size_t n = u.size();
  if (n < 2) throw InputError(FieldError("bw.input: u.size()", n, "needs at least 2 samples"));
  for (size_t i = 0; i < n; ++i) {
    if (!std::isfinite(u[i]))
      throw InputError(
          FieldError("bw.input: u[" + std::to_string(i) + "]", u[i], "must be finite"));
  }
  options_ = options;
  const size_t L = 2 * static_cast<size_t>(options.substeps);  // half steps per sample
  fine_.resize(L * (n - 1) + 1);
  switch (options.interpolation) {
    case InputInterpolation::kZeroOrderHold:
      // u[i] on [t_i, t_{i+1}); a node takes the new sample (the last sub-step of an interval
      // sees it at its end point only).
      for (size_t j = 0; j < fine_.size(); ++j) fine_[j] = u[std::min(j / L, n - 1)];
      break;
    case InputInterpolation::kLinear: {
      // u_i + (u_{i+1} − u_i) r/L, the fractions r/L divided once (the same values).
      thread_local std::vector<double> frac;
      frac.resize(L);
      for (size_t r = 0; r < L; ++r) frac[r] = static_cast<double>(r) / static_cast<double>(L);
      for (size_t i = 0; i + 1 < n; ++i) {
        const double a = u[i], d = u[i + 1] - u[i];
        double* f = fine_.data() + i * L;
        for (size_t r = 0; r < L; ++r) f[r] = a + d * frac[r];
      }
      fine_.back() = u[n - 1];
      break;
    }
    case InputInterpolation::kCubicSpline: {
      if (n < 4)
        throw InputError(
            FieldError("bw.input: u.size()", n, "the cubic spline needs at least 4 samples"));
      boost::math::interpolators::cardinal_cubic_b_spline<double> spline(u.data(), n, 0.0, 1.0);
      for (size_t i = 0; i + 1 < n; ++i) {
        fine_[i * L] = u[i];
        for (size_t r = 1; r < L; ++r) {
          fine_[i * L + r] =
              spline(static_cast<double>(i) + static_cast<double>(r) / static_cast<double>(L));
        }
      }
      fine_.back() = u[n - 1];
      break;
    }
    case InputInterpolation::kPeriodicFourier: {
      const size_t period = options.period_samples == 0 ? n : options.period_samples;
      if (n % period != 0) {
        throw InputError(FieldError("bw.input.period_samples", period,
                                    "must divide the record length " + std::to_string(n)));
      }
      double scale = 0;
      for (double v : u) scale = std::max(scale, std::abs(v));
      for (size_t i = period; i < n; ++i) {
        if (std::abs(u[i] - u[i % period]) > 1e-9 * scale) {
          throw InputError(
              "bw.input: u[" + std::to_string(i) + "] = " + Num(u[i]) + " differs from u[" +
              std::to_string(i % period) + "] = " + Num(u[i % period]) +
              ": the record is not periodic with period_samples = " + std::to_string(period));
        }
      }
      const std::vector<double> one = FourierUpsample(u.subspan(0, period), L);
      for (size_t j = 0; j < fine_.size(); ++j) fine_[j] = one[j % one.size()];
      break;
    }
  }
  samples_ = n;
}

Status SimulateBw(const BwParams& params, const BwInput& input, std::span<double> y,
                  BwState* state) {
  ThrowIfError(params.Validate());
  if (y.size() != input.samples()) {
    throw InputError(
        FieldError("bw: y.size()", y.size(),
                   "must equal the input's samples = " + std::to_string(input.samples())));
  }
  if (input.samples() == 0)
    throw InputError("bw: the input is empty (default-constructed BwInput)");
  return params.nu == 1.0 ? Integrate<true>(params, input, y, state)
                          : Integrate<false>(params, input, y, state);
}

std::vector<Status> SimulateBwMany(std::span<const BwParams> params,
                                   std::span<const BwInput* const> inputs,
                                   std::span<const std::span<double>> y,
                                   std::span<BwState> states) {
  const size_t N = params.size();
  if (inputs.size() != N || y.size() != N || (!states.empty() && states.size() != N))
    throw InputError("bw: one input, output (and state) per parameter set expected");
  for (size_t l = 0; l < N; ++l) {
    ThrowIfError(params[l].Validate());
    if (inputs[l] == nullptr || inputs[l]->samples() == 0)
      throw InputError("bw: input " + std::to_string(l) +
                       " is empty (default-constructed BwInput)");
    if (y[l].size() != inputs[l]->samples()) {
      throw InputError(
          FieldError("bw: y[" + std::to_string(l) + "].size()", y[l].size(),
                     "must equal the input's samples = " + std::to_string(inputs[l]->samples())));
    }
    const BwInput &a = *inputs[0], &b = *inputs[l];
    if (b.samples() != a.samples() || b.substeps() != a.substeps() ||
        b.sample_rate_hz() != a.sample_rate_hz()) {
      throw InputError("bw: the inputs differ in samples (" + std::to_string(a.samples()) + ", " +
                       std::to_string(b.samples()) + "), sub-steps (" +
                       std::to_string(a.substeps()) + ", " + std::to_string(b.substeps()) +
                       ") or sample rate (" + Num(a.sample_rate_hz()) + ", " +
                       Num(b.sample_rate_hz()) + " Hz): they must be equal");
    }
  }
  std::vector<Status> out(N);
  std::vector<BwState> st(N);
  for (size_t l = 0; l < N; ++l) st[l] = states.empty() ? BwState{} : states[l];
  // Groups of four lanes (two vector chains), then of two, then one alone; a group with ν ≠ 1 or a
  // lane that diverges runs each of its lanes alone.
  for (size_t l0 = 0; l0 < N;) {
    const size_t g = N - l0 >= 4 ? 4 : N - l0 >= 2 ? 2 : 1;
    bool nu_one = true;
    for (size_t l = l0; l < l0 + g; ++l) nu_one = nu_one && params[l].nu == 1.0;
    std::vector<BwState> s(st.begin() + static_cast<std::ptrdiff_t>(l0),
                           st.begin() + static_cast<std::ptrdiff_t>(l0 + g));
    const bool grouped = g > 1 && nu_one &&
                         (g == 4 ? IntegrateLanes<2>(&params[l0], &inputs[l0], &y[l0], s.data())
                                 : IntegrateLanes<1>(&params[l0], &inputs[l0], &y[l0], s.data()));
    for (size_t l = l0; l < l0 + g; ++l) {
      if (grouped) {
        st[l] = s[l - l0];
        out[l] = Status::Ok();
      } else {
        out[l] = SimulateBw(params[l], *inputs[l], y[l], &st[l]);
      }
    }
    l0 += g;
  }
  if (!states.empty()) std::copy(st.begin(), st.end(), states.begin());
  return out;
}

std::array<Status, 2> SimulateBwPair(const std::array<BwParams, 2>& params,
                                     const std::array<const BwInput*, 2>& inputs,
                                     const std::array<std::span<double>, 2>& y,
                                     std::array<BwState, 2>* states) {
  const std::vector<Status> st = SimulateBwMany(
      params, inputs, y, states ? std::span<BwState>(*states) : std::span<BwState>());
  return {st[0], st[1]};
}

std::array<Status, 2> SimulateBwPair(const std::array<BwParams, 2>& params, const BwInput& input,
                                     const std::array<std::span<double>, 2>& y,
                                     std::array<BwState, 2>* states) {
  return SimulateBwPair(params, {&input, &input}, y, states);
}

BwParams BwFromIdentifiable(std::span<const double> theta) {
  if (theta.size() != 6)
    throw InputError(FieldError("bw: theta.size()", theta.size(), "must be 6"));
  BwParams p;
  p.m = theta[0];
  p.c = theta[1];
  p.k = theta[2];
  p.alpha = theta[3];
  p.beta = 1;
  p.gamma = theta[4];
  p.delta = theta[5];
  p.nu = 1;
  return p;
}

std::vector<double> BwIdentifiable(const BwParams& p) {
  return {p.m, p.c, p.k, p.alpha, p.beta * p.gamma, p.beta * p.delta};
}

const std::vector<std::string>& BwIdentifiableNames() {
  static const std::vector<std::string> names = {"m",     "c",          "k",
                                                 "alpha", "beta_gamma", "beta_delta"};
  return names;
}

}  // namespace pz::model
