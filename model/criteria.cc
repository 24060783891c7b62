#include "model/criteria.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "model/metrics.h"

namespace pz::model {
namespace {

void CheckSeries(std::span<const double> y, std::span<const double> yhat) {
  if (y.size() != yhat.size()) {
    throw InputError("criteria: y has " + std::to_string(y.size()) + " samples, yhat has " +
                     std::to_string(yhat.size()));
  }
  if (y.empty()) throw InputError("criteria: y and yhat are empty");
  for (size_t k = 0; k < y.size(); ++k) {
    if (!std::isfinite(y[k]))
      throw InputError(
          FieldError("criteria: y[" + std::to_string(k) + "]", y[k], "must be finite"));
    if (!std::isfinite(yhat[k])) {
      throw InputError(
          FieldError("criteria: yhat[" + std::to_string(k) + "]", yhat[k], "must be finite"));
    }
  }
}

void CheckWindow(size_t n, double dt, double t0, double t1) {
  if (!(std::isfinite(dt) && dt > 0))
    throw InputError(FieldError("criteria: dt", dt, "must be finite and > 0"));
  const double end = static_cast<double>(n - 1) * dt;
  if (!std::isfinite(t0) || t0 < 0)
    throw InputError(FieldError("criteria: t0", t0, "must be finite and >= 0"));
  if (!std::isfinite(t1) || t1 < t0) {
    throw InputError(
        FieldError("criteria: t1", t1, "must be finite and >= t0 = " + std::to_string(t0)));
  }
  // A window end may exceed the last sample time by rounding only (relative 1e-12).
  if (t1 > end * (1 + 1e-12) + 1e-300) {
    throw InputError(
        FieldError("criteria: t1", t1,
                   "is after the last sample at (n - 1) dt = " + std::to_string(end) + " s"));
  }
}

// Indices [first, last] of the samples with t0 ≤ k dt ≤ t1; throws when there are none.
void SampleRange(size_t n, double dt, double t0, double t1, size_t* first, size_t* last) {
  CheckWindow(n, dt, t0, t1);
  double f = std::ceil(t0 / dt);
  if (f * dt < t0) f += 1;  // rounding of the division
  double l = std::floor(t1 / dt);
  if (l * dt > t1) l -= 1;
  l = std::min(l, static_cast<double>(n - 1));
  if (l < f) {
    throw InputError("criteria: no sample in the window [" + std::to_string(t0) + ", " +
                     std::to_string(t1) + "] s (dt = " + std::to_string(dt) + " s)");
  }
  *first = static_cast<size_t>(f);
  *last = static_cast<size_t>(l);
}

}  // namespace

double Iae(std::span<const double> y, std::span<const double> yhat, double dt, double t0,
           double t1) {
  CheckSeries(y, yhat);
  CheckWindow(y.size(), dt, t0, t1);
  const size_t n = y.size();
  if (n == 1 || t1 == t0) return 0.0;
  const double end = static_cast<double>(n - 1) * dt;
  t1 = std::min(t1, end);
  auto e = [&](size_t k) { return y[k] - yhat[k]; };
  // |e| at time t inside interval [k dt, (k+1) dt], e interpolated linearly (as model/metrics.h's
  // IntegratedAbsError does).
  auto at = [&](size_t k, double t) {
    const double w = (t - static_cast<double>(k) * dt) / dt;
    return std::abs(e(k) + (e(k + 1) - e(k)) * std::clamp(w, 0.0, 1.0));
  };
  size_t k0 = std::min(static_cast<size_t>(std::floor(t0 / dt)), n - 2);
  size_t k1 = std::min(static_cast<size_t>(std::floor(t1 / dt)), n - 2);
  double sum = 0;
  for (size_t k = k0; k <= k1; ++k) {
    const double a = std::max(t0, static_cast<double>(k) * dt);
    const double b = std::min(t1, static_cast<double>(k + 1) * dt);
    if (b <= a) continue;
    sum += 0.5 * (at(k, a) + at(k, b)) * (b - a);
  }
  return sum;
}

double Iae(std::span<const double> y, std::span<const double> yhat, double dt) {
  CheckSeries(y, yhat);
  return Iae(y, yhat, dt, 0.0, static_cast<double>(y.size() - 1) * dt);
}

double Sse(std::span<const double> y, std::span<const double> yhat, double dt, double t0,
           double t1) {
  CheckSeries(y, yhat);
  size_t f, l;
  SampleRange(y.size(), dt, t0, t1, &f, &l);
  return PerformanceIndex(y.subspan(f, l - f + 1), yhat.subspan(f, l - f + 1));
}

double Sse(std::span<const double> y, std::span<const double> yhat) {
  CheckSeries(y, yhat);
  return PerformanceIndex(y, yhat);
}

double Rmse(std::span<const double> y, std::span<const double> yhat, double dt, double t0,
            double t1) {
  CheckSeries(y, yhat);
  size_t f, l;
  SampleRange(y.size(), dt, t0, t1, &f, &l);
  return std::sqrt(Sse(y.subspan(f, l - f + 1), yhat.subspan(f, l - f + 1)) /
                   static_cast<double>(l - f + 1));
}

double Rmse(std::span<const double> y, std::span<const double> yhat) {
  return std::sqrt(Sse(y, yhat) / static_cast<double>(y.size()));
}

double MaxAbsError(std::span<const double> y, std::span<const double> yhat, double dt, double t0,
                   double t1) {
  CheckSeries(y, yhat);
  size_t f, l;
  SampleRange(y.size(), dt, t0, t1, &f, &l);
  double m = 0;
  for (size_t k = f; k <= l; ++k) m = std::max(m, std::abs(y[k] - yhat[k]));
  return m;
}

}  // namespace pz::model
