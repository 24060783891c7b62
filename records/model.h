// A record model: a plant family (records/families.h) plus candidate unmodelled effects, and its
// output on a record with the record's explicit offset (issue 14).
//
// Effects (the diagnosis library of docs/diagnosis.md, for any family; zero magnitude = identity):
//   driver-lowpass   τ u̇_e = u − u_e                       (amplifier low-pass)        tau_s
//   quadratic-drive  u_e = u + c₂ u²                        (electrostriction)          c2
//   creep            τ_c ẋ = k_c (u − u_0) − x, u_e = u + x (one slow relaxation)       k_c, tau_c
//   delay            u_e(t) = u(t − τ_d)                    (transport delay)           tau_d
//   friction         y_e = play_r[y]                        (dead band in the guide)    r
//   stiffening       y_e = y − k₃ Y ((y − y_0)/Y)³          (hardening, Y = half range) k3
//   drift            y_e = y + ρ (t − t_w)                  (slow drift of the reading) rate
// Drive effects act on u in the order above, before the family; output effects after it. Every
// filter starts at rest at u_0 and is discretised exactly for a drive linear between samples; the
// delay reads the drive by linear interpolation (u_0 before the start).
//
// Offsets (io::OffsetMode): ŷ_total = polarity · ŷ + o with o the least-squares offset over the
// scored window (fit), the measured rest level minus the model's rest output (rest: the family's
// output at rest, before the output effects — a drift is zero at the window's start, not at rest),
// or the given value (fixed).
//
// Simulation skips the record's rest segment: every family and effect is at equilibrium under a
// constant drive, so the output there is the rest output (exact).
#pragma once

#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "io/records.h"
#include "records/families.h"

namespace pz::records {

enum class EffectKind : int { kDriverLowpass, kQuadraticDrive, kCreep, kDelay, kFriction, kStiffening, kDrift };

struct EffectInfo {
  EffectKind kind;
  std::string name;
  std::string title;
  std::string equation;
  std::vector<ParamInfo> params;  ///< scaled to the data; params[0] is the magnitude
};
/// Every effect, in the order above, with ranges scaled to the data.
std::vector<EffectInfo> EffectLibrary(const DataScale& scale);
/// Names in that order.
const std::vector<std::string>& EffectNames();
/// Throws InputError naming an unknown effect and the known ones.
EffectKind ParseEffect(std::string_view name);
const char* EffectName(EffectKind kind);

/// A family with effects; a parameter vector is the family's params then each effect's.
class RecordModel {
 public:
  RecordModel(std::shared_ptr<const Family> family, std::vector<EffectKind> effects, const DataScale& scale);
  const Family& family() const { return *family_; }
  std::shared_ptr<const Family> family_ptr() const { return family_; }
  const std::vector<EffectKind>& effects() const { return effects_; }
  const DataScale& scale() const { return scale_; }
  /// The searched parameters: the family's then the effects'.
  const std::vector<ParamInfo>& params() const { return params_; }
  /// "backlash-like + delay".
  std::string Describe() const;

  /// The model output ŷ (without polarity and offset) on samples [0, end) of the record — only
  /// [rest, end) is simulated. For a linear family, `weights` are the solved weights; else empty.
  /// Returns the model's rest output (before the output effects: what a rest measurement is).
  /// `prepared`: Prepare(r, end) (null: none; the output is the same bit for bit).
  double Simulate(const io::Record& r, std::span<const double> p, std::span<const double> weights, size_t end,
                  std::span<double> yhat, const Family::Prepared* prepared = nullptr) const;
  /// The family's per-record prepare step (Family::Prepare) on the drive that Simulate(r, …, end)
  /// hands the family; null when a drive effect changes that drive with the parameters, or when
  /// the family prepares nothing.
  std::shared_ptr<const Family::Prepared> Prepare(const io::Record& r, size_t end) const;
  /// The effective drive after the drive effects, on samples [from, end); and the family's
  /// regressors for a linear family (rows = samples from..end).
  void EffectiveDrive(const io::Record& r, std::span<const double> effect_params, size_t from, size_t end,
                      std::vector<double>& ue) const;
  /// Applies the output effects in place to y on samples [from, end) of the record (y[0] = rest).
  void ApplyOutputEffects(const io::Record& r, std::span<const double> effect_params, size_t from,
                          std::span<double> y) const;
  size_t family_param_count() const { return family_->params().size(); }

 private:
  std::shared_ptr<const Family> family_;
  std::vector<EffectKind> effects_;
  DataScale scale_;
  std::vector<ParamInfo> params_;
  std::vector<size_t> effect_offset_;  ///< index of each effect's first parameter in p
};

/// The offset o of a record given the model output over the window and its rest output (polarity
/// applied to both by the caller).
double RecordOffset(const io::Record& r, std::span<const double> signed_yhat, double signed_rest_output);

}  // namespace pz::records
