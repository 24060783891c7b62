#include "model/metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>

namespace pz::model {
namespace {

std::string Num(double x) {
  std::ostringstream os;
  os.precision(12);
  os << x;
  return os.str();
}

Status CheckFinite(std::span<const double> x, const char* name) {
  for (size_t k = 0; k < x.size(); ++k)
    if (!std::isfinite(x[k]))
      return InvalidArgument(std::string(name) + "[" + std::to_string(k) + "] = " + Num(x[k]) +
                             " is not finite");
  return Status::Ok();
}

void RequireAligned(std::span<const double> measured, std::span<const double> model) {
  ThrowIfError(CheckAligned(measured, model));
}

}  // namespace

Status CheckAligned(std::span<const double> measured, std::span<const double> model) {
  if (measured.size() != model.size())
    return InvalidArgument("series not aligned: measured has " + std::to_string(measured.size()) +
                           " samples but model has " + std::to_string(model.size()));
  if (measured.empty()) return InvalidArgument("series are empty: nothing to compare");
  if (auto s = CheckFinite(measured, "measured"); !s.ok()) return s;
  return CheckFinite(model, "model");
}

Status CheckSameGrid(std::span<const double> t_a, std::span<const double> t_b, double tolerance_s) {
  if (t_a.size() != t_b.size())
    return InvalidArgument("time grids differ in length: " + std::to_string(t_a.size()) + " vs " +
                           std::to_string(t_b.size()) + " samples");
  if (auto s = CheckFinite(t_a, "t_measured"); !s.ok()) return s;
  if (auto s = CheckFinite(t_b, "t_model"); !s.ok()) return s;
  for (size_t k = 0; k < t_a.size(); ++k)
    if (!(std::abs(t_a[k] - t_b[k]) <= tolerance_s))
      return InvalidArgument("time grids differ first at sample " + std::to_string(k) +
                             ": t = " + Num(t_a[k]) + " s vs " + Num(t_b[k]) + " s (tolerance " +
                             Num(tolerance_s) + " s)");
  return Status::Ok();
}

double PerformanceIndex(std::span<const double> measured, std::span<const double> model) {
  RequireAligned(measured, model);
  double sum = 0;
  for (size_t k = 0; k < measured.size(); ++k) {
    const double e = measured[k] - model[k];
    sum += e * e;
  }
  return sum;
}

double MeanSquaredError(std::span<const double> measured, std::span<const double> model) {
  return PerformanceIndex(measured, model) / static_cast<double>(measured.size());
}

double RootMeanSquaredError(std::span<const double> measured, std::span<const double> model) {
  return std::sqrt(MeanSquaredError(measured, model));
}

double MaxAbsError(std::span<const double> measured, std::span<const double> model) {
  return CompareSeries(measured, model).max_abs;
}

double RSquared(std::span<const double> measured, std::span<const double> model) {
  const ErrorMetrics m = CompareSeries(measured, model);
  if (std::isnan(m.r2))
    throw InputError("R² undefined: the measured series is constant (" + std::to_string(m.n) +
                     " samples equal to " + Num(measured[0]) + ")");
  return m.r2;
}

ErrorMetrics CompareSeries(std::span<const double> measured, std::span<const double> model) {
  RequireAligned(measured, model);
  ErrorMetrics m;
  m.n = measured.size();
  double mean = 0;
  for (double y : measured) mean += y;
  mean /= static_cast<double>(m.n);
  double ss_tot = 0;
  for (size_t k = 0; k < m.n; ++k) {
    const double e = measured[k] - model[k];
    m.pi += e * e;
    if (std::abs(e) > m.max_abs) {
      m.max_abs = std::abs(e);
      m.max_abs_index = k;
    }
    ss_tot += (measured[k] - mean) * (measured[k] - mean);
  }
  m.mse = m.pi / static_cast<double>(m.n);
  m.rmse = std::sqrt(m.mse);
  m.r2 = ss_tot > 0 ? 1.0 - m.pi / ss_tot : std::numeric_limits<double>::quiet_NaN();
  return m;
}

ErrorMetrics CompareTraces(std::span<const double> t_measured, std::span<const double> measured,
                           std::span<const double> t_model, std::span<const double> model,
                           double tolerance_s) {
  if (t_measured.size() != measured.size())
    throw InputError("measured series has " + std::to_string(measured.size()) + " values but " +
                     std::to_string(t_measured.size()) + " times");
  if (t_model.size() != model.size())
    throw InputError("model series has " + std::to_string(model.size()) + " values but " +
                     std::to_string(t_model.size()) + " times");
  ThrowIfError(CheckSameGrid(t_measured, t_model, tolerance_s));
  return CompareSeries(measured, model);
}

double IntegratedAbsError(std::span<const double> t, std::span<const double> measured,
                          std::span<const double> model, double t0, double t1) {
  RequireAligned(measured, model);
  if (t.size() != measured.size())
    throw InputError("IAE: " + std::to_string(t.size()) + " times but " +
                     std::to_string(measured.size()) + " values");
  ThrowIfError(CheckFinite(t, "t"));
  for (size_t k = 1; k < t.size(); ++k)
    if (!(t[k] > t[k - 1]))
      throw InputError("IAE: time not strictly increasing at sample " + std::to_string(k) +
                       ": t = " + Num(t[k]) + " s after " + Num(t[k - 1]) + " s");
  if (!(std::isfinite(t0) && std::isfinite(t1) && t0 <= t1 && t0 >= t.front() && t1 <= t.back()))
    throw InputError("IAE: window [" + Num(t0) + ", " + Num(t1) +
                     "] s must be ordered and inside the series [" + Num(t.front()) + ", " +
                     Num(t.back()) + "] s");
  auto err = [&](size_t k) { return measured[k] - model[k]; };
  // |e| at time x inside the interval [t_k, t_{k+1}], e interpolated linearly.
  auto abs_err_at = [&](size_t k, double x) {
    const double s = (x - t[k]) / (t[k + 1] - t[k]);
    return std::abs(err(k) + s * (err(k + 1) - err(k)));
  };
  double sum = 0;
  for (size_t k = 0; k + 1 < t.size(); ++k) {
    const double a = std::max(t0, t[k]), b = std::min(t1, t[k + 1]);
    if (!(b > a)) continue;
    sum += 0.5 * (abs_err_at(k, a) + abs_err_at(k, b)) * (b - a);
  }
  return sum;
}

}  // namespace pz::model
