#include "synth/reallike.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

#include "model/status.h"
#include "opt/random.h"
#include "synth/synthetic.h"

namespace pz::synth {
namespace {

constexpr double kPi = std::numbers::pi;

std::string Num(double x) {
  std::ostringstream s;
  s.precision(4);
  s << x;
  return s.str();
}

/// The relaxation times: three per decade from τ_min to τ_max (both included).
std::vector<double> CreepTimes(const RealLikeStack& s) {
  std::vector<double> taus;
  const double decades = std::log10(s.creep_tau_max_s / s.creep_tau_min_s);
  const int n = std::max(1, static_cast<int>(std::lround(3 * decades)));
  for (int i = 0; i <= n; ++i) taus.push_back(s.creep_tau_min_s * std::pow(10.0, decades * i / n));
  return taus;
}

}  // namespace

std::string RealLikeStack::Validate() const {
  if (!(u_hi > u_lo)) return FieldError("stack.u_hi", u_hi, "must be above u_lo = " + Num(u_lo));
  if (!(stroke_um > 0)) return FieldError("stack.stroke_um", stroke_um, "must be > 0");
  if (!(hysteresis_share >= 0 && hysteresis_share < 1))
    return FieldError("stack.hysteresis_share", hysteresis_share, "must be in [0, 1)");
  if (!(density_width > 0 && density_width <= 1))
    return FieldError("stack.density_width", density_width, "must be in (0, 1]");
  if (!(density_width_spread > 0))
    return FieldError("stack.density_width_spread", density_width_spread, "must be > 0");
  if (!(density_center_spread > 0))
    return FieldError("stack.density_center_spread", density_center_spread, "must be > 0");
  if (!(std::abs(asymmetry) <= 10))
    return FieldError("stack.asymmetry", asymmetry, "must be in [-10, 10]");
  if (!(std::abs(quadratic) < 1))
    return FieldError("stack.quadratic", quadratic,
                      "must be in (-1, 1) (a monotone reversible part)");
  if (!(creep_per_decade >= 0 && creep_per_decade < 0.1))
    return FieldError("stack.creep_per_decade", creep_per_decade, "must be in [0, 0.1)");
  if (!(creep_tau_min_s > 0 && creep_tau_max_s >= creep_tau_min_s))
    return FieldError("stack.creep_tau_max_s", creep_tau_max_s, "must be >= creep_tau_min_s > 0");
  if (everett_grid < 8 || everett_grid > 2000)
    return FieldError("stack.everett_grid", everett_grid, "must be in [8, 2000]");
  if (!(rate_lag_v >= 0 && rate_lag_v <= u_hi - u_lo))
    return FieldError("stack.rate_lag_v", rate_lag_v, "must be in [0, u_hi - u_lo]");
  if (!(rate_time_s > 0 && rate_time_s <= 10))
    return FieldError("stack.rate_time_s", rate_time_s, "must be in (0, 10]");
  if (!(driver_tau_s >= 0 && driver_tau_s <= 10))
    return FieldError("stack.driver_tau_s", driver_tau_s, "must be in [0, 10]");
  return "";
}

std::string RealLikeSensor::Validate() const {
  if (!(fs_hz > 0)) return FieldError("sensor.fs_hz", fs_hz, "must be > 0");
  if (oversample < 1 || oversample > 64)
    return FieldError("sensor.oversample", oversample, "must be in [1, 64]");
  if (!(lag_samples >= 0 && lag_samples <= 1000))
    return FieldError("sensor.lag_samples", lag_samples, "must be in [0, 1000]");
  if (!(noise_white_um >= 0))
    return FieldError("sensor.noise_white_um", noise_white_um, "must be >= 0");
  if (!(noise_colored_um >= 0))
    return FieldError("sensor.noise_colored_um", noise_colored_um, "must be >= 0");
  if (!(colored_time_s > 0))
    return FieldError("sensor.colored_time_s", colored_time_s, "must be > 0");
  if (!(quantum_um >= 0)) return FieldError("sensor.quantum_um", quantum_um, "must be >= 0");
  if (!(drive_quantum_v >= 0))
    return FieldError("sensor.drive_quantum_v", drive_quantum_v, "must be >= 0");
  if (!(offset_range_um >= 0))
    return FieldError("sensor.offset_range_um", offset_range_um, "must be >= 0");
  return "";
}

double RealLikeSensor::NominalFloor() const {
  return std::sqrt(noise_white_um * noise_white_um + noise_colored_um * noise_colored_um +
                   quantum_um * quantum_um / 12);
}

std::string RealLikeDrive::Describe() const {
  std::ostringstream s;
  s << "rest " << Num(rest_s) << " s at " << Num(rest_level) << " V, then ";
  switch (kind) {
    case Kind::kSine:
      s << "a sine " << Num(bias) << " ± " << Num(amplitude) << " V at " << Num(frequency_hz)
        << " Hz";
      break;
    case Kind::kRampedSine:
      s << "a sine " << Num(bias) << " ± " << Num(amplitude) << " V at " << Num(frequency_hz)
        << " Hz whose amplitude ramps down to zero and back";
      break;
    case Kind::kReversals:
      s << "a random reversal sequence in " << Num(bias - amplitude) << " … "
        << Num(bias + amplitude) << " V (seed " << seed << ")";
      break;
    case Kind::kSamples:
      s << "a played drive of " << samples.size() << " samples at " << Num(samples_fs_hz) << " Hz";
      break;
    case Kind::kChirp:
      s << "a logarithmic chirp " << Num(bias) << " ± " << Num(amplitude) << " V from "
        << Num(frequency_hz) << " to " << Num(frequency_end_hz) << " Hz";
      break;
  }
  if (kind != Kind::kSamples) s << " from phase " << Num(phase_rad) << " rad";
  s << " for " << Num(duration_s) << " s";
  return s.str();
}

std::function<double(double)> DriveFunction(const RealLikeDrive& d) {
  if (!(d.rest_s >= 0) || !(d.duration_s > 0))
    throw InputError(FieldError("drive.duration_s", d.duration_s, "must be > 0 (rest >= 0)"));
  const double rest = d.rest_s, level = d.rest_level;
  switch (d.kind) {
    case RealLikeDrive::Kind::kSine:
    case RealLikeDrive::Kind::kRampedSine: {
      if (!(d.frequency_hz > 0))
        throw InputError(FieldError("drive.frequency_hz", d.frequency_hz, "must be > 0"));
      const bool ramp = d.kind == RealLikeDrive::Kind::kRampedSine;
      return [d, ramp](double t) {
        if (t < d.rest_s) return d.rest_level;
        const double tau = t - d.rest_s;
        const double a =
            ramp ? d.amplitude * std::abs(1 - 2 * std::min(tau, d.duration_s) / d.duration_s)
                 : d.amplitude;
        return d.bias + a * std::sin(2 * kPi * d.frequency_hz * tau + d.phase_rad);
      };
    }
    case RealLikeDrive::Kind::kChirp: {
      if (!(d.frequency_hz > 0) || !(d.frequency_end_hz > 0))
        throw InputError(FieldError("drive.frequency_end_hz", d.frequency_end_hz,
                                    "and frequency_hz must be > 0 (a chirp)"));
      // Phase of f(τ) = f0 k^{τ/T}, k = f1/f0: 2π f0 T (k^{τ/T} − 1) / ln k (2π f0 τ for k = 1).
      const double k = d.frequency_end_hz / d.frequency_hz, T = d.duration_s, lnk = std::log(k);
      return [d, k, T, lnk](double t) {
        if (t < d.rest_s) return d.rest_level;
        const double tau = std::min(t - d.rest_s, T);
        const double phase = std::abs(lnk) < 1e-12
                                 ? 2 * kPi * d.frequency_hz * tau
                                 : 2 * kPi * d.frequency_hz * T * (std::pow(k, tau / T) - 1) / lnk;
        return d.bias + d.amplitude * std::sin(phase + d.phase_rad);
      };
    }
    case RealLikeDrive::Kind::kReversals: {
      if (!(d.frequency_hz > 0) || !(d.amplitude > 0))
        throw InputError("drive: a reversal sequence needs frequency_hz > 0 and amplitude > 0");
      // Turning points uniform in bias ± A (each at least 5 % of the span from the last), joined
      // by half-cosine segments at the mean rate of the sine of the same amplitude and frequency.
      opt::Rng rng(d.seed * 2654435761u + 11);
      const double rate = 4 * d.amplitude * d.frequency_hz, span = 2 * d.amplitude;
      std::vector<double> times{0}, levels{d.bias + d.amplitude * std::sin(d.phase_rad)};
      while (times.back() < d.duration_s) {
        double next = levels.back();
        while (std::abs(next - levels.back()) < 0.05 * span)
          next = d.bias - d.amplitude + span * rng.Uniform01();
        times.push_back(times.back() + std::max(0.05, std::abs(next - levels.back()) / rate));
        levels.push_back(next);
      }
      return [rest, level, times, levels](double t) {
        if (t < rest) return level;
        const double tau = t - rest;
        const size_t i =
            static_cast<size_t>(std::upper_bound(times.begin(), times.end(), tau) - times.begin());
        if (i >= times.size()) return levels.back();
        const double s = (tau - times[i - 1]) / (times[i] - times[i - 1]);
        return levels[i - 1] + (levels[i] - levels[i - 1]) * (1 - std::cos(kPi * s)) / 2;
      };
    }
    case RealLikeDrive::Kind::kSamples: {
      if (d.samples.empty() || !(d.samples_fs_hz > 0))
        throw InputError("drive: a played drive needs samples and samples_fs_hz > 0");
      for (size_t i = 0; i < d.samples.size(); ++i)
        if (!std::isfinite(d.samples[i]))
          throw InputError("drive: sample " + std::to_string(i) + " is not finite");
      return [rest, level, s = d.samples, fs = d.samples_fs_hz](double t) {
        if (t < rest) return level;
        const double x = (t - rest) * fs;
        const size_t i = static_cast<size_t>(x);
        if (i + 1 >= s.size()) return s.back();
        return s[i] + (s[i + 1] - s[i]) * (x - static_cast<double>(i));
      };
    }
  }
  return [level](double) { return level; };
}

// The memory of dominant extrema: e[0] a maximum, then alternately minima and maxima, the last
// element the present input; empty = negative saturation. Wiping-out removes the pair an input
// passes.
class RealLikePlant::Memory {
 public:
  Memory(double lo, double hi) : lo_(lo), hi_(hi) {}
  void Update(double u) {
    u = std::clamp(u, lo_, hi_);
    if (e_.empty()) {
      if (u > lo_) e_.push_back(u);
      return;
    }
    const bool rising = e_.size() % 2 == 1;
    if (u == e_.back()) return;
    if (rising ? u > e_.back() : u < e_.back()) {
      e_.back() = u;
    } else {
      e_.push_back(u);
    }
    const bool up = e_.size() % 2 == 1;
    for (;;) {
      const size_t n = e_.size();
      if (n >= 3 && (up ? u >= e_[n - 3] : u <= e_[n - 3])) {
        e_.erase(e_.end() - 3, e_.end() - 1);
        continue;
      }
      if (!up && n == 2 && u <= lo_) e_.clear();
      break;
    }
  }
  const std::vector<double>& extrema() const { return e_; }

 private:
  double lo_, hi_;
  std::vector<double> e_;
};

RealLikePlant::RealLikePlant(const RealLikeStack& s) : stack_(s) {
  if (const std::string e = s.Validate(); !e.empty()) throw InputError(e);
  g_ = s.everett_grid;
  const int g = g_;
  const double h = 1.0 / g;  // normalised cell
  // Cell masses m(i, j), α-cell i ≥ β-cell j; the diagonal cells hold half a cell.
  std::vector<double> mass(static_cast<size_t>(g) * g, 0.0);
  for (int i = 0; i < g; ++i) {
    for (int j = 0; j <= i; ++j) {
      const double a = (i + 0.5) * h, b = (j + 0.5) * h;
      const double w = i == j ? h / 3 : a - b, c = (a + b) / 2 - 0.5;
      const double dw = (w - s.density_width) / s.density_width_spread,
                   dc = c / s.density_center_spread;
      const double mu = std::exp(-0.5 * dw * dw - 0.5 * dc * dc + s.asymmetry * c);
      mass[static_cast<size_t>(i) * g + j] = mu * h * h * (i == j ? 0.5 : 1.0);
    }
  }
  // F at nodes: F[A][B] = Σ_{i<A, j<B} m(i, j).
  table_.assign(static_cast<size_t>(g + 1) * (g + 1), 0.0);
  for (int A = 1; A <= g; ++A) {
    double row = 0;
    for (int B = 1; B <= g; ++B) {
      row += mass[static_cast<size_t>(A - 1) * g + (B - 1)];
      table_[static_cast<size_t>(A) * (g + 1) + B] =
          table_[static_cast<size_t>(A - 1) * (g + 1) + B] + row;
    }
  }
  total_ = table_.back();
  // The hysterons swing 2·total: scaled to the hysteretic share of the stroke.
  hyst_scale_ = s.hysteresis_share * s.stroke_um / (2 * total_);
  rev_scale_ = (1 - s.hysteresis_share) * s.stroke_um;
}

double RealLikePlant::Everett(double a, double b) const {
  const double range = stack_.u_hi - stack_.u_lo;
  const double x = std::clamp((a - stack_.u_lo) / range, 0.0, 1.0) * g_;
  const double y = std::clamp((b - stack_.u_lo) / range, 0.0, 1.0) * g_;
  const int i = std::min(static_cast<int>(x), g_ - 1), j = std::min(static_cast<int>(y), g_ - 1);
  const double fx = x - i, fy = y - j;
  const auto F = [&](int A, int B) { return table_[static_cast<size_t>(A) * (g_ + 1) + B]; };
  return (1 - fx) * (1 - fy) * F(i, j) + fx * (1 - fy) * F(i + 1, j) + (1 - fx) * fy * F(i, j + 1) +
         fx * fy * F(i + 1, j + 1);
}

double RealLikePlant::Hysteretic(const std::vector<double>& e) const {
  double p = 0;
  for (size_t k = 0; k < e.size(); k += 2) {
    const double prev_min = k == 0 ? stack_.u_lo : e[k - 1];
    const double next_min = k + 1 < e.size() ? e[k + 1] : stack_.u_hi;
    p += Everett(e[k], next_min) - Everett(e[k], prev_min);
  }
  return hyst_scale_ * (2 * p - total_);
}

double RealLikePlant::Reversible(double u) const {
  const double x =
      (std::clamp(u, stack_.u_lo, stack_.u_hi) - stack_.u_lo) / (stack_.u_hi - stack_.u_lo) - 0.5;
  return rev_scale_ * (x + stack_.quadratic * (x * x - 0.25));
}

std::vector<double> RealLikePlant::Static(const std::vector<double>& u) const {
  Memory m(stack_.u_lo, stack_.u_hi);
  std::vector<double> y;
  y.reserve(u.size());
  for (double v : u) {
    m.Update(v);
    y.push_back(Hysteretic(m.extrema()) + Reversible(v));
  }
  return y;
}

std::vector<double> RealLikePlant::Respond(const std::function<double(double)>& u, size_t samples,
                                           const RealLikeSensor& sensor) const {
  if (const std::string e = sensor.Validate(); !e.empty()) throw InputError(e);
  if (samples == 0) return {};
  const int os = sensor.oversample;
  const double dtf = 1 / (sensor.fs_hz * os);
  const size_t fine = (samples - 1) * static_cast<size_t>(os) + 1;
  const std::vector<double> taus = CreepTimes(stack_);
  const double c = stack_.creep_per_decade * std::log10(taus.size() > 1 ? taus[1] / taus[0] : 10.0);
  std::vector<double> decay(taus.size());
  for (size_t i = 0; i < taus.size(); ++i) decay[i] = std::exp(-dtf / taus[i]);
  Memory m(stack_.u_lo, stack_.u_hi);
  std::vector<double> z, s(fine);
  // The amplifier's low-pass τ ẋ = u − x, integrated exactly over each fine step for u linear in
  // it, from rest; its rate is (u − x)/τ. Without it, the analytic drive's rate by a central
  // difference.
  const double tau_d = stack_.driver_tau_s, a_d = tau_d > 0 ? std::exp(-dtf / tau_d) : 0;
  const double hd = 1e-3 * dtf;
  double x_d = 0, u_prev = 0, v_rate = 0;
  for (size_t j = 0; j < fine; ++j) {
    const double t = static_cast<double>(j) * dtf;
    double v = u(t);
    if (tau_d > 0 || stack_.rate_lag_v > 0) {
      const double applied = v;
      double rate = 0;
      if (tau_d > 0) {
        if (j == 0) {
          x_d = applied;
        } else {
          const double slope =
              (applied - u_prev) / dtf;  // u over the step: u_prev + slope (t' − t_prev)
          x_d = applied - tau_d * slope + a_d * (x_d - u_prev + tau_d * slope);
        }
        u_prev = applied;
        v = x_d;
        rate = (applied - x_d) / tau_d;
      } else if (t > hd) {
        rate = (u(t + hd) - u(t - hd)) / (2 * hd);
      }
      if (stack_.rate_lag_v > 0) {  // the effective drive held within ± lag of the applied one
        const double lag =
            stack_.rate_lag_v * std::tanh(stack_.rate_time_s * std::abs(rate) / stack_.rate_lag_v);
        v_rate = j == 0 ? v : std::clamp(v_rate, v - lag, v + lag);
        v = v_rate;
      }
    }
    m.Update(v);
    const double x = Hysteretic(m.extrema()) + Reversible(v);
    if (j == 0) z.assign(taus.size(), x);  // settled at rest
    double creep = 0;
    for (size_t i = 0; i < taus.size(); ++i) {
      z[i] = decay[i] * z[i] + (1 - decay[i]) * x;
      creep += c * (x - z[i]);
    }
    s[j] = x - creep;  // a step creeps up as 1 − Σ c e^{−t/τ}: log creep over the span
  }
  std::vector<double> y(samples);
  for (size_t k = 0; k < samples; ++k) {
    const double p = static_cast<double>(k * static_cast<size_t>(os)) - sensor.lag_samples * os;
    if (p <= 0) {
      y[k] = s[0];
      continue;
    }
    const size_t i = static_cast<size_t>(p);
    const double f = p - static_cast<double>(i);
    y[k] = i + 1 < fine ? (1 - f) * s[i] + f * s[i + 1] : s[i];
  }
  return y;
}

io::Record SynthesizeRealLikeRecord(const RealLikePlant& plant, const RealLikeSensor& sensor,
                                    const RealLikeDrive& drive, const std::string& name,
                                    model::CaseRole role, uint64_t seed, RealLikeRecordTruth* truth,
                                    std::vector<double>* clean_out) {
  if (const std::string e = sensor.Validate(); !e.empty()) throw InputError(e);
  const auto u = DriveFunction(drive);
  const size_t n =
      static_cast<size_t>(std::llround((drive.rest_s + drive.duration_s) * sensor.fs_hz)) + 1;
  if (n < 40)
    throw InputError("drive '" + name + "': " + std::to_string(n) +
                     " samples; at least 40 are needed");
  io::Record r;
  r.name = name;
  r.role = role;
  r.file = name + ".csv";
  r.dt = 1 / sensor.fs_hz;
  r.t.resize(n);
  r.u.resize(n);
  for (size_t k = 0; k < n; ++k) {
    r.t[k] = static_cast<double>(k) * r.dt;
    r.u[k] = Quantise(u(r.t[k]), sensor.drive_quantum_v);
  }
  const std::vector<double> clean = plant.Respond(u, n, sensor);
  opt::Rng rng(seed * 6364136223846793005ull + 1442695040888963407ull);
  const double offset = sensor.offset_range_um * (2 * rng.Uniform01() - 1);
  const double a = std::exp(-r.dt / sensor.colored_time_s);
  double colored = sensor.noise_colored_um * NormalDraw(rng);
  r.y.resize(n);
  for (size_t k = 0; k < n; ++k) {
    if (k > 0)
      colored = a * colored + sensor.noise_colored_um * std::sqrt(1 - a * a) * NormalDraw(rng);
    r.y[k] = Quantise(clean[k] + offset + sensor.noise_white_um * NormalDraw(rng) + colored,
                      sensor.quantum_um);
  }
  r.quantum = sensor.quantum_um;
  r.rest_samples = 1;
  while (r.rest_samples < n && r.u[r.rest_samples] == r.u[0]) ++r.rest_samples;
  r.first_scored = std::min(n - 1, r.rest_samples);
  r.end_scored = n;
  r.offset_mode = io::OffsetMode::kFit;
  if (drive.kind == RealLikeDrive::Kind::kSine) r.frequency_hz = drive.frequency_hz;
  if (truth) {
    truth->name = name;
    truth->role = model::CaseRoleName(role);
    truth->drive = drive.Describe();
    truth->offset_um = offset;
    double ss = 0;
    for (size_t k = r.first_scored; k < r.end_scored; ++k)
      ss += (r.y[k] - clean[k] - offset) * (r.y[k] - clean[k] - offset);
    truth->scored = r.scored();
    truth->noise_rms_um = std::sqrt(ss / static_cast<double>(r.scored()));
  }
  if (clean_out) *clean_out = clean;
  return r;
}

RealLikeSet GenerateRealLikeSet(const RealLikeOptions& o) {
  if (!(o.train_s > 0) || !(o.withheld_s > 0))
    throw InputError(FieldError("train_s", o.train_s, "and withheld_s must be > 0"));
  if (!(o.frequency_hz > 0) || o.frequency_hz > o.sensor.fs_hz / 8)
    throw InputError(FieldError("frequency_hz", o.frequency_hz, "must be in (0, fs/8]"));
  if (!(o.amplitude_share > 0 && o.amplitude_share <= 0.5))
    throw InputError(FieldError("amplitude_share", o.amplitude_share, "must be in (0, 0.5]"));
  for (const auto* list : {&o.train_frequencies_hz, &o.withheld_frequencies_hz})
    for (double f : *list)
      if (!(f > 0) || f > o.sensor.fs_hz / 8)
        throw InputError(FieldError(
            list == &o.train_frequencies_hz ? "train_frequencies_hz" : "withheld_frequencies_hz", f,
            "must be in (0, fs/8]"));
  if (o.chirp && o.train_frequencies_hz.empty())
    throw InputError("chirp: a chirp spans the training frequencies; give train_frequencies_hz");
  const RealLikePlant plant(o.stack);
  RealLikeSet out;
  out.options = o;
  out.set.source = "real-like stack (seed " + std::to_string(o.seed) + ")";
  out.set.format = "manifest";
  out.set.drive_unit = "V";
  out.set.response_unit = "um";
  opt::Rng rng(o.seed * 40503u + 3);
  RealLikeDrive base;
  base.rest_level = o.stack.u_lo;
  base.rest_s = 1;
  base.bias = (o.stack.u_lo + o.stack.u_hi) / 2;
  base.amplitude = o.amplitude_share * (o.stack.u_hi - o.stack.u_lo);
  base.frequency_hz = o.frequency_hz;
  struct Item {
    std::string name;
    model::CaseRole role;
    RealLikeDrive::Kind kind;
    double duration;
    double frequency = 0, frequency_end = 0;  ///< 0: base's
  };
  std::vector<Item> items;
  if (o.train_frequencies_hz.empty()) {
    items.push_back({"major", model::CaseRole::kTrain, RealLikeDrive::Kind::kSine, o.train_s});
  } else {
    for (double f : o.train_frequencies_hz)
      items.push_back({"train-" + Num(f) + "hz", model::CaseRole::kTrain,
                       RealLikeDrive::Kind::kSine, o.train_s, f});
  }
  if (o.second_sine)
    items.push_back(
        {"major-2", model::CaseRole::kValidate, RealLikeDrive::Kind::kSine, o.withheld_s});
  if (o.ramp)
    items.push_back(
        {"ramp", model::CaseRole::kValidate, RealLikeDrive::Kind::kRampedSine, o.withheld_s});
  if (o.reversals)
    items.push_back(
        {"reversals", model::CaseRole::kTest, RealLikeDrive::Kind::kReversals, o.withheld_s});
  for (double f : o.withheld_frequencies_hz)
    items.push_back({"sine-" + Num(f) + "hz", model::CaseRole::kValidate,
                     RealLikeDrive::Kind::kSine, o.withheld_s, f});
  if (o.chirp) {
    const auto [lo, hi] =
        std::minmax_element(o.train_frequencies_hz.begin(), o.train_frequencies_hz.end());
    items.push_back(
        {"chirp", model::CaseRole::kValidate, RealLikeDrive::Kind::kChirp, o.withheld_s, *lo, *hi});
  }
  double ss = 0;
  size_t n = 0;
  for (size_t i = 0; i < items.size(); ++i) {
    RealLikeDrive d = base;
    d.kind = items[i].kind;
    d.duration_s = items[i].duration;
    if (items[i].frequency > 0) d.frequency_hz = items[i].frequency;
    d.frequency_end_hz = items[i].frequency_end;
    d.phase_rad = 2 * kPi * rng.Uniform01();
    d.seed = o.seed * 1000 + i;
    if (i == 0 && !o.train_drive.empty()) {
      items[0].name = "played";
      d.kind = RealLikeDrive::Kind::kSamples;
      d.samples = o.train_drive;
      d.samples_fs_hz = o.sensor.fs_hz;
      d.rest_s = 0;
      d.rest_level = o.train_drive.front();
      d.duration_s = static_cast<double>(o.train_drive.size() - 1) / o.sensor.fs_hz;
    }
    RealLikeRecordTruth t;
    out.set.records.push_back(SynthesizeRealLikeRecord(plant, o.sensor, d, items[i].name,
                                                       items[i].role, o.seed * 1000 + 500 + i, &t));
    ss += t.noise_rms_um * t.noise_rms_um * static_cast<double>(t.scored);
    n += t.scored;
    out.truth.push_back(t);
  }
  out.nominal_floor_um = o.sensor.NominalFloor();
  out.realised_floor_um = std::sqrt(ss / static_cast<double>(n));
  // The noise-free major loop's width: the branches up and down over the training amplitude.
  const int steps = 400;
  std::vector<double> u;
  for (int k = 0; k <= steps; ++k)
    u.push_back(base.bias - base.amplitude + 2 * base.amplitude * k / steps);
  std::vector<double> loop = u;
  for (int k = steps; k >= 0; --k) loop.push_back(u[static_cast<size_t>(k)]);
  for (int k = 0; k <= steps; ++k)
    loop.push_back(u[static_cast<size_t>(k)]);  // the loop closes from here
  const std::vector<double> y = plant.Static(loop);
  const size_t up0 = 2 * (steps + 1);
  double width = 0, lo = y[up0], hi = y[up0];
  for (int k = 0; k <= steps; ++k) {
    const double up = y[up0 + static_cast<size_t>(k)],
                 down = y[2 * (steps + 1) - 1 - static_cast<size_t>(k)];
    width = std::max(width, std::abs(up - down));
    lo = std::min(lo, up);
    hi = std::max(hi, up);
  }
  out.major_loop_width = hi > lo ? width / (hi - lo) : 0;
  return out;
}

}  // namespace pz::synth
