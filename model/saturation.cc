#include "model/saturation.h"

#include <Eigen/Dense>
#include <boost/math/distributions/students_t.hpp>
#include <cmath>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

namespace pz::model {
namespace {

RegressionTerm Term(double coef, double variance, int dof) {
  RegressionTerm t;
  t.coef = coef;
  t.std_error = std::sqrt(std::max(variance, 0.0));
  if (t.std_error > 0) {
    t.t_stat = coef / t.std_error;
    const boost::math::students_t dist(dof);
    t.p_value = 2 * boost::math::cdf(boost::math::complement(dist, std::abs(t.t_stat)));
  } else {  // perfect fit: the estimate is exact
    t.t_stat = coef == 0 ? std::numeric_limits<double>::quiet_NaN()
                         : std::copysign(std::numeric_limits<double>::infinity(), coef);
    t.p_value = coef == 0 ? 1.0 : 0.0;
  }
  return t;
}

}  // namespace

SaturationPair SaturationFromExtremes(std::span<const double> y) {
  if (y.empty()) throw InputError("saturation fit: the measured angle series is empty");
  SaturationPair p{y[0], y[0]};
  for (size_t k = 0; k < y.size(); ++k) {
    if (!std::isfinite(y[k]))
      throw InputError("saturation fit: " + FieldError("measured angle[" + std::to_string(k) + "]",
                                                       y[k], "must be finite"));
    p.b1 = std::max(p.b1, y[k]);
    p.b2 = std::min(p.b2, y[k]);
  }
  if (!(p.b1 > 0))
    throw InputError(FieldError(
        "b1", p.b1, "the measured angle never rises above 0 deg, so b1 > 0 cannot be fitted"));
  if (!(p.b2 < 0))
    throw InputError(FieldError(
        "b2", p.b2, "the measured angle never falls below 0 deg, so b2 < 0 cannot be fitted"));
  return p;
}

PlaneFit FitPlane(std::span<const double> v, std::span<const double> f, std::span<const double> y) {
  if (v.size() != f.size() || v.size() != y.size())
    throw InputError("plane fit: " + std::to_string(v.size()) + " amplitudes, " +
                     std::to_string(f.size()) + " frequencies and " + std::to_string(y.size()) +
                     " responses: lengths must match");
  const int n = static_cast<int>(v.size());
  if (n < 4)
    throw InputError("plane fit: " + std::to_string(n) +
                     " observations; a fit of 3 coefficients with statistics needs at least 4");
  Eigen::MatrixXd x(n, 3);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    if (!std::isfinite(v[i]) || !std::isfinite(f[i]) || !std::isfinite(y[i])) {
      std::ostringstream os;
      os << "plane fit: observation " << i << " (V = " << v[i] << ", f = " << f[i]
         << ", y = " << y[i] << ") is not finite";
      throw InputError(os.str());
    }
    x(i, 0) = v[i];
    x(i, 1) = f[i];
    x(i, 2) = 1.0;
    b(i) = y[i];
  }
  // Scale the columns so the rank test does not depend on units (V ~ 1e2, f ~ 1).
  const Eigen::Vector3d scale = x.colwise().norm().transpose();
  const Eigen::MatrixXd xs = x * scale.cwiseInverse().asDiagonal();
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(xs);
  qr.setThreshold(1e-10);
  if (qr.rank() < 3)
    throw InputError(
        "plane fit: amplitude, frequency and intercept are collinear (need at least two "
        "amplitudes and two frequencies not on one line)");
  const Eigen::Vector3d coef = qr.solve(b).cwiseQuotient(scale);
  const Eigen::VectorXd resid = b - x * coef;
  const double sse = resid.squaredNorm();
  const double mean = b.mean();
  const double sst = (b.array() - mean).square().sum();

  PlaneFit fit;
  fit.n = n;
  fit.dof = n - 3;
  const double s2 = sse / fit.dof;
  fit.residual_se = std::sqrt(s2);
  // Cov = s² (XᵀX)⁻¹, computed on the scaled design for conditioning.
  const Eigen::Matrix3d xtx_inv_s = (xs.transpose() * xs).inverse();
  const Eigen::Matrix3d cov =
      s2 * scale.cwiseInverse().asDiagonal() * xtx_inv_s * scale.cwiseInverse().asDiagonal();
  fit.v = Term(coef(0), cov(0, 0), fit.dof);
  fit.f = Term(coef(1), cov(1, 1), fit.dof);
  fit.intercept = Term(coef(2), cov(2, 2), fit.dof);
  fit.r2 = sst > 0 ? 1.0 - sse / sst : std::numeric_limits<double>::quiet_NaN();
  fit.adjusted_r2 = 1.0 - (1.0 - fit.r2) * (n - 1) / fit.dof;
  return fit;
}

SaturationRegression FitSaturationRegression(std::span<const SaturationSample> samples) {
  std::vector<double> v, f, b1, b2;
  for (const auto& s : samples) {
    v.push_back(s.amplitude_v);
    f.push_back(s.frequency_hz);
    b1.push_back(s.b1);
    b2.push_back(s.b2);
  }
  return {FitPlane(v, f, b1), FitPlane(v, f, b2)};
}

SaturationRegression PaperSaturationRegression() {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto term = [nan](double c) { return RegressionTerm{c, nan, nan, nan}; };
  SaturationRegression r;
  r.b1 = PlaneFit{term(0.00645), term(-0.84771), term(-0.63061), 0.985, nan, nan, 9, 6};
  r.b2 = PlaneFit{term(-0.00622), term(0.68371), term(0.71011), 0.981, nan, nan, 9, 6};
  return r;
}

}  // namespace pz::model
