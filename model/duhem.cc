#include "model/duhem.h"

#include <cmath>

namespace pz::model {
namespace {

/// φ1(z) = (e^z − 1)/z, φ2(z) = (e^z − 1 − z)/z², φ3(z) = (e^z − 1 − z − z²/2)/z³ for z ≤ 0, by
/// their Taylor series near 0 (where the closed forms cancel) and the closed forms elsewhere.
inline void Phi123(double z, double& p1, double& p2, double& p3) {
  if (std::abs(z) < 0.1) {
    // Σ z^j / (j + m)!, j = 0 … 9: truncation below 1e-17 relative for |z| < 0.1.
    double t1 = 1, t2 = 0.5, t3 = 1.0 / 6;
    p1 = p2 = p3 = 0;
    for (int j = 0; j < 10; ++j) {
      p1 += t1;
      p2 += t2;
      p3 += t3;
      t1 *= z / (j + 2);
      t2 *= z / (j + 3);
      t3 *= z / (j + 4);
    }
    return;
  }
  const double em1 = std::expm1(z);
  p1 = em1 / z;
  p2 = (em1 - z) / (z * z);
  p3 = (em1 - z - z * z / 2) / (z * z * z);
}

}  // namespace

Status DuhemParams::Validate() const {
  const std::pair<const char*, double> all[] = {{"alpha", alpha}, {"c", c}, {"c3", c3}, {"b", b}, {"lambda", lambda}};
  for (const auto& [n, v] : all)
    if (!std::isfinite(v)) return InvalidArgument(FieldError(std::string("duhem.") + n, v, "must be finite"));
  if (alpha < 0) return InvalidArgument(FieldError("duhem.alpha", alpha, "must be >= 0"));
  if (lambda < 0) return InvalidArgument(FieldError("duhem.lambda", lambda, "must be >= 0"));
  return Status::Ok();
}

const std::vector<std::string>& DuhemParamNames() {
  static const std::vector<std::string> names = {"alpha", "c", "c3", "b", "lambda"};
  return names;
}

DuhemParams DuhemFromVector(std::span<const double> p) {
  if (p.size() != 5) {
    throw InputError("duhem: " + std::to_string(p.size()) + " parameters given, 5 expected (alpha, c, c3, b, lambda)");
  }
  return {p[0], p[1], p[2], p[3], p[4]};
}

void SimulateDuhem(const DuhemParams& p, std::span<const double> u, double dt, std::span<double> y) {
  ThrowIfError(p.Validate());
  if (!(dt > 0) || !std::isfinite(dt)) throw InputError(FieldError("duhem dt", dt, "must be finite and > 0"));
  if (y.size() != u.size()) throw InputError("SimulateDuhem: output size mismatch");
  if (u.empty()) return;
  auto f = [&](double v) { return p.c * v + p.c3 * v * v * v; };
  double w = 0;  // f(u) − y, at rest on the curve
  y[0] = f(u[0]);
  for (size_t k = 1; k < u.size(); ++k) {
    const double u0 = u[k - 1], s = (u[k] - u0) / dt;
    const double kk = p.alpha * std::abs(s) + p.lambda;
    // dw/dτ = −k w + g(τ), g(τ) = s (c − b + 3 c3 (u0 + s τ)²): a quadratic in τ, integrated exactly.
    const double g0 = s * (p.c - p.b + 3 * p.c3 * u0 * u0);
    const double g1 = 6 * p.c3 * s * s * u0;  // g'(0)
    const double g2 = 6 * p.c3 * s * s * s;   // g''
    double p1, p2, p3;
    const double z = -kk * dt;
    Phi123(z, p1, p2, p3);
    w = std::exp(z) * w + dt * p1 * g0 + dt * dt * p2 * g1 + dt * dt * dt * p3 * g2;
    y[k] = f(u[k]) - w;
  }
}

}  // namespace pz::model
