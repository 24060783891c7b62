#include "diagnose/reallike_check.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "model/status.h"
#include "opt/random.h"
#include "synth/synthetic.h"

namespace pz::diagnose {

RealLikeCheckSummary RunRealLikeCheck(
    const RealLikeCheckOptions& o,
    const std::function<void(const RealLikeCheckTrial&, int)>& on_trial) {
  if (o.trials < 1) throw InputError(FieldError("trials", o.trials, "must be >= 1"));
  const auto start = std::chrono::steady_clock::now();
  RealLikeCheckSummary sum;
  for (int i = 0; i < o.trials; ++i) {
    RealLikeCheckTrial t;
    t.seed = o.seed + static_cast<uint64_t>(i);
    opt::Rng rng(t.seed * 104729 + 11);
    synth::RealLikeOptions g = o.base;
    g.seed = t.seed;
    g.ramp = g.reversals = g.second_sine = true;
    g.stack.creep_per_decade = rng.Uniform01() < 1.0 / 3 ? 0 : synth::UniformDraw(rng, 0.005, 0.03);
    g.sensor.lag_samples = rng.Uniform01() < 1.0 / 3 ? 0 : synth::UniformDraw(rng, 0.5, 3);
    g.stack.asymmetry = synth::UniformDraw(rng, -1.5, 1.5);
    g.stack.hysteresis_share = synth::UniformDraw(rng, 0.1, 0.25);
    g.stack.quadratic = synth::UniformDraw(rng, -0.2, 0.2);
    g.amplitude_share = synth::UniformDraw(rng, 0.35, 0.48);
    g.sensor.noise_white_um = synth::UniformDraw(rng, 0.03, 0.1);
    if (g.stack.creep_per_decade > 0) t.truth_effects.push_back("creep");
    if (g.sensor.lag_samples > 0) t.truth_effects.push_back("delay");
    if (std::abs(g.stack.quadratic) >= 0.05) t.truth_effects.push_back("quadratic-drive");
    std::ostringstream desc;
    desc.precision(3);
    desc << "creep " << g.stack.creep_per_decade << "/dec, lag " << g.sensor.lag_samples
         << ", quad " << g.stack.quadratic << ", asym " << g.stack.asymmetry << ", hyst "
         << g.stack.hysteresis_share;
    t.description = desc.str();
    const synth::RealLikeSet s = GenerateRealLikeSet(g);
    t.floor_truth = s.realised_floor_um;
    RecordDiagnoseOptions dopt = o.diagnose;
    dopt.family = o.family;
    dopt.propose = false;
    const RecordDiagnosis d = DiagnoseRecords(s.set, dopt);
    t.floor_estimate = d.noise.sigma;
    t.floor_used = d.noise.used;
    t.excitation_right = true;
    for (const records::WithheldExcitation& w : d.excitation.withheld) {
      const std::string& name = s.set.records[w.record].name;
      bool reversals = false;
      for (const records::ExcitationNeed& n : w.needs) {
        t.excitation += (t.excitation.empty() ? "" : " ") + name + ":" + ExcitationNeedName(n.kind);
        reversals = reversals || n.kind == records::ExcitationNeed::Kind::kReversals;
      }
      if (reversals != (name != "major-2")) t.excitation_right = false;
    }
    if (t.excitation.empty()) t.excitation = "none";
    t.excitation_note = !d.excitation_note.empty();
    static_cast<TrialVerdict&>(t) = TrialVerdictOf(d);
    if (d.named >= 0)
      t.named_present = std::find(t.truth_effects.begin(), t.truth_effects.end(), t.named) !=
                        t.truth_effects.end();
    const double ratio = t.floor_estimate / t.floor_truth;
    sum.floor_ratio_min = i == 0 ? ratio : std::min(sum.floor_ratio_min, ratio);
    sum.floor_ratio_max = i == 0 ? ratio : std::max(sum.floor_ratio_max, ratio);
    sum.excitation_right += t.excitation_right;
    sum.excitation_notes += t.excitation_note;
    sum.significant += t.significant;
    sum.named += d.named >= 0;
    sum.named_present += t.named_present;
    sum.trials.push_back(t);
    if (on_trial) on_trial(t, i);
  }
  sum.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return sum;
}

}  // namespace pz::diagnose
