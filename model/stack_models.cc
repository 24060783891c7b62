#include "model/stack_models.h"

#include <cmath>
#include <numbers>

#include "model/kernels/pzk.h"

namespace pz::model {
namespace {

// φ(z) = (1 − e^{−z}) / z, φ(0) = 1: the exact solution of x' = a − k x over a length v is
// x(v) = x + (a − k x) v φ(k v).
inline double Phi(double z) {
  // Taylor for small |z| (error < z⁴/120 < 1e-14 for |z| < 1e-2.5): the low-frequency records
  // have tiny steps of u, and this spares them a call of expm1.
  if (std::abs(z) < 3e-3) return 1.0 + z * (-0.5 + z * (1.0 / 6.0 - z * (1.0 / 24.0)));
  return -std::expm1(-z) / z;
}

// L(z) = log1p(z) / z, L(0) = 1.
inline double LogRatio(double z) {
  if (std::abs(z) < 1e-8) return 1.0 - 0.5 * z;
  return std::log1p(z) / z;
}

bool Finite(double x) { return std::isfinite(x); }

void CheckLengths(std::span<const double> u, std::span<double> yhat, const char* what) {
  if (u.size() != yhat.size())
    throw InputError(std::string(what) + ": u has " + std::to_string(u.size()) +
                     " samples, yhat has " + std::to_string(yhat.size()));
  if (u.empty()) throw InputError(std::string(what) + ": u has no samples");
}

}  // namespace

Status StackBoucWenParams::Validate() const {
  if (!Finite(alpha)) return InvalidArgument(FieldError("alpha", alpha, "must be finite"));
  if (!Finite(beta)) return InvalidArgument(FieldError("beta", beta, "must be finite"));
  if (!Finite(gamma)) return InvalidArgument(FieldError("gamma", gamma, "must be finite"));
  if (!Finite(d)) return InvalidArgument(FieldError("d", d, "must be finite"));
  if (!(Finite(fc_hz) && fc_hz > 0))
    return InvalidArgument(FieldError("fc_Hz", fc_hz, "must be finite and > 0"));
  return Status::Ok();
}

Status BacklashLikeParams::Validate() const {
  if (!(Finite(alpha) && alpha >= 0))
    return InvalidArgument(FieldError("alpha", alpha, "must be finite and >= 0"));
  if (!Finite(c)) return InvalidArgument(FieldError("c", c, "must be finite"));
  if (!Finite(b1)) return InvalidArgument(FieldError("B1", b1, "must be finite"));
  return Status::Ok();
}

Status StackSimOptions::Validate() const {
  if (substeps < 1 || substeps > 1024)
    return InvalidArgument(FieldError("substeps", substeps, "must be in 1 … 1024"));
  return Status::Ok();
}

const char* StackFamilyName(StackFamily family) {
  switch (family) {
    case StackFamily::kBoucWen:
      return "bouc-wen";
    case StackFamily::kBacklashLike:
      return "backlash-like";
  }
  return "unknown";
}

const char* StackFamilyTitle(StackFamily family) {
  switch (family) {
    case StackFamily::kBoucWen:
      return "Bouc–Wen";
    case StackFamily::kBacklashLike:
      return "backlash-like";
  }
  return "unknown";
}

std::optional<StackFamily> ParseStackFamily(std::string_view name) {
  for (StackFamily f : {StackFamily::kBoucWen, StackFamily::kBacklashLike})
    if (name == StackFamilyName(f)) return f;
  return std::nullopt;
}

std::vector<std::string> StackParamNames(StackFamily family) {
  if (family == StackFamily::kBoucWen) return {"alpha", "beta", "gamma", "d", "fc_Hz"};
  return {"alpha", "c", "B1"};
}

StackBoucWenParams BoucWenFromVector(std::span<const double> p) {
  if (p.size() != 5)
    throw InputError("bouc-wen parameters: " + std::to_string(p.size()) +
                     " values given, 5 expected (alpha, beta, gamma, d, fc_Hz)");
  return {p[0], p[1], p[2], p[3], p[4]};
}

BacklashLikeParams BacklashLikeFromVector(std::span<const double> p) {
  if (p.size() != 3)
    throw InputError("backlash-like parameters: " + std::to_string(p.size()) +
                     " values given, 3 expected (alpha, c, B1)");
  return {p[0], p[1], p[2]};
}

std::vector<double> ToVector(const StackBoucWenParams& p) {
  return {p.alpha, p.beta, p.gamma, p.d, p.fc_hz};
}
std::vector<double> ToVector(const BacklashLikeParams& p) { return {p.alpha, p.c, p.b1}; }

double BoucWenStateStep(double h, double du, double alpha, double beta, double gamma) {
  if (du == 0) return h;
  const double s = du > 0 ? 1.0 : -1.0;
  // The sign region of h on this piece: at h = 0 the slope is α, so h leaves 0 towards sgn(α du).
  const bool positive = h > 0 || (h == 0 && alpha * du >= 0);
  const double k = beta * s + (positive ? gamma : -gamma);
  const double h1 = h + (alpha - k * h) * du * Phi(k * du);
  if (h == 0 || alpha == 0) return h1;  // from 0, or towards the fixed point 0: no crossing
  if ((h > 0 && h1 >= 0) || (h < 0 && h1 <= 0)) return h1;
  // h changes sign inside the piece (monotone exponential in u, so once): at
  // v0 = ln(1 − k h / α) / k = (−h/α) L(−k h/α); the rest from 0 on the other side.
  const double z = -k * h / alpha;
  const double v0 = (-h / alpha) * LogRatio(z);
  const double rest = du - v0;
  if (!(rest * du > 0)) return 0.0;  // the crossing is at the end of the piece (rounding)
  const double k2 = beta * s + (positive ? -gamma : gamma);
  return alpha * rest * Phi(k2 * rest);
}

void SimulateStackBoucWen(const StackBoucWenParams& p, std::span<const double> u, double dt,
                          std::span<double> yhat, const StackSimOptions& options,
                          std::span<double> h_out) {
  ThrowIfError(p.Validate());
  ThrowIfError(options.Validate());
  CheckLengths(u, yhat, "SimulateStackBoucWen");
  if (!(Finite(dt) && dt > 0)) throw InputError(FieldError("dt", dt, "must be finite and > 0"));
  if (!h_out.empty() && h_out.size() != u.size())
    throw InputError("SimulateStackBoucWen: h has " + std::to_string(h_out.size()) +
                     " samples, u has " + std::to_string(u.size()));
  const int m = options.substeps;
  // Exact first-order-hold discretisation of dy/dt = ω (x − y) over a sub-step τ:
  // y1 = a y0 + b0 x0 + b1 x1, a = e^{−ωτ}, b1 = 1 − (1 − a)/(ωτ), b0 = (1 − a)/(ωτ) − a.
  const double wt = 2 * std::numbers::pi * p.fc_hz * dt / m;
  const double one_minus_a = -std::expm1(-wt);
  const double a = 1.0 - one_minus_a;
  const double q = Phi(wt);  // (1 − a)/(ωτ)
  const double b1 = 1.0 - q, b0 = q - a;
  const double inv_m = 1.0 / m;
  const double alpha = p.alpha, beta = p.beta, gamma = p.gamma;
  double h = options.rest_state;
  double x = p.d * (u[0] - h);
  double y = x;
  yhat[0] = y;
  if (!h_out.empty()) h_out[0] = h;
  for (size_t k = 1; k < u.size(); ++k) {
    const double du = (u[k] - u[k - 1]) * inv_m;
    // The m sub-steps share du, so φ(k du) of each sign region of h is computed once per sample
    // (lazily); a sub-step where h changes sign takes the general (splitting) update.
    const double s = du >= 0 ? 1.0 : -1.0;
    const double kp = beta * s + gamma, kn = beta * s - gamma;
    double php = 0, phn = 0;
    bool have_p = false, have_n = false;
    for (int j = 1; j <= m; ++j) {
      const double uj = (j == m) ? u[k] : u[k - 1] + j * du;
      if (du != 0) {
        const bool positive = h > 0 || (h == 0 && alpha * du >= 0);
        double h1;
        if (positive) {
          if (!have_p) php = Phi(kp * du), have_p = true;
          h1 = h + (alpha - kp * h) * du * php;
        } else {
          if (!have_n) phn = Phi(kn * du), have_n = true;
          h1 = h + (alpha - kn * h) * du * phn;
        }
        if ((h > 0 && h1 < 0) || (h < 0 && h1 > 0))
          h1 = BoucWenStateStep(h, du, alpha, beta, gamma);  // sign change inside the sub-step
        h = h1;
      }
      const double x1 = p.d * (uj - h);
      y = a * y + b0 * x + b1 * x1;
      x = x1;
    }
    yhat[k] = y;
    if (!h_out.empty()) h_out[k] = h;
  }
}

double BacklashLikeStateStep(double w, double du, const BacklashLikeParams& p) {
  const double as = du >= 0 ? p.alpha : -p.alpha;
  return w + ((p.c - p.b1) - as * w) * du * Phi(as * du);
}

double StackRestState(const StackBoucWenParams& p, double range, InitialState s) {
  if (s == InitialState::kCentred || s == InitialState::kAuto)
    return 0.0;  // kAuto: resolve it first
  const double first = s == InitialState::kDescended ? range : -range;
  return BoucWenStateStep(BoucWenStateStep(0.0, first, p.alpha, p.beta, p.gamma), -first, p.alpha,
                          p.beta, p.gamma);
}

double StackRestState(const BacklashLikeParams& p, double range, InitialState s) {
  if (s == InitialState::kCentred || s == InitialState::kAuto) return 0.0;
  const double first = s == InitialState::kDescended ? range : -range;
  return BacklashLikeStateStep(BacklashLikeStateStep(0.0, first, p), -first, p);
}

void SimulateBacklashLike(const BacklashLikeParams& p, std::span<const double> u,
                          std::span<double> yhat, double w0) {
  ThrowIfError(p.Validate());
  CheckLengths(u, yhat, "SimulateBacklashLike");
  // The step is the backlash-like kernel's (model/kernels/stack_models.h pzk_backlash_step):
  // w = c u − ŷ obeys dw/du = (c − B1) − α s w on a piece of sign s, w1 = w + (c − B1 − α s w) Δu
  // φ(α s Δu), with α s Δu = α |Δu| ≥ 0 (a decaying exponential).
  const double params[3] = {p.alpha, p.c, p.b1};
  pzk::pzk_block b{};
  b.kind = pzk::PZK_BACKLASH_LIKE;
  b.p = params;
  b.np = 3;
  double d[2] = {w0, u[0]};
  yhat[0] = p.c * u[0] - w0;
  for (size_t k = 1; k < u.size(); ++k) yhat[k] = pzk::pzk_backlash_step(&b, d, d, u[k]);
}

void SimulateStack(StackFamily family, std::span<const double> params, std::span<const double> u,
                   double dt, std::span<double> yhat, const StackSimOptions& options) {
  if (family == StackFamily::kBoucWen)
    SimulateStackBoucWen(BoucWenFromVector(params), u, dt, yhat, options);
  else
    SimulateBacklashLike(BacklashLikeFromVector(params), u, yhat);
}

}  // namespace pz::model
