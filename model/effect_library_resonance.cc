#include "model/effect_library_resonance.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <numbers>
#include <unsupported/Eigen/FFT>

namespace pz::model {

PowerSpectrum WelchSpectrum(std::span<const double> x, double fs, size_t max_segment) {
  PowerSpectrum out;
  size_t seg = 16;
  if (x.size() < seg || !(fs > 0)) return out;
  while (2 * seg <= std::min(x.size(), max_segment)) seg *= 2;
  const size_t hop = seg / 2, bins = seg / 2 + 1;
  std::vector<double> win(seg);
  double wpow = 0;
  for (size_t i = 0; i < seg; ++i) {
    win[i] = 0.5 - 0.5 * std::cos(2 * std::numbers::pi * static_cast<double>(i) /
                                  static_cast<double>(seg));
    wpow += win[i] * win[i];
  }
  out.df = fs / static_cast<double>(seg);
  out.p.assign(bins, 0.0);
  Eigen::FFT<double> fft;
  std::vector<double> buf(seg);
  std::vector<std::complex<double>> X;
  size_t count = 0;
  for (size_t start = 0; start + seg <= x.size(); start += hop, ++count) {
    double mean = 0;
    for (size_t i = 0; i < seg; ++i) mean += x[start + i];
    mean /= static_cast<double>(seg);
    for (size_t i = 0; i < seg; ++i) buf[i] = (x[start + i] - mean) * win[i];
    fft.fwd(X, buf);
    for (size_t k = 0; k < bins; ++k) {
      const double one_sided = k == 0 || 2 * k == seg ? 1.0 : 2.0;
      out.p[k] += one_sided * std::norm(X[k]) / (static_cast<double>(seg) * wpow);
    }
  }
  for (double& v : out.p) v /= static_cast<double>(count);
  out.f.resize(bins);
  for (size_t k = 0; k < bins; ++k) out.f[k] = static_cast<double>(k) * out.df;
  return out;
}

double BandPower(const PowerSpectrum& s, double lo, double hi) {
  double sum = 0;
  for (size_t k = 1; k < s.p.size(); ++k)
    if (s.f[k] >= lo && s.f[k] <= hi) sum += s.p[k];
  return sum;
}

SpectralBand DominantBand(const PowerSpectrum& s, double f_min) {
  SpectralBand b;
  if (s.p.size() < 4) return b;
  size_t peak = 0;
  for (size_t k = 1; k + 1 < s.p.size(); ++k)
    if (s.f[k] >= f_min && (peak == 0 || s.p[k] > s.p[peak])) peak = k;
  if (peak == 0 || !(s.p[peak] > 0)) return b;
  b.found = true;
  // The peak between bins: a parabola through the log powers of the three bins about it.
  const double l0 = std::log(std::max(s.p[peak - 1], 1e-300)), l1 = std::log(s.p[peak]),
               l2 = std::log(std::max(s.p[peak + 1], 1e-300));
  const double den = l0 - 2 * l1 + l2;
  const double shift = den < 0 ? std::clamp(0.5 * (l0 - l2) / den, -0.5, 0.5) : 0.0;
  b.f_peak = (static_cast<double>(peak) + shift) * s.df;
  b.f_lo = 0.6 * b.f_peak;
  b.f_hi = 1.4 * b.f_peak;
  const double total = BandPower(s, s.df / 2, s.f.back());
  const double in = BandPower(s, b.f_lo, b.f_hi);
  b.share = total > 0 ? in / total : 0;
  size_t n_in = 0;
  for (size_t k = 1; k < s.p.size(); ++k) n_in += s.f[k] >= b.f_lo && s.f[k] <= b.f_hi;
  const size_t n_out = s.p.size() - 1 - n_in;
  b.contrast = n_out == 0 || !(total - in > 0)
                   ? (in > 0 ? 1e300 : 0)
                   : (in / static_cast<double>(n_in)) / ((total - in) / static_cast<double>(n_out));
  // Half-power points of the spectrum smoothed over three bins (a Welch estimate scatters by a
  // third from bin to bin: the raw peak is often a high draw and its neighbours low ones), linearly
  // interpolated between bins.
  std::vector<double> q(s.p.size());
  for (size_t k = 0; k < q.size(); ++k)
    q[k] = (s.p[k > 0 ? k - 1 : k] + s.p[k] + s.p[k + 1 < q.size() ? k + 1 : k]) / 3;
  const double half = q[peak] / 2;
  size_t i = peak, j = peak;
  while (i > 1 && q[i - 1] > half) --i;
  while (j + 1 < q.size() && q[j + 1] > half) ++j;
  const double f1 = i > 1 ? s.f[i - 1] + s.df * (half - q[i - 1]) / (q[i] - q[i - 1]) : s.f[i];
  const double f2 = j + 1 < q.size() ? s.f[j] + s.df * (q[j] - half) / (q[j] - q[j + 1]) : s.f[j];
  b.zeta = std::clamp((f2 - f1) / (2 * b.f_peak), s.df / (2 * b.f_peak), 0.5);
  return b;
}

SpectralBand RingingBand(std::span<const double> rest, double fs, double f_min) {
  if (rest.size() < 64) return {};
  // The least-squares line removed: the rest's settling and creep are not its ringing.
  const double n = static_cast<double>(rest.size());
  double st = 0, sy = 0, stt = 0, sty = 0;
  for (size_t k = 0; k < rest.size(); ++k) {
    const double t = static_cast<double>(k);
    st += t;
    sy += rest[k];
    stt += t * t;
    sty += t * rest[k];
  }
  const double slope = (n * sty - st * sy) / (n * stt - st * st), icpt = (sy - slope * st) / n;
  std::vector<double> x(rest.size());
  for (size_t k = 0; k < rest.size(); ++k) x[k] = rest[k] - icpt - slope * static_cast<double>(k);
  return DominantBand(WelchSpectrum(x, fs, 1024), f_min);
}

}  // namespace pz::model
