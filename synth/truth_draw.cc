#include "synth/truth_draw.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace pz::synth {
namespace {

using model::DataScale;
using model::EffectKind;

// The draws of one effect (null: none of that check). Records: the effect's parameters in the
// library's order (EffectDef::Params); fin: the copies in the fin bench's box
// (records/fin_effects.h).
struct EffectTruths {
  const char* effect = "";
  std::vector<double> (*records)(TruthDraw&, const DataScale&) = nullptr;
  FinTruth (*fin)(TruthDraw&, bool other_form) = nullptr;
};

using Params = std::vector<double>;

// One line per effect of the library, in its chain order; the draws of each in the order written
// (the seeded checks' truths depend on it).
const EffectTruths kTruths[] = {
    {.effect = "driver-lowpass",
     .records = [](TruthDraw& d, const DataScale&) -> Params { return {d.Uniform(0.004, 0.03)}; },
     .fin = [](TruthDraw& d, bool other_form) -> FinTruth {
       const double tau = d.LogUniform(0.005, 0.08);
       if (other_form)
         return {"second-order (two poles)", tau, {{tau / 2}, {tau / 2}}};  // same total lag
       return {"first-order", tau, {{tau}}};
     }},
    {.effect = "quadratic-drive",
     .records = [](TruthDraw& d, const DataScale&) -> Params {
       const double s = d.Sign();
       return {s * d.Uniform(0.0005, 0.002)};
     },
     .fin = [](TruthDraw& d, bool) -> FinTruth {
       const double s = d.Sign();
       const double c2 = s * d.LogUniform(1e-5, 2e-4);
       return {"quadratic", c2, {{c2}}};
     }},
    {.effect = "creep",
     .records = [](TruthDraw& d, const DataScale&) -> Params {
       const double s = d.Sign();
       const double k = s * d.Uniform(0.03, 0.15);
       return {k, d.Uniform(0.5, 2)};
     },
     .fin = [](TruthDraw& d, bool other_form) -> FinTruth {
       const double k = d.LogUniform(0.02, 0.3), tau = d.LogUniform(0.5, 10);
       if (other_form)  // a decade apart, one gain
         return {"two relaxations", k, {{k / 2, tau / 3}, {k / 2, tau * 3}}};
       return {"one relaxation", k, {{k, tau}}};
     }},
    {.effect = "delay",
     .records = [](TruthDraw& d, const DataScale&) -> Params { return {d.Uniform(0.003, 0.02)}; },
     .fin = [](TruthDraw& d, bool) -> FinTruth {
       const double tau = d.LogUniform(0.003, 0.05);
       return {"pure delay", tau, {{tau}}};
     }},
    // The bound 4–10 % of the half range, the knee rate r_m/τ_r at ½–2 × the peak rate of the
    // dominant sine over the range (a lag that saturates within the records' rates).
    {.effect = "rate-dependence",
     .records = [](TruthDraw& d, const DataScale& s) -> Params {
       const double r_m = d.Uniform(0.04, 0.1) * s.u_half;
       const double knee = d.LogUniform(0.5, 2) * 2 * std::numbers::pi * s.f_dom * s.u_half;
       return {r_m, r_m / knee};
     }},
    {.effect = "hinge-friction",
     .fin = [](TruthDraw& d, bool) -> FinTruth {
       const double fc = d.LogUniform(0.02, 0.3), sigma = d.LogUniform(500, 1e4);
       return {"Dahl", fc, {{fc, sigma}}};
     }},
    {.effect = "cubic-stiffening",
     .fin = [](TruthDraw& d, bool) -> FinTruth {
       const double k3 = d.LogUniform(3e5, 1e7);
       return {"cubic", k3, {{k3}}};
     }},
    // Log creep: equal weights, 1–4 % of the output per relaxation (as many as the scale gives).
    {.effect = "creep-spectrum",
     .records = [](TruthDraw& d, const DataScale& s) -> Params {
       const size_t n = EffectKind::Named("creep-spectrum")->Params(s).size();
       return Params(n, d.Uniform(0.01, 0.04));
     }},
    // A mode the check's drives (sines, multisines and triangles of 1–6 Hz at 500 Hz) excite: its
    // corners ring, and a chirp to 6 Hz feels the gain rise below it: f_n 8–30 × the dominant drive
    // frequency of the scale, ζ 0.02–0.1, most of the output through it.
    {.effect = "resonance",
     .records = [](TruthDraw& d, const DataScale& s) -> Params {
       const double a = d.Uniform(0.6, 1.0);
       const double f_n = std::min(d.LogUniform(8, 30) * s.f_dom, 0.3 * s.fs);
       return {a, f_n, d.LogUniform(0.02, 0.1)};
     }},
    {.effect = "friction",
     .records = [](TruthDraw& d, const DataScale&) -> Params { return {d.Uniform(0.05, 0.4)}; }},
    {.effect = "stiffening",
     .records = [](TruthDraw& d, const DataScale&) -> Params {
       const double s = d.Sign();
       return {s * d.Uniform(0.02, 0.12)};
     }},
    {.effect = "drift",
     .records = [](TruthDraw& d, const DataScale&) -> Params {
       const double s = d.Sign();
       return {s * d.Uniform(0.03, 0.15)};
     },
     .fin = [](TruthDraw& d, bool) -> FinTruth {
       const double s = d.Sign();
       const double r = s * d.LogUniform(0.002, 0.05);
       return {"linear", r, {{r}}};
     }},
};

// The table's line of an effect (null: none); a line naming no effect of the library is a bug
// (std::logic_error from EffectKind::Named on first use).
const EffectTruths* TruthsOf(EffectKind e) {
  static const std::vector<std::pair<EffectKind, const EffectTruths*>> keyed = [] {
    std::vector<std::pair<EffectKind, const EffectTruths*>> k;
    for (const EffectTruths& t : kTruths) k.push_back({EffectKind::Named(t.effect), &t});
    return k;
  }();
  for (const auto& [kind, t] : keyed)
    if (kind == e) return t;
  return nullptr;
}

}  // namespace

double TruthDraw::Uniform(double lo, double hi) { return lo + (hi - lo) * u01_(); }
double TruthDraw::LogUniform(double lo, double hi) {
  return lo * std::exp(std::log(hi / lo) * u01_());
}
double TruthDraw::Sign() { return u01_() < 0.5 ? -1.0 : 1.0; }

std::vector<double> DrawRecordsTruth(EffectKind effect, TruthDraw& draw, const DataScale& scale) {
  const EffectTruths* t = effect.none() ? nullptr : TruthsOf(effect);
  return t != nullptr && t->records != nullptr ? t->records(draw, scale) : Params{};
}

FinTruth DrawFinTruth(EffectKind effect, TruthDraw& draw, bool other_form) {
  const EffectTruths* t = effect.none() ? nullptr : TruthsOf(effect);
  return t != nullptr && t->fin != nullptr ? t->fin(draw, other_form) : FinTruth{};
}

}  // namespace pz::synth
