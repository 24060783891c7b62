#include "io/quantum.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace pz::io {

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
  std::sort(by_size.begin(), by_size.end(),
            [](double a, double b) { return std::abs(a) < std::abs(b); });
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

}  // namespace pz::io
