#include "model/prandtl_ishlinskii.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>

#include "model/format.h"
#include "model/kernels/pzk.h"

namespace pz::model {
namespace {

std::string Num(double x) { return FormatG(x, 17); }

}  // namespace

const char* InitialStateName(InitialState s) {
  switch (s) {
    case InitialState::kCentred:
      return "centred";
    case InitialState::kDescended:
      return "descended";
    case InitialState::kAscended:
      return "ascended";
    case InitialState::kAuto:
      return "auto";
  }
  return "centred";
}

InitialState ParseInitialState(std::string_view name, std::string_view field) {
  for (InitialState s : {InitialState::kCentred, InitialState::kDescended, InitialState::kAscended,
                         InitialState::kAuto})
    if (name == InitialStateName(s)) return s;
  throw InputError(std::string(field) + " '" + std::string(name) +
                   "' is unknown (allowed: centred, descended, ascended, auto)");
}

void RequireResolved(InitialState s, std::string_view what) {
  if (s == InitialState::kAuto) {
    throw InputError(std::string(what) +
                     ": initial state 'auto' must be resolved on the drive range first "
                     "(ResolveInitialState)");
  }
}

Status PiOperator::Validate() const {
  if (!std::isfinite(w0)) return InvalidArgument("pi.w0 = " + Num(w0) + ": must be finite");
  if (thresholds.size() != weights.size()) {
    return InvalidArgument("pi.weights has " + std::to_string(weights.size()) + " values for " +
                           std::to_string(thresholds.size()) + " thresholds");
  }
  for (size_t i = 0; i < thresholds.size(); ++i) {
    if (!std::isfinite(thresholds[i]) || thresholds[i] <= 0 ||
        (i > 0 && thresholds[i] <= thresholds[i - 1])) {
      return InvalidArgument("pi.thresholds[" + std::to_string(i) + "] = " + Num(thresholds[i]) +
                             ": must be finite, > 0 and above the previous one");
    }
    if (!std::isfinite(weights[i])) {
      return InvalidArgument("pi.weights[" + std::to_string(i) + "] = " + Num(weights[i]) +
                             ": must be finite");
    }
  }
  return Status::Ok();
}

bool PiOperator::Invertible() const {
  if (!Validate().ok() || !(w0 > 0)) return false;
  return std::all_of(weights.begin(), weights.end(), [](double w) { return w >= 0; });
}

std::vector<double> PiThresholds(int n, double half_range) {
  if (n < 1 || n > 10000)
    throw InputError("pi operators = " + std::to_string(n) + ": must be 1 … 10000");
  if (!(half_range > 0) || !std::isfinite(half_range)) {
    throw InputError("pi: the drive's half range " + Num(half_range) +
                     " must be finite and > 0 (a constant drive?)");
  }
  std::vector<double> r(static_cast<size_t>(n));
  for (int i = 0; i < n; ++i) r[static_cast<size_t>(i)] = half_range * (i + 1) / (n + 1);
  return r;
}

void PiPlayOutputs(std::span<const double> r, std::span<const double> u, std::span<double> out,
                   InitialState start) {
  const size_t n = r.size(), len = u.size();
  if (out.size() != len * n) throw InputError("PiPlayOutputs: output size mismatch");
  if (len == 0) return;
  RequireResolved(start, "PiPlayOutputs");
  std::vector<double> z(n);
  for (size_t i = 0; i < n; ++i) z[i] = PlayRest(u[0], r[i], start);
  for (size_t k = 0; k < len; ++k) {
    const double uk = u[k];
    double* row = out.data() + k * n;
    for (size_t i = 0; i < n; ++i) {
      z[i] = std::max(uk - r[i], std::min(uk + r[i], z[i]));
      row[i] = z[i];
    }
  }
}

void ApplyPi(const PiOperator& op, std::span<const double> u, std::span<double> y) {
  if (Status s = op.Validate(); !s.ok()) throw InputError(s);
  if (y.size() != u.size()) throw InputError("ApplyPi: output size mismatch");
  if (u.empty()) return;
  RequireResolved(op.start, "ApplyPi");
  // The step is the PI kernel's (model/kernels/play_operators.h pzk_pi_step) on the operator's own
  // thresholds: y = w0 u + Σ w_i z_i, the plays updated in order.
  const size_t n = op.thresholds.size();
  std::vector<double> w(n + 1), z(n);
  w[0] = op.w0;
  std::copy(op.weights.begin(), op.weights.end(), w.begin() + 1);
  pzk::pzk_block b{};
  b.kind = pzk::PZK_PRANDTL_ISHLINSKII;
  b.n = static_cast<int>(n);
  b.w = w.data();
  b.nw = static_cast<int>(n + 1);
  for (size_t i = 0; i < n; ++i) z[i] = PlayRest(u[0], op.thresholds[i], op.start);
  for (size_t k = 0; k < u.size(); ++k)
    y[k] = pzk::pzk_pi_step(&b, op.thresholds.data(), z.data(), z.data(), u[k]);
}

PiOperator InvertPi(const PiOperator& op) {
  if (!op.Invertible()) {
    throw InputError("pi: the operator is not invertible (it needs w0 > 0 and every weight ≥ 0)");
  }
  const size_t n = op.thresholds.size();
  PiOperator inv;
  inv.w0 = 1.0 / op.w0;
  RequireResolved(op.start, "InvertPi");
  inv.start = op.start;  // a descent of the drive is a descent of the output
  inv.thresholds.resize(n);
  inv.weights.resize(n);
  double below = op.w0;  // w0 + Σ_{i<j} w_i
  for (size_t j = 0; j < n; ++j) {
    double r = op.w0 * op.thresholds[j];
    for (size_t i = 0; i < j; ++i) r += op.weights[i] * (op.thresholds[j] - op.thresholds[i]);
    inv.thresholds[j] = r;
    const double upto = below + op.weights[j];
    inv.weights[j] = -op.weights[j] / (upto * below);
    below = upto;
  }
  // Equal thresholds can only come from a zero spacing, impossible with w0 > 0: r' strictly
  // increases.
  return inv;
}

}  // namespace pz::model
