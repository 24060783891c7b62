#include "synth/relay_preisach_check.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

#include "model/status.h"

namespace pz::synth {
namespace {

std::string Bad(const std::string& field, double value, const std::string& rule) {
  return "relay-preisach-check." + field + " = " + std::to_string(value) + ": " + rule;
}

/// The drive in shares of the range [0, 1] → volts.
double Volts(const RelayPreisachCheckOptions& o, double share) {
  return o.u_lo + (o.u_hi - o.u_lo) * share;
}

/// Linear ramps through turning points drawn in [lo, hi] of the range, `mean_s` each on average,
/// with a hold of hold_s after a turning point with probability p_hold; appended to u (shares).
void Reversals(std::mt19937_64& g, double fs, double seconds, double lo, double hi, double mean_s,
               double p_hold, double hold_s, std::vector<double>& u) {
  std::uniform_real_distribution<double> level(lo, hi), len(0.4 * mean_s, 1.6 * mean_s), coin(0, 1);
  const size_t n = static_cast<size_t>(seconds * fs);
  const size_t end = u.size() + n;
  double from = u.empty() ? 0 : u.back();
  while (u.size() < end) {
    const double to = level(g);
    const size_t steps = std::max<size_t>(2, static_cast<size_t>(len(g) * fs));
    for (size_t k = 1; k <= steps && u.size() < end; ++k)
      u.push_back(from + (to - from) * static_cast<double>(k) / steps);
    if (coin(g) < p_hold)
      for (size_t k = 0; k < static_cast<size_t>(hold_s * fs) && u.size() < end; ++k)
        u.push_back(to);
    from = to;
  }
}

/// The training excitation (shares of the range, after the rest at 0).
std::vector<double> RichDrive(const RelayPreisachCheckOptions& o, std::mt19937_64& g) {
  const double fs = o.fs_hz, T1 = 0.45 * o.train_s, T2 = 0.35 * o.train_s, T3 = o.train_s - T1 - T2;
  std::vector<double> u;
  // A sine whose amplitude decays from the full range to a tenth, its centre wandering inside the
  // room the amplitude leaves: minor loops nested at every level.
  for (size_t k = 0; k < static_cast<size_t>(T1 * fs); ++k) {
    const double t = static_cast<double>(k) / fs, x = t / T1, A = 1 - 0.9 * x;
    const double c = 0.5 + 0.35 * (1 - A) * std::sin(2 * std::numbers::pi * t / 13);
    u.push_back(c - 0.5 * A * std::cos(2 * std::numbers::pi * 0.4 * t));
  }
  Reversals(g, fs, T2, 0.03, 0.97, 1.5, 0, 0, u);  // random reversals
  // A staircase: ramps of 0.5 s to random levels, holds of 3 s (creep at several levels).
  std::uniform_real_distribution<double> level(0.08, 0.92);
  const size_t end = u.size() + static_cast<size_t>(T3 * fs);
  while (u.size() < end) {
    const double from = u.back(), to = level(g);
    const size_t ramp = static_cast<size_t>(0.5 * fs), hold = static_cast<size_t>(3 * fs);
    for (size_t k = 1; k <= ramp && u.size() < end; ++k)
      u.push_back(from + (to - from) * static_cast<double>(k) / ramp);
    for (size_t k = 0; k < hold && u.size() < end; ++k) u.push_back(to);
  }
  return u;
}

io::Record MakeRecord(const RelayPreisachCheckOptions& o, const std::string& name,
                      model::CaseRole role, const std::vector<double>& shares, uint64_t seed,
                      double* noise_rms) {
  io::Record r;
  r.name = name;
  r.role = role;
  const size_t rest = static_cast<size_t>(o.rest_s * o.fs_hz);
  r.u.assign(rest, o.u_lo);
  for (double s : shares) r.u.push_back(Volts(o, std::clamp(s, 0.0, 1.0)));
  r.y = RelayPreisachCheckResponse(o, r.u);
  std::mt19937_64 g(seed);
  std::normal_distribution<double> noise(0, o.noise_um);
  std::uniform_real_distribution<double> offset(-o.offset_range_um, o.offset_range_um);
  const double off = offset(g);
  double sq = 0;
  for (size_t k = 0; k < r.y.size(); ++k) {
    const double e = noise(g);
    r.y[k] += e + off;
    if (k >= rest) sq += e * e;
  }
  r.dt = 1 / o.fs_hz;
  for (size_t k = 0; k < r.u.size(); ++k) r.t.push_back(static_cast<double>(k) * r.dt);
  r.rest_samples = rest;
  r.first_scored = rest;
  r.end_scored = r.u.size();
  *noise_rms = std::sqrt(sq / static_cast<double>(r.scored()));
  return r;
}

}  // namespace

std::string RelayPreisachCheckOptions::Validate() const {
  if (relay_levels < 40 || relay_levels > 2000)
    return Bad("relay_levels", relay_levels, "must be 40 … 2000");
  if (!std::isfinite(u_lo) || !std::isfinite(u_hi) || !(u_lo < u_hi))
    return Bad("u_hi", u_hi, "must be finite, > u_lo");
  if (!(quadratic > -0.5 && quadratic < 10))
    return Bad("quadratic", quadratic, "must be in (-0.5, 10)");
  if (!(stroke_um > 0 && std::isfinite(stroke_um)))
    return Bad("stroke_um", stroke_um, "must be finite and > 0");
  if (!(hysteresis_share >= 0 && hysteresis_share <= 1))
    return Bad("hysteresis_share", hysteresis_share, "must be 0 … 1");
  if (!(width > 0 && std::isfinite(width))) return Bad("width", width, "must be finite and > 0");
  if (!std::isfinite(skew)) return Bad("skew", skew, "must be finite");
  for (size_t j = 0; j < 3; ++j) {
    if (!(creep_tau_s[j] > 0 && std::isfinite(creep_tau_s[j])))
      return Bad("creep_tau_s[" + std::to_string(j) + "]", creep_tau_s[j],
                 "must be finite and > 0");
    if (!(creep_gain[j] >= 0 && creep_gain[j] < 1))
      return Bad("creep_gain[" + std::to_string(j) + "]", creep_gain[j], "must be 0 … 1");
  }
  if (lag_samples < 0 || lag_samples > 1000)
    return Bad("lag_samples", lag_samples, "must be 0 … 1000");
  if (!(noise_um >= 0 && std::isfinite(noise_um)))
    return Bad("noise_um", noise_um, "must be finite and >= 0");
  if (!(offset_range_um >= 0 && std::isfinite(offset_range_um)))
    return Bad("offset_range_um", offset_range_um, "must be finite and >= 0");
  if (!(fs_hz >= 1 && fs_hz <= 1e5)) return Bad("fs_hz", fs_hz, "must be 1 … 1e5");
  if (!(rest_s >= 0 && rest_s <= 1e4)) return Bad("rest_s", rest_s, "must be 0 … 1e4");
  if (!(train_s * fs_hz >= 200 && train_s <= 1e5))
    return Bad("train_s", train_s, "must hold 200 samples, <= 1e5 s");
  if (!(withheld_s * fs_hz >= 100 && withheld_s <= 1e5))
    return Bad("withheld_s", withheld_s, "must hold 100 samples, <= 1e5 s");
  return "";
}

std::vector<double> RelayPreisachCheckResponse(const RelayPreisachCheckOptions& o,
                                               const std::vector<double>& u) {
  if (const std::string e = o.Validate(); !e.empty()) throw InputError(e);
  const double range = o.u_hi - o.u_lo;
  auto shaped = [&](double v) { return v + o.quadratic * (v - o.u_lo) * (v - o.u_lo) / range; };
  const double q_lo = shaped(o.u_lo), q_hi = shaped(o.u_hi), q_range = q_hi - q_lo;
  const int K = o.relay_levels;
  const double h = q_range / K;
  std::vector<double> alpha, beta, weight;
  double total = 0;
  for (int a = 0; a < K; ++a) {
    for (int b = 0; b <= a; ++b) {
      const double al = q_lo + (a + 0.5) * h, be = q_lo + (b + 0.5) * h;
      const double centre = (0.5 * (al + be) - q_lo) / q_range - 0.5;
      const double mu = std::exp(-(al - be) / (o.width * q_range)) * std::exp(o.skew * centre);
      alpha.push_back(al);
      beta.push_back(be);
      weight.push_back(mu);
      total += mu;
    }
  }
  for (double& w : weight) w *= o.hysteresis_share * o.stroke_um / total;
  const double rev = (1 - o.hysteresis_share) * o.stroke_um / q_range;
  std::vector<char> on(alpha.size(), 0);  // negative saturation: every relay off
  std::vector<double> y(u.size());
  for (size_t k = 0; k < u.size(); ++k) {
    const double q = shaped(u[k]);
    double acc = rev * (q - q_lo);
    for (size_t i = 0; i < on.size(); ++i) {
      if (q >= alpha[i])
        on[i] = 1;
      else if (q <= beta[i])
        on[i] = 0;
      if (on[i]) acc += weight[i];
    }
    y[k] = acc;
  }
  // Creep: three relaxations of the output's change since the first sample (the rest).
  const double dt = 1 / o.fs_hz, y0 = y.empty() ? 0 : y[0];
  std::array<double, 3> x{}, a{};
  for (size_t j = 0; j < 3; ++j) a[j] = std::exp(-dt / o.creep_tau_s[j]);
  std::vector<double> yc(u.size());
  for (size_t k = 0; k < u.size(); ++k) {
    double c = y[k];
    for (size_t j = 0; j < 3; ++j) {
      x[j] = a[j] * x[j] + (1 - a[j]) * (y[k] - y0);
      c += o.creep_gain[j] * x[j];
    }
    yc[k] = c;
  }
  // The sensor's lag: sample k reads the plant at k − lag (the rest before the first sample).
  std::vector<double> out(u.size());
  const size_t lag = static_cast<size_t>(o.lag_samples);
  for (size_t k = 0; k < u.size(); ++k) out[k] = k >= lag ? yc[k - lag] : yc[0];
  return out;
}

RelayPreisachCheckSet GenerateRelayPreisachCheck(const RelayPreisachCheckOptions& o) {
  if (const std::string e = o.Validate(); !e.empty()) throw InputError(e);
  RelayPreisachCheckSet s;
  s.set.source = "relay-preisach-check";
  s.set.format = "synthetic";
  std::mt19937_64 g(o.seed);
  double rms = 0;
  s.set.records.push_back(
      MakeRecord(o, "rich", model::CaseRole::kTrain, RichDrive(o, g), o.seed * 1000 + 1, &rms));
  s.noise_rms_um.push_back(rms);
  // Nested minor loops: the amplitude ramps down to zero and back, at another rate.
  std::vector<double> nested;
  const size_t n = static_cast<size_t>(o.withheld_s * o.fs_hz);
  for (size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / o.fs_hz, x = t / o.withheld_s;
    nested.push_back(0.5 - 0.5 * std::abs(1 - 2 * x) * std::cos(2 * std::numbers::pi * 0.55 * t));
  }
  s.set.records.push_back(
      MakeRecord(o, "nested", model::CaseRole::kValidate, nested, o.seed * 1000 + 2, &rms));
  s.noise_rms_um.push_back(rms);
  // Random reversals with holds (another draw).
  std::vector<double> rev;
  std::mt19937_64 g2(o.seed * 7919 + 3);
  Reversals(g2, o.fs_hz, o.withheld_s, 0.05, 0.95, 1.2, 0.3, 2, rev);
  s.set.records.push_back(
      MakeRecord(o, "reversals", model::CaseRole::kValidate, rev, o.seed * 1000 + 3, &rms));
  s.noise_rms_um.push_back(rms);
  return s;
}

}  // namespace pz::synth
