// The one library of candidate unmodelled effects (issue 21): every effect is written once, as one
// small class in model/effect_library.cc, with its name, title, equation, stage, parameters (ranges
// scaled to the data), its arithmetic and the id of its C step (kernel); the registry (Effects())
// lists them in stage order, and one handle (EffectKind) names an effect for every user. What a
// protocol adds to an effect lives with the protocol, keyed by the effect: the fin bench's box in
// records/fin_effects.cc, the truths of the synthetic checks in synth/truth_draw.cc. Both users
// run the same code:
//   * records/ (records::RecordModel, every plant family on measured records) applies the drive
//     stage to the record's sampled drive and the output stage to the family's output;
//   * the bimorph-fin bench (records/fin_effects.h, EffectSimulator) applies the same drive stage
//     to its sinusoid sampled on a fine grid (or, for memoryless effects, pointwise with the delay
//     as an exact time shift), the same output stage to the fin angle, and runs beam effects —
//     and, on its CVODE path, the drive effects too — as BimorphExtensions (model/bimorph_ode.h).
//
//   name             stage   equation                                   parameters
//   driver-lowpass   drive   τ u̇_e = u − u_e                           tau_s
//   quadratic-drive  drive   u_e = u + c₂ u²                            c2
//   creep            drive   τ_c ẋ = k_c (u − u_0) − x, u_e = u + x     k_c, tau_c_s
//   delay            drive   u_e(t) = u(t − τ_d)                        tau_d_s
//   rate-dependence  drive   u_e = play_λ[u], λ = r_m tanh(τ_r |u̇|/r_m)  r_m, tau_r_s
//   hinge-friction   beam    Ḟ = σ ẇ (1 − F/F_c sgn ẇ), tip force −F    fc_n, sigma_n_per_m
//   cubic-stiffening beam    tip force −k₃ w_tip³                       k3_n_per_m3
//   creep-spectrum   output  y_e = y − Σ w_i (y − x_i), τ_i ẋ_i = y − x_i    w_i ≥ 0 at τ_i = 0.05
//                                                                       s … T
//   resonance        output  y_e = (1 − a) y + a q,                      share, f_n_hz, zeta
//                            q̈ + 2ζω q̇ + ω² q = ω² y
//   friction         output  y_e = play_r[y]                            r
//   stiffening       output  y_e = y − k₃ Y ((y − y_0)/Y)³              k3
//   drift            output  y_e = y + ρ (t − t_w)                      rate
//
// Drive effects act on u in registry order, output effects on y in registry order; params[0] is the
// magnitude (zero: identity; the creep spectrum's weights are each their relaxation's magnitude,
// all zero the identity). A drive filter starts at rest at u[0] and is discretised exactly for
// a drive linear between samples; the delay reads the drive by linear interpolation (u[0] before).
// Beam effects exist only for a plant with a beam (the bimorph fin); records families refuse them.
//
// Seams for later forms of the same effect (each one more virtual method of EffectDef, written
// next to the arithmetic it mirrors): a per-sample step form for a controller (state in a caller's
// buffer of StateSize() doubles, one Step(p, state, u) per sample), and a C-code emission of that
// step (EmitC) for the controller export. See docs/architecture.md, "One effect library".
//
// Pure library: no I/O. The effects are immutable singletons, safe from any thread.
#pragma once

#include <cmath>
#include <compare>
#include <cstddef>
#include <iosfwd>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace pz::model {

class BimorphExtension;

/// Scales measured on the data a model is made for (records::MeasureScale measures them).
struct DataScale {
  double u_min = 0, u_max = 0;  ///< drive range over the scored samples
  double u_half = 1;            ///< (u_max − u_min)/2, > 0
  double y_half = 1;            ///< half range of the response over the scored samples, > 0
  double gain = 1;              ///< |slope| of the least-squares line y = a u + b, > 0
  int polarity = 1;             ///< sign of that slope
  double f_dom = 1;             ///< dominant drive frequency [Hz] (from the drive's reversals)
  double fs = 1;                ///< sample rate [Hz]
  double duration = 1;          ///< longest scored window [s]
};

/// One searched parameter: name, unit, range, scale of the search.
struct ParamInfo {
  std::string name;
  std::string unit;
  double lower = 0, upper = 1;
  bool log_scale = false;
};

enum class EffectStage : int {
  kDrive = 0,   ///< shapes u before the plant
  kBeam = 1,    ///< couples to the beam state (a plant with a beam only: CVODE path)
  kOutput = 2,  ///< acts on the plant's output
};
const char* StageName(EffectStage stage);

/// Where the output stage reads time and scale: y[k] is at time (k − origin)·dt from the window's
/// start; y[0] is the rest output; y_half the data's half range (EffectDef::Params's scale).
struct OutputFrame {
  double dt = 1;
  double origin = 0;
  double y_half = 1;
  double duration = 1;  ///< the data's longest scored window [s] (DataScale::duration)
};

/// One effect. Subclasses override the methods of their stage; the defaults are the identity.
class EffectDef {
 public:
  virtual ~EffectDef() = default;
  virtual const char* name() const = 0;
  /// A former name still accepted by FindEffect (drift's "output-drift"); null: none.
  virtual const char* former_name() const { return nullptr; }
  virtual const char* title() const = 0;
  virtual const char* equation() const = 0;
  virtual EffectStage stage() const = 0;
  /// The parameters, ranges scaled to the data (params[0] is the magnitude).
  virtual std::vector<ParamInfo> Params(const DataScale& scale) const = 0;

  // ---- drive stage ----
  /// In place on a drive sampled every dt (linear in between, at rest at u[0] before u[0]).
  virtual void ApplyDrive(std::span<const double> p, double dt, std::span<double> u) const;
  /// True when ApplyDrive acts sample by sample without memory (valid on any, even non-uniform,
  /// grid).
  virtual bool memoryless() const { return false; }
  /// The effect's pure time shift [s] (the delay's τ_d; 0 else): for a caller with an analytic
  /// drive and a time-invariant chain started from rest, exact in place of ApplyDrive.
  virtual double TimeShift(std::span<const double>) const { return 0; }

  // ---- output stage ----
  /// In place on the output y (y[0] = rest output).
  virtual void ApplyOutput(std::span<const double> p, const OutputFrame& frame,
                           std::span<double> y) const;
  /// True when ApplyOutput is linear and homogeneous in y (L[a y₁ + b y₂] = a L[y₁] + b L[y₂], the
  /// rest output a fixed point): a linear family can take it on each of its regressors.
  virtual bool linear_output() const { return false; }

  // ---- step kernel ----
  /// Constants a step kernel needs beyond the parameters, derived from the data scale (the creep
  /// spectrum's relaxation times); empty for most effects.
  virtual std::vector<double> KernelData(const DataScale&) const { return {}; }

  // ---- beam stage, and the continuous-time form of drive effects ----
  /// The effect as an extension of the bimorph ODE (model/bimorph_ode.h); null when it has none
  /// (output effects; the delay, which the CVODE path takes as a shift of the output times).
  virtual std::unique_ptr<BimorphExtension> MakeExtension(std::span<const double> p) const;

  // ---- per-sample step (controller export) ----
  /// The id of the effect's step in the C kernels (model/kernels/common.h PZK_*, run by
  /// model/kernels/chain.h for records/stepper.h and copied into `piezoid export` headers); 0:
  /// none (beam effects, which only the fin bench's CVODE path runs). Drive effects take ids below
  /// PZK_STACK_BOUC_WEN (10), output effects from PZK_FRICTION (30).
  virtual int kernel() const { return 0; }
};

/// The handle of an effect: the library's effect, or none (default). Compared in chain order
/// (none first), hashable, printed by name. Every user — records fits and diagnoses, the fin bench,
/// the synthetic checks, the stepper — names an effect by this one handle.
class EffectKind {
 public:
  constexpr EffectKind() = default;
  EffectKind(const EffectDef& def) : def_(&def) {}  // NOLINT: an effect is its own handle
  /// The registered effect of that name or former name; throws std::logic_error if there is none
  /// (for code that names an effect it knows; input goes through FindEffect / the parsers).
  static EffectKind Named(std::string_view name);

  bool none() const { return def_ == nullptr; }
  const EffectDef* def() const { return def_; }
  const EffectDef* operator->() const { return def_; }
  /// The effect's name, "none" for none.
  const char* name() const;

  friend bool operator==(EffectKind a, EffectKind b) { return a.def_ == b.def_; }
  friend std::strong_ordering operator<=>(EffectKind a, EffectKind b);

 private:
  const EffectDef* def_ = nullptr;
};
std::ostream& operator<<(std::ostream& os, EffectKind kind);
/// kind.name().
inline const char* EffectName(EffectKind kind) { return kind.name(); }

/// The exact first-order-hold step of a first-order low-pass τ ẋ = v − x over a sample of dt (v
/// linear in between): x ← a x + (1 − a) v_prev + (v − v_prev) c. One arithmetic for the drive
/// low-passes, the creep spectrum's relaxations and their joint solve (records/spectrum_solve.h).
struct LowpassStep {
  double a, c;
};
inline LowpassStep LowpassConsts(double tau, double dt) {
  const double a = std::exp(-dt / tau);
  return {a, 1 - tau * (1 - a) / dt};
}

/// Every effect, in stage order (the order in which a chain applies them).
const std::vector<const EffectDef*>& Effects();
/// The effect of that name (or former name), or null.
const EffectDef* FindEffect(std::string_view name);
/// Position of an effect in Effects() (the chain order); throws std::logic_error if unregistered.
size_t EffectIndex(const EffectDef& effect);

}  // namespace pz::model

template <>
struct std::hash<pz::model::EffectKind> {
  size_t operator()(pz::model::EffectKind k) const noexcept {
    return std::hash<const void*>()(k.def());
  }
};
