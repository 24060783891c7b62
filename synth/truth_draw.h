// The truths of the synthetic checks (issues 14, 21, 38, 46), per effect of the one library
// (model/effect_library.h), in one table keyed by the effect (kTruths in synth/truth_draw.cc):
// what a records check draws (its parameters on the synthetic stack's scale) and what a fin-bench
// check draws (one or more copies of the effect in the fin bench's units, in the library's form or
// in a form the library lacks). The library knows nothing of the checks; synth/synthetic.h draws
// its trials through these.
//
// Pure library: no I/O; the draws are deterministic in the caller's generator (each draw takes one
// uniform number, in the order written: a seed gives the same truths whatever else changes).
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include "model/effect_library.h"

namespace pz::synth {

/// Random draws of a synthetic check's truth on the caller's seeded generator (a source of uniform
/// numbers in [0, 1)); each draw takes one number, in the order written.
class TruthDraw {
 public:
  explicit TruthDraw(std::function<double()> uniform01) : u01_(std::move(uniform01)) {}
  double Uniform(double lo, double hi);     ///< lo + (hi − lo) u
  double LogUniform(double lo, double hi);  ///< lo (hi/lo)^u
  double Sign();                            ///< −1 if u < 0.5, else 1

 private:
  std::function<double()> u01_;
};

/// A drawn truth of the fin bench's check (synth/synthetic.h FinTrialDraw): one or more copies
/// of the effect simulated together (a second form the library lacks, e.g. two equal low-pass
/// poles), the drawn magnitude and the form's name.
struct FinTruth {
  std::string form;                        ///< e.g. "first-order", "two relaxations"
  double magnitude = 0;                    ///< physical units
  std::vector<std::vector<double>> parts;  ///< the parameters of each copy (fin-bench units)
};

/// The parameters of a records check's truth of `effect`, on the synthetic stack's scale
/// (SyntheticStackScale: 200 V peak to peak, about 0.1 y/V; `scale` for an effect whose parameter
/// count depends on the data, as creep-spectrum's); empty: the effect has no records truth (beam
/// effects).
std::vector<double> DrawRecordsTruth(model::EffectKind effect, TruthDraw& draw,
                                     const model::DataScale& scale);
/// A fin-bench check's truth of `effect` in the fin bench's units; `other_form` asks for a form
/// the library lacks where the effect has one. No parts: the effect has no fin truth (the fin bench
/// does not offer it).
FinTruth DrawFinTruth(model::EffectKind effect, TruthDraw& draw, bool other_form);

}  // namespace pz::synth
