#include "model/stack_models.h"

#include <cmath>

#include "model/kernels/pzk.h"

namespace pz::model {
namespace {

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
  // The kernel's (model/kernels/stack_models.h pzk_bouc_wen_state_step): exact on the piece, h
  // split where it changes sign.
  return pzk::pzk_bouc_wen_state_step(h, du, alpha, beta, gamma);
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
  // The step is the stack Bouc–Wen kernel's (model/kernels/stack_models.h pzk_stack_bw_step): m
  // sub-steps of the exact h update on a straight piece of drive, each followed by the driver
  // filter dy/dt = ω (x − y), x = d (u − h), discretised exactly for x linear over a sub-step.
  const double params[5] = {p.alpha, p.beta, p.gamma, p.d, p.fc_hz};
  pzk::pzk_block b{};
  b.kind = pzk::PZK_STACK_BOUC_WEN;
  b.n = options.substeps;
  b.dt = dt;
  b.p = params;
  b.np = 5;
  b.init = pzk::PZK_CENTRED;
  double c[4], d[4];
  pzk::pzk_stack_bw_init(&b, c, d, u[0]);  // the constants; the state at rest is the options'
  d[0] = options.rest_state;
  d[1] = p.d * (u[0] - d[0]);
  d[2] = d[1];
  yhat[0] = d[2];
  if (!h_out.empty()) h_out[0] = d[0];
  for (size_t k = 1; k < u.size(); ++k) {
    yhat[k] = pzk::pzk_stack_bw_step(&b, c, d, d, u[k]);
    if (!h_out.empty()) h_out[k] = d[0];
  }
}

double BacklashLikeStateStep(double w, double du, const BacklashLikeParams& p) {
  // The kernel's (model/kernels/stack_models.h pzk_backlash_state_step).
  const double params[3] = {p.alpha, p.c, p.b1};
  pzk::pzk_block b{};
  b.p = params;
  b.np = 3;
  return pzk::pzk_backlash_state_step(&b, w, du);
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
