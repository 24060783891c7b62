#include "model/duhem.h"

#include <cmath>

#include "model/kernels/pzk.h"

namespace pz::model {
Status DuhemParams::Validate() const {
  const std::pair<const char*, double> all[] = {
      {"alpha", alpha}, {"c", c}, {"c3", c3}, {"b", b}, {"lambda", lambda}};
  for (const auto& [n, v] : all)
    if (!std::isfinite(v))
      return InvalidArgument(FieldError(std::string("duhem.") + n, v, "must be finite"));
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
    throw InputError("duhem: " + std::to_string(p.size()) +
                     " parameters given, 5 expected (alpha, c, c3, b, lambda)");
  }
  return {p[0], p[1], p[2], p[3], p[4]};
}

void SimulateDuhem(const DuhemParams& p, std::span<const double> u, double dt,
                   std::span<double> y) {
  ThrowIfError(p.Validate());
  if (!(dt > 0) || !std::isfinite(dt))
    throw InputError(FieldError("duhem dt", dt, "must be finite and > 0"));
  if (y.size() != u.size()) throw InputError("SimulateDuhem: output size mismatch");
  if (u.empty()) return;
  // The step is the Duhem kernel's (model/kernels/stack_models.h pzk_duhem_step: w = f(u) − y
  // obeys dw/dτ = −k w + g(τ), g quadratic in τ on a piece of linear drive, integrated exactly).
  const double params[5] = {p.alpha, p.c, p.c3, p.b, p.lambda};
  pzk::pzk_block b{};
  b.kind = pzk::PZK_DUHEM;
  b.dt = dt;
  b.p = params;
  b.np = 5;
  double d[2];
  y[0] = pzk::pzk_duhem_init(&b, d, u[0]);  // at rest on the curve
  for (size_t k = 1; k < u.size(); ++k) y[k] = pzk::pzk_duhem_step(&b, d, d, u[k]);
}

}  // namespace pz::model
