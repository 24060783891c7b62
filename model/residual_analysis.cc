#include "model/residual_analysis.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <cstdio>
#include <numbers>

namespace pz::model {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kReversalHalfWidthDeg = 20.0;

std::string Fmt(const char* fmt, double a, double b = 0, double c = 0, double d = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, fmt, a, b, c, d);
  return buf;
}

void Merge(BinStat& into, const BinStat& b) {
  // Both finished: recombine Σe² and Σe.
  const double s2 = into.rms * into.rms * into.n + b.rms * b.rms * b.n;
  const double s1 = into.mean * into.n + b.mean * b.n;
  into.n += b.n;
  into.rms = into.n ? std::sqrt(s2 / into.n) : 0;
  into.mean = into.n ? s1 / into.n : 0;
}

// Fourier coefficient (2/M Σ x_j e^{−i k ω t_j}) over samples [a, b).
std::complex<double> Coef(std::span<const double> x, size_t a, size_t b, double om, double fs,
                          int k) {
  std::complex<double> s = 0;
  for (size_t j = a; j < b; ++j) {
    const double ph = k * om * (static_cast<double>(j) / fs);
    s += x[j] * std::complex<double>(std::cos(ph), -std::sin(ph));
  }
  return s * (2.0 / static_cast<double>(b - a));
}

size_t PerCycle(size_t n, int cycles) { return n / static_cast<size_t>(cycles); }

}  // namespace

void BinStat::Finish() {
  if (n > 0) {
    rms = std::sqrt(rms / n);
    mean /= n;
  }
}

LoopFeatures ComputeLoop(std::span<const double> y, double amplitude_v, double frequency_hz,
                         double sample_rate_hz, int cycles, double quantum_deg) {
  LoopFeatures lf;
  const size_t n = y.size();
  const size_t p = PerCycle(n, cycles);
  if (p < 4) return lf;
  const double om = 2 * kPi * frequency_hz, fs = sample_rate_hz;
  const size_t a = (cycles - 1) * p, b = a + p;
  auto u = [&](size_t k) { return amplitude_v * std::sin(om * static_cast<double>(k) / fs); };
  double ymax = -INFINITY, ymin = INFINITY;
  for (size_t k = a; k < b; ++k) {
    ymax = std::max(ymax, y[k]);
    ymin = std::min(ymin, y[k]);
  }
  lf.offset_deg = 0.5 * (ymax + ymin);
  lf.peak_to_peak_deg = ymax - ymin;
  // Area ∮ u dy = −∮ y du over one cycle (positive when y lags u).
  for (size_t k = a; k < b; ++k) {
    const size_t k1 = k + 1 < b ? k + 1 : a;  // closed: the cycle's last sample joins its first
    lf.area_deg_v -= 0.5 * (y[k] + y[k1]) * (u(k1) - u(k));
  }
  // y at the zero crossings of u: rising crossing at phase 0, falling at phase 180 (interpolated).
  auto at_phase = [&](double phase_deg) {
    const double tc = (static_cast<double>(a) / fs) + phase_deg / 360.0 / frequency_hz;
    const double r = tc * fs;
    const size_t i = std::min(static_cast<size_t>(r), n - 2);
    const double w = r - static_cast<double>(i);
    return (1 - w) * y[i] + w * y[i + 1];
  };
  lf.width_deg = at_phase(180.0) - at_phase(0.0);
  const double tol = quantum_deg > 0 ? 0.5 * quantum_deg : 1e-9 * std::max(1.0, std::abs(ymax));
  for (size_t k = a; k < b; ++k) {
    if (y[k] >= ymax - tol) {
      lf.top_phase_deg = 360.0 * frequency_hz * (static_cast<double>(k - a) / fs);
      break;
    }
  }
  if (cycles >= 2) {
    const size_t s = p;  // later cycles
    const std::complex<double> cy = Coef(y, s, cycles * p, om, fs, 1);
    std::complex<double> cu = 0;
    for (size_t j = s; j < cycles * p; ++j) {
      const double ph = om * (static_cast<double>(j) / fs);
      cu += u(j) * std::complex<double>(std::cos(ph), -std::sin(ph));
    }
    double lag = (std::arg(cu) - std::arg(cy)) * 180.0 / kPi;
    while (lag > 180) lag -= 360;
    while (lag <= -180) lag += 360;
    lf.phase_lag_deg = lag;
    lf.fundamental_deg = std::abs(cy);
  }
  return lf;
}

namespace {

/// Time (cycle means, the trend over the later cycles) and frequency (harmonics over the later
/// cycles, low-frequency content) of a case's residuals e.
void AddTimeAndFrequency(const ResidualCaseInput& in, const std::vector<double>& e, size_t p,
                         CaseResidual& c) {
  const size_t n = e.size();
  const double fs = in.sample_rate_hz, om = 2 * kPi * in.frequency_hz;
  for (int cy = 0; cy < in.cycles && p > 0; ++cy) {
    double s = 0;
    for (size_t k = cy * p; k < (cy + 1) * p; ++k) s += e[k];
    c.cycle_mean.push_back(s / p);
  }
  const size_t a = in.cycles >= 2 ? p : 0, b = in.cycles >= 1 && p > 0 ? in.cycles * p : n;
  {
    double st = 0, se = 0, stt = 0, ste = 0;
    const double m = static_cast<double>(b - a);
    for (size_t k = a; k < b; ++k) {
      const double t = static_cast<double>(k) / fs;
      st += t;
      se += e[k];
      stt += t * t;
      ste += t * e[k];
    }
    const double sxx = stt - st * st / m;
    if (sxx > 0) {
      c.trend_deg_per_s = (ste - st * se / m) / sxx;
      c.trend_se = c.floor_rms / std::sqrt(sxx);
    }
  }
  // Frequency: harmonics over the later cycles, low-frequency content.
  if (b > a + 4) {
    double mean = 0;
    for (size_t k = a; k < b; ++k) mean += e[k];
    mean /= static_cast<double>(b - a);
    c.harmonic[0] = std::abs(mean);
    double odd = 0, even = 0;
    for (int k = 1; k <= kHarmonics; ++k) {
      c.harmonic[k] = std::abs(Coef(e, a, b, om, fs, k));
      (k % 2 ? odd : even) += 0.5 * c.harmonic[k] * c.harmonic[k];
    }
    c.odd_rms = std::sqrt(odd);
    c.even_rms = std::sqrt(even);
    c.harmonic_noise = 2.0 * c.floor_rms / std::sqrt(static_cast<double>(b - a));
  }
  if (p > 0 && n >= p) {
    // One-cycle moving average (valid part): removes every harmonic of f, keeps DC and trends.
    double s = 0, s2 = 0;
    int cnt = 0;
    for (size_t k = 0; k < p; ++k) s += e[k];
    for (size_t k = p;; ++k) {
      const double avg = s / p;
      s2 += avg * avg;
      ++cnt;
      if (k >= n) break;
      s += e[k] - e[k - p];
    }
    c.low_rms = std::sqrt(s2 / cnt);
  }
}

/// One case's residuals: their statistics over the cycle, in time and in frequency, and both
/// loops.
CaseResidual AnalyseCase(const ResidualCaseInput& in) {
  const std::string where = "case " + std::to_string(in.number) + ": ";
  const size_t n = in.measured.size();
  if (n < 4 || in.model.size() != n)
    throw InputError(where + "measured has " + std::to_string(n) + " samples, model " +
                     std::to_string(in.model.size()) + " (need equal, >= 4)");
  if (!(in.frequency_hz > 0) || !(in.sample_rate_hz > 0) || in.cycles < 1)
    throw InputError(where + "frequency, sample rate and cycles must be > 0");
  for (size_t k = 0; k < n; ++k)
    if (!std::isfinite(in.measured[k]) || !std::isfinite(in.model[k]))
      throw InputError(where + FieldError("sample", k, "non-finite value"));

  CaseResidual c;
  c.number = in.number;
  c.training = in.training;
  c.amplitude_v = in.amplitude_v;
  c.frequency_hz = in.frequency_hz;
  c.samples = static_cast<int>(n);
  c.floor_rms = in.floor_rms_deg;
  const double fs = in.sample_rate_hz, om = 2 * kPi * in.frequency_hz;
  const size_t p = PerCycle(n, in.cycles);
  std::vector<double> e(n);
  double ymax = -INFINITY, ymin = INFINITY;
  for (size_t k = 0; k < n; ++k) {
    e[k] = in.measured[k] - in.model[k];
    ymax = std::max(ymax, in.measured[k]);
    ymin = std::min(ymin, in.measured[k]);
  }
  const double sat_tol = in.quantum_deg > 0 ? 0.5 * in.quantum_deg : 1e-9;
  for (size_t k = 0; k < n; ++k) {
    const double ek = e[k];
    c.pi += ek * ek;
    c.max_abs = std::max(c.max_abs, std::abs(ek));
    const double t = static_cast<double>(k) / fs;
    double phase = std::fmod(360.0 * in.frequency_hz * t, 360.0);
    if (phase < 0) phase += 360.0;
    const bool later = p == 0 || k >= p;
    (later ? c.later_cycles : c.first_cycle).Add(ek);
    if (!later) continue;
    c.phase[std::min(kPhaseBins - 1, static_cast<int>(phase / (360.0 / kPhaseBins)))].Add(ek);
    (std::cos(om * t) > 0 ? c.rising : c.falling).Add(ek);
    if (std::abs(phase - 90.0) < kReversalHalfWidthDeg ||
        std::abs(phase - 270.0) < kReversalHalfWidthDeg)
      c.near_reversal.Add(ek);
    if (in.measured[k] >= ymax - sat_tol || in.measured[k] <= ymin + sat_tol)
      c.in_saturation.Add(ek);
  }
  c.rms = std::sqrt(c.pi / n);
  c.rms_over_floor = c.floor_rms > 0 ? c.rms / c.floor_rms : INFINITY;
  for (auto& b : c.phase) b.Finish();
  for (BinStat* b :
       {&c.rising, &c.falling, &c.near_reversal, &c.in_saturation, &c.first_cycle, &c.later_cycles})
    b->Finish();
  AddTimeAndFrequency(in, e, p, c);
  c.measured_loop =
      ComputeLoop(in.measured, in.amplitude_v, in.frequency_hz, fs, in.cycles, in.quantum_deg);
  c.model_loop =
      ComputeLoop(in.model, in.amplitude_v, in.frequency_hz, fs, in.cycles, in.quantum_deg);
  return c;
}

/// The cases' shares and the training and withheld groups.
void MergeGroups(double total_pi, ResidualAnalysis& out) {
  for (CaseResidual& c : out.cases) {
    c.share = total_pi > 0 ? c.pi / total_pi : 0;
    GroupResidual& g = c.training ? out.training : out.withheld;
    g.cases += 1;
    g.samples += c.samples;
    g.pi += c.pi;
    g.floor_rms += c.samples * c.floor_rms * c.floor_rms;
    if (c.rms > g.worst_rms) {
      g.worst_rms = c.rms;
      g.worst_case = c.number;
    }
    for (int i = 0; i < kPhaseBins; ++i) Merge(g.phase[i], c.phase[i]);
    Merge(g.rising, c.rising);
    Merge(g.falling, c.falling);
    Merge(g.near_reversal, c.near_reversal);
    Merge(g.in_saturation, c.in_saturation);
    Merge(g.first_cycle, c.first_cycle);
    Merge(g.later_cycles, c.later_cycles);
    g.odd_rms += c.odd_rms * c.odd_rms;
    g.even_rms += c.even_rms * c.even_rms;
    g.low_rms += c.low_rms * c.low_rms;
    g.harmonic_noise += c.harmonic_noise * c.harmonic_noise;
  }
  for (GroupResidual* g : {&out.training, &out.withheld}) {
    if (g->samples == 0) continue;
    g->rms = std::sqrt(g->pi / g->samples);
    g->floor_rms = std::sqrt(g->floor_rms / g->samples);
    g->odd_rms = std::sqrt(g->odd_rms / g->cases);
    g->even_rms = std::sqrt(g->even_rms / g->cases);
    g->low_rms = std::sqrt(g->low_rms / g->cases);
    g->harmonic_noise = std::sqrt(g->harmonic_noise / g->cases);
  }
}

/// Findings, against the floor (withheld cases first: they carry the verdict).
void AddFindings(ResidualAnalysis& out) {
  auto& f = out.findings;
  for (const auto* gp : {&out.withheld, &out.training}) {
    const GroupResidual& g = *gp;
    if (g.cases == 0) continue;
    const char* name = gp == &out.withheld ? "withheld" : "training";
    f.push_back(std::string(name) +
                Fmt(" cases: RMS %.4f deg = %.2f x the noise floor %.4f deg; worst case %.0f",
                    g.rms, g.floor_rms > 0 ? g.rms / g.floor_rms : INFINITY, g.floor_rms,
                    g.worst_case) +
                Fmt(" at %.4f deg", g.worst_rms));
  }
  const GroupResidual& w = out.withheld.cases ? out.withheld : out.training;
  if (w.cases) {
    const double fl = std::max(w.floor_rms, 1e-12);
    f.push_back(Fmt("over the cycle: rising branch %.4f, falling %.4f, near reversals %.4f, in "
                    "saturation %.4f deg RMS",
                    w.rising.rms, w.falling.rms, w.near_reversal.rms, w.in_saturation.rms) +
                Fmt(" (floor %.4f)", fl));
    f.push_back(Fmt(
        "over time: first cycle %.4f vs later cycles %.4f deg RMS (%.2f vs %.2f x floor)",
        w.first_cycle.rms, w.later_cycles.rms, w.first_cycle.rms / fl, w.later_cycles.rms / fl));
    f.push_back(
        Fmt("in frequency: odd harmonics %.4f, even harmonics %.4f, DC/low frequency %.4f deg RMS",
            w.odd_rms, w.even_rms, w.low_rms) +
        Fmt(" (one-bin noise %.4f deg)", w.harmonic_noise));
    double lag_m = 0, lag_s = 0, width_m = 0, width_s = 0;
    int cnt = 0;
    for (const CaseResidual& c : out.cases) {
      if (c.training && out.withheld.cases) continue;
      lag_m += c.measured_loop.phase_lag_deg;
      lag_s += c.model_loop.phase_lag_deg;
      width_m += c.measured_loop.width_deg;
      width_s += c.model_loop.width_deg;
      ++cnt;
    }
    if (cnt)
      f.push_back(
          Fmt("in the loop (mean over cases): phase lag measured %.2f vs model %.2f deg, width at "
              "u = 0 measured "
              "%.4f vs model %.4f deg",
              lag_m / cnt, lag_s / cnt, width_m / cnt, width_s / cnt));
  }
}

}  // namespace

ResidualAnalysis AnalyseResiduals(std::span<const ResidualCaseInput> inputs) {
  ResidualAnalysis out;
  double total_pi = 0;
  for (const ResidualCaseInput& in : inputs) {
    CaseResidual c = AnalyseCase(in);
    total_pi += c.pi;
    out.cases.push_back(std::move(c));
  }
  MergeGroups(total_pi, out);
  AddFindings(out);
  return out;
}

}  // namespace pz::model
