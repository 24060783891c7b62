// Hysteresis models of a piezo stack stage (seed 002, spec committee-machine.md), driven by a
// sampled voltage u_k = u(k Δt) [V], output ŷ [µm]:
//
//  Bouc–Wen stack model with driver filter, parameters (α, β, γ, d, fc):
//    ŷ = LPF_fc[ d (u − h) ],   dh/dt = α du/dt − β |du/dt| h − γ du/dt |h|,
//    LPF_fc the first-order low-pass dŷ/dt = 2π fc (x − ŷ), x = d (u − h);
//    α [-], β, γ [1/V], d [µm/V], fc [Hz].
//  Backlash-like model (Su et al.), parameters (α, c, B1):
//    dŷ/dt = α |du/dt| (c u − ŷ) + B1 du/dt;   α [1/V], c, B1 [µm/V].
//
// Discretisation (stated, and tested for convergence against finer steps):
//  - between samples the drive is the straight line through (t_k, u_k), (t_{k+1}, u_{k+1}): du/dt
//    is the constant (u_{k+1} − u_k)/Δt on each interval. Nothing else is assumed about u.
//  - both hysteresis laws are rate-independent: divided by du/dt they are ODEs in u,
//      dh/du = α − (β s + γ sgn h) h,   s = sgn(du),   (Bouc–Wen, linear in h on each sign of h)
//      d(cu − ŷ)/du = c − B1 − α s (cu − ŷ)            (backlash-like, linear in w = cu − ŷ)
//    and are integrated EXACTLY over each linear piece of u (an exponential in Δu, through expm1;
//    a sign change of h inside a piece is located in closed form and the piece split there). For
//    the backlash-like model the result is therefore exact for the piecewise-linear drive.
//  - the filter is integrated exactly for an input x that is linear between the points where it
//    is evaluated (first-order hold): x = d (u − h) is evaluated at M equal sub-steps of every
//    sample interval (StackSimOptions::substeps, default 2); the only discretisation error left is
//    the curvature of x inside a sub-step, second order in Δt / M.
//  - initial state: at rest at the first sample u_0 (the 400 V offset of the bench), by default
//  with
//    no hysteretic memory, h(0) = 0 and ŷ(0) = d u_0 (the filter in steady state) for Bouc–Wen;
//    ŷ(0) = c u_0 (on the anhysteretic line, w = 0) for the backlash-like model. StackRestState
//    gives the memory of a stack resting after use (model/prandtl_ishlinskii.h InitialState): the
//    state after the drive rose from that virgin rest by a range R and came back down to u_0
//    (descended), or fell by R and came back up (ascended) — two exact pieces of the laws above.
//
// The simulations allocate nothing and keep no state between calls: they are pure functions of
// (parameters, u, Δt), safe on any number of threads. A diverging parameter set (e.g. β + γ < 0
// lets h grow exponentially) produces non-finite or huge outputs; callers judge them.
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "model/prandtl_ishlinskii.h"
#include "model/status.h"

namespace pz::model {

struct StackBoucWenParams {
  double alpha = 0.3;     ///< [-]
  double beta = 0.0045;   ///< [1/V]
  double gamma = 0.0015;  ///< [1/V]
  double d = 0.05;        ///< stack gain [µm/V]
  double fc_hz = 1500;    ///< driver filter cut-off [Hz], > 0
  /// Finite values and fc > 0; the error names the field.
  Status Validate() const;
};

struct BacklashLikeParams {
  double alpha = 0.02;  ///< [1/V], ≥ 0
  double c = 0.05;      ///< [µm/V]
  double b1 = 0.02;     ///< [µm/V]
  /// Finite values and α ≥ 0; the error names the field.
  Status Validate() const;
};

struct StackSimOptions {
  int substeps = 2;  ///< filter sub-steps per sample interval (Bouc–Wen only), 1 … 1024
  /// The hysteretic memory at rest at u_0: h(0) (Bouc–Wen) or w(0) = c u_0 − ŷ(0) (backlash-like);
  /// StackRestState. 0: the virgin state.
  double rest_state = 0;
  Status Validate() const;
};

enum class StackFamily : int { kBoucWen = 0, kBacklashLike = 1 };

/// "bouc-wen", "backlash-like".
const char* StackFamilyName(StackFamily family);
/// "Bouc–Wen", "backlash-like" (for reports).
const char* StackFamilyTitle(StackFamily family);
/// Parses a family name as printed by StackFamilyName; nullopt if unknown.
std::optional<StackFamily> ParseStackFamily(std::string_view name);
/// The parameter names in vector order: {alpha, beta, gamma, d, fc_Hz} or {alpha, c, B1}.
std::vector<std::string> StackParamNames(StackFamily family);

/// Parameters from / to a vector in StackParamNames order. FromVector throws InputError on a wrong
/// size (naming the family and both sizes).
StackBoucWenParams BoucWenFromVector(std::span<const double> p);
BacklashLikeParams BacklashLikeFromVector(std::span<const double> p);
std::vector<double> ToVector(const StackBoucWenParams& p);
std::vector<double> ToVector(const BacklashLikeParams& p);

/// Simulates the Bouc–Wen stack model on the samples u (step dt > 0) into yhat (same length; it
/// may not alias u); h, when not empty, receives the hysteretic state at the samples. Throws
/// InputError on invalid parameters, options, dt or lengths.
void SimulateStackBoucWen(const StackBoucWenParams& p, std::span<const double> u, double dt,
                          std::span<double> yhat, const StackSimOptions& options = {},
                          std::span<double> h = {});

/// Simulates the backlash-like model on the samples u into yhat (same length; may not alias u).
/// Exact for the piecewise-linear drive; the step does not enter. Throws InputError on invalid
/// parameters or lengths. w0: the memory at rest (StackSimOptions::rest_state).
void SimulateBacklashLike(const BacklashLikeParams& p, std::span<const double> u,
                          std::span<double> yhat, double w0 = 0);

/// The memory at rest in state s (header comment; range R > 0 the drive's full range): h of the
/// Bouc–Wen law, w of the backlash-like one; 0 when s is centred (resolve kAuto first:
/// ResolveInitialState). Rate-independent: exact.
double StackRestState(const StackBoucWenParams& p, double range, InitialState s);
double StackRestState(const BacklashLikeParams& p, double range, InitialState s);
/// The backlash-like law's exact update of w over a straight piece of drive du (exposed for the
/// rest state and tests): dw/du = (c − B1) − α sgn(du) w.
double BacklashLikeStateStep(double w, double du, const BacklashLikeParams& p);

/// Either family from a parameter vector in StackParamNames order.
void SimulateStack(StackFamily family, std::span<const double> params, std::span<const double> u,
                   double dt, std::span<double> yhat, const StackSimOptions& options = {});

/// The exact Bouc–Wen state update over a straight piece of drive of signed length du [V] (exposed
/// for tests): dh/du = α − (β sgn(du) + γ sgn h) h from h.
double BoucWenStateStep(double h, double du, double alpha, double beta, double gamma);

}  // namespace pz::model
