// Synthetic benches for checking the diagnosis on data whose effect is withheld from it
// (`piezoid diagnose-check`): the bench plant (spec "bimorph-fin model") with parameters drawn
// around the physical bench's, an effect drawn at random from the library — in its library form or
// in another functional form the library does not have (a second-order amplifier, creep with two
// relaxations) — or none, at a random magnitude; the paper's nine cases and split; saturations from
// the paper's regression (Appendix B) with a random spread; read through the bench's encoder
// (2048-line quadrature, quantum 360/8192 deg) after a vibration jitter (RMS 0.003 deg).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "diagnose/problem.h"
#include "opt/random.h"

namespace pz::diagnose {

/// One drawn bench: what it holds (never shown to the diagnosis) and its cases.
struct SyntheticTrial {
  uint64_t seed = 0;
  model::EffectKind truth;             ///< the effect family (none: a clean bench)
  std::string form;                    ///< e.g. "first-order", "two relaxations"
  std::vector<model::Effect> effects;  ///< as simulated (library building blocks)
  double magnitude = 0;                ///< the drawn magnitude (physical units)
  model::BimorphParams plant;          ///< μ … a2 of the bench (b1, b2 per case)
  std::vector<DiagCase> cases;
  std::string Describe() const;
};

struct SyntheticOptions {
  double quantum_deg = 360.0 / 8192;     ///< encoder quantum [deg], ≥ 0 (0: no quantisation)
  double jitter_rms_deg = 0.003;         ///< vibration jitter before quantisation [deg], ≥ 0
  double none_probability = 0.2;         ///< share of clean benches, in [0, 1]
  double other_form_probability = 0.3;   ///< share of effects drawn in a form the library lacks
  std::vector<model::EffectKind> kinds;  ///< effects to draw from; empty = the whole library
};

/// Draws and simulates one bench (deterministic for the seed). Throws InputError if the plant
/// cannot be simulated (a bug: the drawn ranges are valid).
SyntheticTrial MakeSyntheticTrial(const model::BimorphPlant& plant, uint64_t seed,
                                  const SyntheticOptions& options);

/// Simulates a bench with given plant parameters and effects (paper's nine cases and split,
/// saturations given per case as b1 = sat[c].first, b2 = sat[c].second), quantised with jitter
/// drawn from rng.
std::vector<DiagCase> SimulateBench(const model::BimorphPlant& plant,
                                    const model::BimorphParams& params,
                                    const std::vector<model::Effect>& effects,
                                    const std::vector<std::pair<double, double>>& saturations,
                                    const SyntheticOptions& options, opt::Rng& rng);

}  // namespace pz::diagnose
