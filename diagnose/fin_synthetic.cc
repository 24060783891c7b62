#include "diagnose/fin_synthetic.h"

#include <cmath>
#include <numbers>
#include <sstream>
#include <utility>

#include "diagnose/synthetic.h"
#include "model/saturation.h"

namespace pz::diagnose {
namespace {

using model::Effect;
using model::EffectKind;
using records::UniformDraw;

// Box–Muller on the portable generator. Not records::NormalDraw (which takes log(1 − u)): the same
// distribution from other draws, and the bundled benches' checks are pinned on these.
double Normal(opt::Rng& rng) {
  const double u1 = std::max(rng.Uniform01(), 1e-300), u2 = rng.Uniform01();
  return std::sqrt(-2 * std::log(u1)) * std::cos(2 * std::numbers::pi * u2);
}

// The paper's nine cases (V, f) and split (training 1, 5, 6, 7).
struct CaseDef {
  int number;
  double v, f;
  bool training;
};
constexpr CaseDef kCases[9] = {{1, 375, 0.25, true},  {2, 375, 0.5, false}, {3, 375, 1.0, false},
                               {4, 500, 0.25, false}, {5, 500, 0.5, true},  {6, 500, 1.0, true},
                               {7, 750, 0.25, true},  {8, 750, 0.5, false}, {9, 750, 1.0, false}};

}  // namespace

std::string SyntheticTrial::Describe() const {
  std::ostringstream os;
  os << "seed " << seed << ": " << model::EffectName(truth);
  if (!form.empty()) os << " (" << form << ")";
  for (const Effect& e : effects) os << " " << e.Describe();
  return os.str();
}

std::vector<DiagCase> SimulateBench(const model::BimorphPlant& plant,
                                    const model::BimorphParams& params,
                                    const std::vector<Effect>& effects,
                                    const std::vector<std::pair<double, double>>& saturations,
                                    const SyntheticOptions& o, opt::Rng& rng) {
  const model::EffectSimulator sim(plant);
  std::vector<DiagCase> cases;
  for (int c = 0; c < 9; ++c) {
    const model::Sinusoid d{kCases[c].v, kCases[c].f};
    model::BimorphParams p = params;
    p.b1 = saturations[c].first;
    p.b2 = saturations[c].second;
    std::vector<double> y(d.NumSamples());
    const model::SimulationSummary s = sim.SimulateAngle(p, effects, d, y);
    if (!s.ok())
      throw InputError("synthetic bench, case " + std::to_string(kCases[c].number) + ": " +
                       s.message);
    for (double& v : y) {
      v += o.jitter_rms_deg * Normal(rng);
      if (o.quantum_deg > 0) v = o.quantum_deg * std::round(v / o.quantum_deg);
    }
    cases.push_back(MakeCase(kCases[c].number, d, std::move(y), kCases[c].training));
  }
  return cases;
}

SyntheticTrial MakeSyntheticTrial(const model::BimorphPlant& plant, uint64_t seed,
                                  const SyntheticOptions& o) {
  opt::Rng rng(seed);
  SyntheticTrial t;
  t.seed = seed;
  // The bench plant, around the physical bench's values.
  model::BimorphParams& p = t.plant;
  p.mu = UniformDraw(rng, 60, 130);
  p.delta = UniformDraw(rng, 0.07, 0.13);
  p.alpha = UniformDraw(rng, 1.5e-3, 3.5e-3);
  p.beta = UniformDraw(rng, 4e-3, 8e-3);
  p.gamma = p.beta * UniformDraw(rng, 0.3, 0.8);
  p.a1 = UniformDraw(rng, 0.05, 0.15);
  p.a2 = UniformDraw(rng, 0.1, 0.2);
  // Saturations: the paper's regression with a ±4 % spread.
  const model::SaturationRegression reg = model::PaperSaturationRegression();
  std::vector<std::pair<double, double>> sat;
  for (const CaseDef& c : kCases) {
    const model::SaturationPair s = reg.Predict(c.v, c.f);
    sat.push_back({s.b1 * UniformDraw(rng, 0.96, 1.04), s.b2 * UniformDraw(rng, 0.96, 1.04)});
  }
  // The effect.
  std::vector<EffectKind> kinds = o.kinds;
  if (kinds.empty())
    for (const auto& e : model::EffectLibrary()) kinds.push_back(e.kind);
  const bool none = rng.Uniform01() < o.none_probability;
  const bool other_form = rng.Uniform01() < o.other_form_probability;
  if (!none) {
    t.truth = kinds[rng.UniformBelow(kinds.size())];
    model::TruthDraw draw([&rng] { return rng.Uniform01(); });
    model::FinTruth truth = t.truth->DrawFinTruth(draw, other_form);
    if (truth.parts.empty()) {
      throw InputError(std::string("synthetic bench: effect '") + t.truth.name() +
                       "' draws no fin truth (its DrawFinTruth in model/effect_library.cc)");
    }
    t.form = std::move(truth.form);
    t.magnitude = truth.magnitude;
    for (std::vector<double>& part : truth.parts) t.effects.push_back({t.truth, std::move(part)});
  }
  try {
    t.cases = SimulateBench(plant, p, t.effects, sat, o, rng);
  } catch (const InputError& e) {
    throw InputError(t.Describe() + ": " + e.what());
  }
  return t;
}

}  // namespace pz::diagnose
