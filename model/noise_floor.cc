#include "model/noise_floor.h"

#include <algorithm>
#include <cmath>
#include <string>

namespace pz::model {

double EstimateQuantum(std::span<const double> y) {
  std::vector<double> v(y.begin(), y.end());
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  if (v.size() < 2) return 0.0;
  double dmin = INFINITY;
  for (size_t i = 1; i < v.size(); ++i) dmin = std::min(dmin, v[i] - v[i - 1]);
  if (!(dmin > 0) || !std::isfinite(dmin)) return 0.0;
  for (int div = 1; div <= 16; ++div) {
    const double q = dmin / div;
    bool ok = true;
    for (double x : v) {
      const double r = x / q;
      if (std::abs(r - std::round(r)) > 1e-6 * std::max(1.0, 1e-3 * std::abs(r))) {
        ok = false;
        break;
      }
    }
    if (ok) return q;
  }
  // A printed grid: refine q on the values in order of magnitude (n = round(x / q) is sure for
  // small |x| while q is still rough), then check every value against the refined q.
  std::vector<double> by_size = v;
  std::sort(by_size.begin(), by_size.end(), [](double a, double b) { return std::abs(a) < std::abs(b); });
  for (int div = 1; div <= 16; ++div) {
    double q = dmin / div, sxn = 0, snn = 0;
    bool ok = true;
    for (double x : by_size) {
      const double n = std::round(x / q);
      if (std::abs(x - n * q) > 0.02 * q) {
        ok = false;
        break;
      }
      sxn += x * n;
      snn += n * n;
      if (snn > 0) q = sxn / snn;
    }
    if (!ok || !(q > 0)) continue;
    for (double x : v) {
      if (std::abs(x - std::round(x / q) * q) > 1e-3 * q) {
        ok = false;
        break;
      }
    }
    if (ok) return q;
  }
  return 0.0;
}

double PeriodDifferenceSquares(std::span<const double> y, size_t a, size_t period) {
  if (period < 2 || a + 2 * period > y.size())
    throw InputError("period difference: periods of " + std::to_string(period) + " samples from sample " +
                     std::to_string(a) + " need " + std::to_string(a + 2 * period) + " samples, the series has " +
                     std::to_string(y.size()));
  const size_t b = a + period;
  // d_k = y_{b+k} − y_{a+k} = noise difference (variance 2 s²) + whatever is not periodic (creep,
  // drift: slow). First differences of d remove the slow part: var(d_k − d_{k−1}) = 4 s².
  double sum2 = 0, prev = y[b] - y[a];
  for (size_t k = 1; k < period; ++k) {
    const double d = y[b + k] - y[a + k];
    sum2 += (d - prev) * (d - prev);
    prev = d;
  }
  return sum2;
}

CaseNoise EstimateCaseNoise(std::span<const double> y, int cycles, double quantum_deg) {
  if (y.empty()) throw InputError("noise floor: empty series");
  if (cycles < 1) throw InputError(FieldError("cycles", cycles, "must be >= 1"));
  for (size_t k = 0; k < y.size(); ++k)
    if (!std::isfinite(y[k]))
      throw InputError(FieldError("y[" + std::to_string(k) + "]", y[k], "must be finite"));
  CaseNoise n;
  n.quantum_deg = quantum_deg >= 0 ? quantum_deg : EstimateQuantum(y);
  n.quantisation_rms_deg = n.quantum_deg / std::sqrt(12.0);
  const size_t p = y.size() / static_cast<size_t>(cycles);
  if (cycles >= 2 && p >= 2) {
    const double sum2 = PeriodDifferenceSquares(y, (cycles - 2) * p, p);
    n.scatter_rms_deg = std::sqrt(sum2 / (p - 1) / 4.0);
    n.compared_samples = static_cast<int>(p);
  }
  n.floor_rms_deg = std::sqrt(n.quantisation_rms_deg * n.quantisation_rms_deg +
                              n.scatter_rms_deg * n.scatter_rms_deg);
  return n;
}

double SaturationAwareFloor(const CaseNoise& noise, std::span<const double> measured, std::span<const double> model,
                            double b1, double b2) {
  if (measured.size() != model.size() || measured.empty())
    throw InputError("saturation-aware floor: measured has " + std::to_string(measured.size()) +
                     " samples, model " + std::to_string(model.size()));
  const double v = noise.floor_rms_deg * noise.floor_rms_deg;
  const double tol = 1e-9 * std::max(1.0, std::max(std::abs(b1), std::abs(b2)));
  double sum = 0;
  for (size_t k = 0; k < measured.size(); ++k) {
    const bool sat = std::abs(model[k] - b1) <= tol || std::abs(model[k] - b2) <= tol;
    const double e = measured[k] - model[k];
    if (sat && noise.quantum_deg > 0 && std::abs(e) <= 1.01 * noise.quantum_deg) {
      sum += e * e;  // the plateau read off its extreme: rounding, not model error
    } else {
      sum += v;
    }
  }
  return std::sqrt(sum / static_cast<double>(measured.size()));
}

double PooledFloor(std::span<const CaseNoise> noise, std::span<const int> samples) {
  PZ_CHECK(noise.size() == samples.size());
  double num = 0, den = 0;
  for (size_t i = 0; i < noise.size(); ++i) {
    num += samples[i] * noise[i].floor_rms_deg * noise[i].floor_rms_deg;
    den += samples[i];
  }
  return den > 0 ? std::sqrt(num / den) : 0.0;
}

}  // namespace pz::model
