#include "synth/reallike_ring.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "model/status.h"
#include "opt/random.h"
#include "synth/synthetic.h"

namespace pz::synth {
namespace {

constexpr double kPi = std::numbers::pi;

/// The stage's mode on the stack's response s (sampled at dt): ẍ = ω²(s − x) − 2ζω ẋ, s linear
/// between samples, 20 symplectic-Euler sub-steps per sample (ω dt / 20 ≤ 0.03 at 740 Hz and
/// 10 kHz), starting `step` above s[0] at rest (the step to the rest level just made) and with the
/// step's relaxation `settle` e^{−t/τ} added to s.
std::vector<double> Mode(const std::vector<double>& s, double dt, const RingingOptions& o) {
  const double w = 2 * kPi * o.mode_hz, h = dt / 20;
  std::vector<double> x(s.size());
  auto in = [&](size_t k) {
    return s[k] + o.settle_um * std::exp(-static_cast<double>(k) * dt / o.settle_s);
  };
  double pos = in(0) + o.step_um, vel = 0;
  for (size_t k = 0; k < s.size(); ++k) {
    x[k] = pos;
    if (k + 1 == s.size()) break;
    const double a = in(k), b = in(k + 1);
    for (int j = 0; j < 20; ++j) {
      const double target = a + (b - a) * (j + 0.5) / 20;
      vel += h * (w * w * (target - pos) - 2 * o.mode_zeta * w * vel);
      pos += h * vel;
    }
  }
  return x;
}

/// The drive samples after the rest: nested loops growing from u_lo at f, or (f < 0: a triangle)
/// a sine / triangle at |f| through 90 % of the range with `chatter` (RMS, drive units) added.
std::vector<double> Drive(const RingingOptions& o, double f, double seconds, bool loops,
                          const std::vector<double>& chatter) {
  const double lo = o.stack.u_lo, range = o.stack.u_hi - o.stack.u_lo, fs = o.sensor.fs_hz;
  const size_t n = static_cast<size_t>(std::llround(seconds * fs)) + 1;
  std::vector<double> u(n);
  for (size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / fs;
    if (loops) {
      u[k] = lo + (t / seconds) * range * (1 - std::cos(2 * kPi * f * t)) / 2;
    } else {
      const double phase = std::abs(f) * t - std::floor(std::abs(f) * t);
      const double shape = f > 0 ? -std::cos(2 * kPi * phase) : 1 - 4 * std::abs(phase - 0.5);
      // from the rest at the bottom: the shape starts at −1 (its minimum), 5 % above u_lo
      u[k] = lo + 0.05 * range + 0.9 * range * (1 + shape) / 2;
      u[k] = std::clamp(u[k] + (k < chatter.size() ? chatter[k] : 0), lo, lo + range);
    }
  }
  return u;
}

}  // namespace

RingingOptions RingingDefaults() {
  RingingOptions o;
  RealLikeStack& s = o.stack;
  s.u_lo = -90;
  s.u_hi = 90;
  s.stroke_um = 35;
  s.hysteresis_share = 0.22;
  s.density_width = 0.35;
  s.density_width_spread = 0.25;
  s.density_center_spread = 0.35;
  s.asymmetry = -0.8;
  s.quadratic = 0.08;
  s.creep_per_decade = 0.01;
  s.creep_tau_min_s = 0.01;
  s.creep_tau_max_s = 10;
  RealLikeSensor& se = o.sensor;
  se.fs_hz = 10000;
  se.oversample = 2;
  se.lag_samples = 2.4;
  se.noise_white_um = 0.0012;
  se.noise_colored_um = 0.02;
  se.colored_time_s = 0.1;
  se.quantum_um = 0;
  se.drive_quantum_v = 180.0 / 65536;
  se.offset_range_um = 20;
  return o;
}

RingingSet GenerateRingingSet(const RingingOptions& o) {
  if (!(o.mode_hz > 0 && o.mode_hz < o.sensor.fs_hz / 4))
    throw InputError(FieldError("mode_hz", o.mode_hz, "must be in (0, fs/4)"));
  if (!(o.mode_zeta > 0 && o.mode_zeta < 1))
    throw InputError(FieldError("mode_zeta", o.mode_zeta, "must be in (0, 1)"));
  if (!(o.settle_s > 0) || !(o.rest_s > 0) || !(o.loops_s > 0) || !(o.chatter_s > 0))
    throw InputError("ringing set: settle_s, rest_s, loops_s and chatter_s must be > 0");
  if (o.repeats < 0 || o.repeats == 1)
    throw InputError(FieldError("repeats", o.repeats, "must be 0 or ≥ 2"));
  const RealLikePlant plant(o.stack);
  RealLikeSensor clean_sensor = o.sensor;  // the plant's response without noise; noise added here
  clean_sensor.noise_white_um = clean_sensor.noise_colored_um = 0;
  RingingSet out;
  out.options = o;
  out.set.source = "ringing stage (seed " + std::to_string(o.seed) + ")";
  out.set.format = "manifest";
  opt::Rng rng(o.seed * 7919u + 5);
  struct Item {
    std::string name, repeat;
    model::CaseRole role;
    std::vector<double> drive;
    std::string what;
  };
  std::vector<Item> items;
  for (double f : o.train_loops_hz)
    items.push_back({"loops-" + std::to_string(static_cast<int>(f)) + "hz", "",
                     model::CaseRole::kTrain, Drive(o, f, o.loops_s, true, {}),
                     "loops growing from the bottom at " + std::to_string(f) + " Hz"});
  for (double f : o.withheld_loops_hz)
    items.push_back({"loops-" + std::to_string(static_cast<int>(f)) + "hz", "",
                     model::CaseRole::kValidate, Drive(o, f, o.loops_s, true, {}),
                     "loops growing from the bottom at " + std::to_string(f) + " Hz"});
  if (o.repeats >= 2) {
    const double range = o.stack.u_hi - o.stack.u_lo;
    for (const char* shape : {"sine", "triangle"}) {
      std::vector<double> chatter(static_cast<size_t>(o.chatter_s * o.sensor.fs_hz) + 1);
      for (double& c : chatter) c = o.chatter_share * range * NormalDraw(rng);
      const double f = std::string(shape) == "sine" ? o.chatter_hz : -o.chatter_hz;
      const std::vector<double> u = Drive(o, f, o.chatter_s, false, chatter);
      for (int r = 0; r < o.repeats; ++r)
        items.push_back(
            {std::string(shape) + "-chatter-" + std::to_string(r + 1),
             std::string(shape) + "-chatter", model::CaseRole::kTest, u,
             std::string("a ") + shape + " with chatter (repeat " + std::to_string(r + 1) + ")"});
    }
  }
  double ss = 0, ss_white = 0;
  size_t n = 0;
  for (size_t i = 0; i < items.size(); ++i) {
    RealLikeDrive d;
    d.kind = RealLikeDrive::Kind::kSamples;
    d.rest_level = o.stack.u_lo;
    d.rest_s = o.rest_s;
    d.samples = items[i].drive;
    d.samples_fs_hz = o.sensor.fs_hz;
    d.duration_s = static_cast<double>(d.samples.size() - 1) / o.sensor.fs_hz;
    std::vector<double> clean;
    io::Record r = SynthesizeRealLikeRecord(plant, clean_sensor, d, items[i].name, items[i].role,
                                            o.seed * 1000 + i, nullptr, &clean);
    clean = Mode(clean, r.dt, o);
    opt::Rng noise(o.seed * 104729u + 31 * i + 7);
    const double offset = o.sensor.offset_range_um * (2 * noise.Uniform01() - 1);
    const double a = std::exp(-r.dt / o.sensor.colored_time_s);
    double wander = o.sensor.noise_colored_um * NormalDraw(noise);
    RealLikeRecordTruth t;
    std::vector<double> e;  // the noise over the window
    for (size_t k = 0; k < r.size(); ++k) {
      if (k > 0)
        wander = a * wander + o.sensor.noise_colored_um * std::sqrt(1 - a * a) * NormalDraw(noise);
      const double white = o.sensor.noise_white_um * NormalDraw(noise);
      r.y[k] = clean[k] + offset + wander + white;
      if (k >= r.first_scored && k < r.end_scored) {
        e.push_back(wander + white);
        ss_white += white * white;
      }
    }
    // What a perfect model leaves with the record's offset fitted: the noise less its mean.
    double mean = 0;
    for (double v : e) mean += v / static_cast<double>(e.size());
    for (double v : e) t.noise_rms_um += (v - mean) * (v - mean);
    r.repeat = items[i].repeat;
    r.quantum = 0;
    t.name = r.name;
    t.role = model::CaseRoleName(r.role);
    t.drive = "rest " + std::to_string(o.rest_s) + " s at " + std::to_string(o.stack.u_lo) +
              " V, then " + items[i].what;
    t.offset_um = offset;
    t.scored = r.scored();
    ss += t.noise_rms_um;
    n += t.scored;
    t.noise_rms_um = std::sqrt(t.noise_rms_um / static_cast<double>(t.scored));
    out.truth.push_back(t);
    out.set.records.push_back(std::move(r));
  }
  out.realised_floor_um = std::sqrt(ss / static_cast<double>(n));
  out.sensor_floor_um = std::sqrt(ss_white / static_cast<double>(n));
  return out;
}

}  // namespace pz::synth
