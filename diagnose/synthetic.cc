#include "diagnose/synthetic.h"

#include <cmath>
#include <numbers>

namespace pz::records {

double NormalDraw(opt::Rng& rng) {
  const double a = 1 - rng.Uniform01(), b = rng.Uniform01();
  return std::sqrt(-2 * std::log(a)) * std::cos(2 * std::numbers::pi * b);
}

const char* WaveformName(Waveform w) {
  switch (w) {
    case Waveform::kSine:
      return "sine";
    case Waveform::kMultisine:
      return "multisine";
    case Waveform::kTriangle:
      return "triangle";
    case Waveform::kSquare:
      return "square";
    case Waveform::kSweep:
      return "sweep";
  }
  return "?";
}

std::vector<double> MakeDrive(const DriveShape& s) {
  if (!(s.fs_hz > 0) || !(s.duration_s > 0) || !(s.rest_s >= 0) || !(s.frequency_hz > 0) ||
      !(s.amplitude >= 0)) {
    throw InputError(
        "drive shape: fs, duration and frequency must be > 0, rest and amplitude >= 0");
  }
  const double pi2 = 2 * std::numbers::pi;
  const size_t rest = static_cast<size_t>(std::llround(s.rest_s * s.fs_hz));
  const size_t n = rest + static_cast<size_t>(std::llround(s.duration_s * s.fs_hz));
  std::vector<double> u(n + 1, s.bias);
  std::vector<double> freqs, phases;
  if (s.waveform == Waveform::kMultisine) {
    opt::Rng rng(s.seed);
    const int L = std::max(1, s.lines);
    for (int i = 0; i < L; ++i) {
      const double f = L == 1 ? s.frequency_hz
                              : s.frequency_hz * std::pow(s.frequency_end_hz / s.frequency_hz,
                                                          double(i) / (L - 1));
      freqs.push_back(f);
      phases.push_back(pi2 * rng.Uniform01());
    }
  }
  const double slew = std::max(s.slew_s, 1 / s.fs_hz);
  for (size_t k = rest; k <= n; ++k) {
    const double t = static_cast<double>(k - rest) / s.fs_hz;
    double v = 0;
    const double cyc = s.frequency_hz * t + s.phase_rad / pi2;
    switch (s.waveform) {
      case Waveform::kSine:
        v = std::sin(pi2 * cyc);
        break;
      case Waveform::kTriangle: {
        const double x = cyc + 0.25 - std::floor(cyc + 0.25);  // sin-aligned triangle
        v = x < 0.5 ? 4 * x - 1 : 3 - 4 * x;
        break;
      }
      case Waveform::kSquare: {
        // A square wave with linear edges of duration `slew`, aligned with the sine's sign.
        const double period = 1 / s.frequency_hz;
        const double x = (cyc - std::floor(cyc)) * period;
        const double half = period / 2;
        if (x < slew)
          v = -1 + 2 * x / slew;
        else if (x < half)
          v = 1;
        else if (x < half + slew)
          v = 1 - 2 * (x - half) / slew;
        else
          v = -1;
        break;
      }
      case Waveform::kSweep: {
        const double T = s.duration_s, f0 = s.frequency_hz, f1 = s.frequency_end_hz;
        v = std::sin(pi2 * (f0 * t + (f1 - f0) * t * t / (2 * T)) + s.phase_rad);
        break;
      }
      case Waveform::kMultisine: {
        double acc = 0, norm = 0;
        for (size_t i = 0; i < freqs.size(); ++i) {
          acc += std::sin(pi2 * freqs[i] * t + phases[i] + s.phase_rad);
          norm += 1;
        }
        v = acc / std::sqrt(2 * norm) * 1.0;  // RMS ≈ 1/2: peaks near ±1
        v = std::max(-1.0, std::min(1.0, v));
        break;
      }
    }
    u[k] = s.bias + s.amplitude * v;
  }
  return u;
}

DataScale SyntheticStackScale() {
  DataScale s;
  s.u_min = -100;
  s.u_max = 100;
  s.u_half = 100;
  s.y_half = 10;
  s.gain = 0.1;
  s.f_dom = 1;
  s.fs = 500;
  s.duration = 4;
  return s;
}

io::Record SynthesizeRecord(const RecordModel& truth, std::span<const double> params,
                            std::span<const double> weights, const DriveShape& shape,
                            const Measurement& m, const std::string& name, model::CaseRole role,
                            double t0_s, double t1_s) {
  io::Record r;
  r.name = name;
  r.role = role;
  r.file = name + ".csv";
  r.u = MakeDrive(shape);
  const size_t n = r.u.size();
  r.dt = 1 / shape.fs_hz;
  r.t.resize(n);
  for (size_t k = 0; k < n; ++k) r.t[k] = static_cast<double>(k) * r.dt;
  r.rest_samples = 1;
  while (r.rest_samples < n && r.u[r.rest_samples] == r.u[0]) ++r.rest_samples;
  r.first_scored = std::min(n - 1, r.rest_samples);
  r.end_scored = n;
  r.y.assign(n, 0);
  truth.Simulate(r, params, weights, n, r.y);
  opt::Rng rng(m.seed * 7919 + 17);
  for (double& v : r.y) {
    v += m.offset + (m.noise_std > 0 ? m.noise_std * NormalDraw(rng) : 0);
    if (m.quantum > 0) v = m.quantum * std::round(v / m.quantum);
  }
  r.quantum = m.quantum;
  if (t1_s > t0_s) io::SetWindow(r, t0_s, t1_s, 20, "window of " + name);
  return r;
}

}  // namespace pz::records
