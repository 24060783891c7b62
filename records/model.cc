#include "records/model.h"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace pz::records {
namespace {

/// First-order low-pass τ ẋ = v − x over samples of v (linear in between), in place, from rest at v[0].
void LowpassInPlace(std::span<double> v, double tau, double dt) {
  if (!(tau > 1e-12 * dt) || v.empty()) return;
  const double a = std::exp(-dt / tau);
  const double c = 1 - tau * (1 - a) / dt;  // = 1 − τ(1−a)/h
  double x = v[0], prev = v[0];
  for (size_t k = 1; k < v.size(); ++k) {
    const double cur = v[k];
    x = a * x + (1 - a) * prev + (cur - prev) * c;
    prev = cur;
    v[k] = x;
  }
}

}  // namespace

std::vector<EffectInfo> EffectLibrary(const DataScale& s) {
  const double dt = 1 / s.fs;
  const double umax = std::max(std::abs(s.u_min), std::abs(s.u_max));
  const double tau_hi = std::max(0.5 / (2 * std::numbers::pi * s.f_dom), 20 * dt);
  const double delay_hi = std::max(std::min(0.25 / s.f_dom, 500 * dt), 2 * dt);
  const double creep_lo = 0.5 / s.f_dom, creep_hi = std::max(10 * s.duration, 2 * creep_lo);
  return {
      {EffectKind::kDriverLowpass, "driver-lowpass", "driver (amplifier) low-pass", "tau u_e' = u - u_e",
       {{"tau_s", "s", dt / 100, tau_hi, true}}},
      {EffectKind::kQuadraticDrive, "quadratic-drive", "quadratic (electrostrictive) drive", "u_e = u + c2 u^2",
       {{"c2", "1/V", -0.3 / umax, 0.3 / umax, false}}},
      {EffectKind::kCreep, "creep", "creep (one slow relaxation)", "tau_c x' = k_c (u - u0) - x, u_e = u + x",
       {{"k_c", "-", -0.3, 0.3, false}, {"tau_c_s", "s", creep_lo, creep_hi, true}}},
      {EffectKind::kDelay, "delay", "transport delay", "u_e(t) = u(t - tau_d)", {{"tau_d_s", "s", 0, delay_hi, false}}},
      {EffectKind::kFriction, "friction", "friction dead band at the output", "y_e = play_r[y]",
       {{"r", "y", 0, 0.2 * s.y_half, false}}},
      {EffectKind::kStiffening, "stiffening", "cubic stiffening", "y_e = y - k3 Y ((y - y0)/Y)^3",
       {{"k3", "-", -0.3, 0.3, false}}},
      {EffectKind::kDrift, "drift", "drift of the reading", "y_e = y + rate (t - t_window)",
       {{"rate", "y/s", -s.y_half / s.duration, s.y_half / s.duration, false}}},
  };
}

const std::vector<std::string>& EffectNames() {
  static const std::vector<std::string> names = {"driver-lowpass", "quadratic-drive", "creep", "delay",
                                                 "friction", "stiffening", "drift"};
  return names;
}

const char* EffectName(EffectKind kind) { return EffectNames()[static_cast<size_t>(kind)].c_str(); }

EffectKind ParseEffect(std::string_view name) {
  const auto& names = EffectNames();
  for (size_t i = 0; i < names.size(); ++i)
    if (names[i] == name) return static_cast<EffectKind>(i);
  std::string known;
  for (const auto& n : names) known += (known.empty() ? "" : ", ") + n;
  throw InputError("effect '" + std::string(name) + "' is unknown (effects: " + known + ")");
}

RecordModel::RecordModel(std::shared_ptr<const Family> family, std::vector<EffectKind> effects, const DataScale& scale)
    : family_(std::move(family)), effects_(std::move(effects)), scale_(scale) {
  std::sort(effects_.begin(), effects_.end());
  if (std::adjacent_find(effects_.begin(), effects_.end()) != effects_.end()) {
    throw InputError("an effect is listed twice");
  }
  params_ = family_->params();
  const auto lib = EffectLibrary(scale_);
  for (EffectKind e : effects_) {
    effect_offset_.push_back(params_.size() - family_->params().size());
    for (const ParamInfo& p : lib[static_cast<size_t>(e)].params) {
      ParamInfo q = p;
      q.name = std::string(EffectName(e)) + "." + p.name;
      params_.push_back(q);
    }
  }
}

std::string RecordModel::Describe() const {
  std::string s = family_->name();
  for (EffectKind e : effects_) s += std::string(" + ") + EffectName(e);
  return s;
}

void RecordModel::EffectiveDrive(const io::Record& r, std::span<const double> ep, size_t from, size_t end,
                                 std::vector<double>& ue) const {
  ue.assign(r.u.begin() + static_cast<std::ptrdiff_t>(from), r.u.begin() + static_cast<std::ptrdiff_t>(end));
  const double dt = r.dt, u0 = ue.empty() ? 0 : ue[0];
  for (size_t i = 0; i < effects_.size(); ++i) {
    const double* q = ep.data() + effect_offset_[i];
    switch (effects_[i]) {
      case EffectKind::kDriverLowpass: LowpassInPlace(ue, q[0], dt); break;
      case EffectKind::kQuadraticDrive:
        for (double& v : ue) v += q[0] * v * v;
        break;
      case EffectKind::kCreep: {
        if (q[0] == 0) break;
        std::vector<double> x(ue.size());
        for (size_t k = 0; k < ue.size(); ++k) x[k] = q[0] * (ue[k] - u0);
        LowpassInPlace(x, q[1], dt);
        for (size_t k = 0; k < ue.size(); ++k) ue[k] += x[k];
        break;
      }
      case EffectKind::kDelay: {
        const double shift = q[0] / dt;
        if (!(shift > 0)) break;
        const std::vector<double> src = ue;
        for (size_t k = 0; k < ue.size(); ++k) {
          const double pos = static_cast<double>(k) - shift;
          if (pos <= 0) {
            ue[k] = src[0];
          } else {
            const size_t j = static_cast<size_t>(pos);
            const double f = pos - static_cast<double>(j);
            ue[k] = j + 1 < src.size() ? src[j] + f * (src[j + 1] - src[j]) : src[j];
          }
        }
        break;
      }
      default: break;
    }
  }
}

void RecordModel::ApplyOutputEffects(const io::Record& r, std::span<const double> ep, size_t,
                                     std::span<double> y) const {
  if (y.empty()) return;
  for (size_t i = 0; i < effects_.size(); ++i) {
    const double* q = ep.data() + effect_offset_[i];
    switch (effects_[i]) {
      case EffectKind::kFriction: {
        const double rr = std::max(q[0], 0.0);
        if (rr == 0) break;
        double z = y[0];
        for (double& v : y) {
          z = std::max(v - rr, std::min(v + rr, z));
          v = z;
        }
        break;
      }
      case EffectKind::kStiffening: {
        const double y0 = y[0], Y = scale_.y_half;
        for (double& v : y) {
          const double x = (v - y0) / Y;
          v -= q[0] * Y * x * x * x;
        }
        break;
      }
      case EffectKind::kDrift: {
        // Time from the window's start on the record's uniform grid (the same wherever the record
        // is cut: the service's workers receive it without its leading rest).
        const double first = static_cast<double>(r.first_scored);
        for (size_t k = 0; k < y.size(); ++k) y[k] += q[0] * (static_cast<double>(k) - first) * r.dt;
        break;
      }
      default: break;
    }
  }
}

namespace {

// The first simulated sample of a record: the last sample of its rest segment (the model is at
// rest before it), at most end − 1.
size_t SimulatedFrom(const io::Record& r, size_t end) { return std::min(std::max<size_t>(r.rest_samples, 1) - 1, end - 1); }

bool IsDriveEffect(EffectKind e) {
  return e == EffectKind::kDriverLowpass || e == EffectKind::kQuadraticDrive || e == EffectKind::kCreep ||
         e == EffectKind::kDelay;
}

}  // namespace

std::shared_ptr<const Family::Prepared> RecordModel::Prepare(const io::Record& r, size_t end) const {
  if (family_->linear() || end > r.size() || end == 0) return nullptr;
  for (EffectKind e : effects_)
    if (IsDriveEffect(e)) return nullptr;
  const size_t from = SimulatedFrom(r, end);
  return family_->Prepare(std::span<const double>(r.u).subspan(from, end - from), r.dt);
}

double RecordModel::Simulate(const io::Record& r, std::span<const double> p, std::span<const double> weights,
                             size_t end, std::span<double> yhat, const Family::Prepared* prepared) const {
  if (p.size() != params_.size()) {
    throw InputError(Describe() + ": " + std::to_string(p.size()) + " parameters given, " +
                     std::to_string(params_.size()) + " expected");
  }
  if (yhat.size() < end || end > r.size() || end == 0) throw InputError("RecordModel::Simulate: bad end");
  const size_t nf = family_->params().size();
  const size_t from = SimulatedFrom(r, end);
  std::vector<double> ue;
  EffectiveDrive(r, p.subspan(nf), from, end, ue);
  std::span<double> seg = yhat.subspan(from, end - from);
  if (family_->linear()) {
    const size_t m = family_->regressors();
    if (weights.size() != m) throw InputError(family_->name() + ": weights not solved");
    std::vector<double> reg(ue.size() * m);
    family_->Regressors(ue, reg);
    for (size_t k = 0; k < ue.size(); ++k) {
      double acc = 0;
      for (size_t j = 0; j < m; ++j) acc += reg[k * m + j] * weights[j];
      seg[k] = acc;
    }
  } else {
    family_->SimulatePrepared(prepared, p.first(nf), ue, r.dt, seg);
  }
  const double rest_output = seg[0];
  std::fill(yhat.begin(), yhat.begin() + static_cast<std::ptrdiff_t>(from), rest_output);
  ApplyOutputEffects(r, p.subspan(nf), 0, yhat.first(end));
  return rest_output;
}

double RecordOffset(const io::Record& r, std::span<const double> y, double rest_output) {
  switch (r.offset_mode) {
    case io::OffsetMode::kFixed: return r.offset;
    case io::OffsetMode::kRest: return r.offset - rest_output;
    case io::OffsetMode::kFit: {
      double s = 0;
      for (size_t k = r.first_scored; k < r.end_scored; ++k) s += r.y[k] - y[k];
      return s / static_cast<double>(r.scored());
    }
  }
  return 0;
}

}  // namespace pz::records
