// `piezoid diagnose-check --records-family F --real-like`: the records diagnosis
// (diagnose/diagnose.h) on real-like stack sets (synth/reallike.h) whose plant is not any family
// of the product: per trial a plant drawn around the defaults (creep on or off, a lag of 0 or 0.5–3
// samples, the density's asymmetry, the hysteresis share, the reversible curvature, the amplitude,
// the noise), a major-loop training sine and the withheld records (a second sine, a ramped
// amplitude, random reversals). Each trial is checked against the truth that made it: the noise
// floor the diagnosis used against the true one; the excitation report (the ramped and reversal
// records need minor loops the major loop lacks, the second sine needs nothing); the named effect
// against the effects the plant has (creep, delay, and quadratic-drive for a reversible curvature
// |c| ≥ 0.05; the asymmetric density has no effect of its own: the Preisach plant is no family plus
// one effect).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "diagnose/diagnose.h"
#include "synth/reallike.h"

namespace pz::diagnose {

struct RealLikeCheckOptions {
  std::string family = "prandtl-ishlinskii";
  int trials = 10;
  uint64_t seed = 1;
  synth::RealLikeOptions
      base;  ///< lengths, rates, sensor; the plant is drawn around base.stack per trial
  RecordDiagnoseOptions diagnose;  ///< family set per trial; no proposal
};

/// A trial: the drawn plant, what the diagnosis said (diagnose/verdict.h) and how it compares.
struct RealLikeCheckTrial : TrialVerdict {
  uint64_t seed = 0;
  std::string description;  ///< the drawn plant
  std::vector<std::string>
      truth_effects;  ///< library effects the plant has: "creep", "delay", "quadratic-drive"
  double floor_truth = 0, floor_estimate = 0;
  std::string floor_used;
  bool excitation_right = false;  ///< ramp and reversals flagged for their reversals, major-2 not
  std::string excitation;         ///< which records were flagged for what
  bool excitation_note = false;   ///< the verdict carries the excitation-gap sentence
  bool named_present = false;     ///< the named effect is one the plant has
};

struct RealLikeCheckSummary {
  std::vector<RealLikeCheckTrial> trials;
  int excitation_right = 0, excitation_notes = 0, significant = 0, named = 0, named_present = 0;
  double floor_ratio_min = 0, floor_ratio_max = 0;  ///< estimate / truth
  double wall_time_s = 0;
};

/// Runs the trials (seeds seed, seed + 1, …). Throws InputError on bad options.
RealLikeCheckSummary RunRealLikeCheck(
    const RealLikeCheckOptions& options,
    const std::function<void(const RealLikeCheckTrial&, int)>& on_trial = {});

}  // namespace pz::diagnose
