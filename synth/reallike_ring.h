// A second real-like generator (issue 45): a fast stack in a flexure stage, recorded at 10 kHz the
// way the records were, with truths the first generator (synth/reallike.h) does not
// have — for checking the noise floor and the model choice only, never for tuning them:
//
//  - a mechanical mode after the stack (a second-order low-pass of unit gain, f_n and ζ): every
//    record begins right after a step to its rest level, so its rest rings (the mode's free decay
//    from the step) and settles (a relaxation of the step, exponential), and fast drives excite it;
//  - training drives that are nested loops growing from a rest at the bottom of the range
//    (u = u_lo + a(t)(1 − cos 2πft)/2, a growing linearly to the whole range), at several rates;
//  - withheld compensation-like drives: a sine and a triangle through most of the range with
//    chatter (an inverse model's sample-to-sample jitter, the same in every repeat), each recorded
//    `repeats` times with the same drive (a repeat group, io/records.h), and loops growing at
//    another rate;
//  - a sensor whose white noise is far below what the stage repeats to: the non-repeatable part is
//    a slow wander (first-order coloured noise) of its own in each recording.
//
// The hysteresis and creep are RealLikePlant's (a Preisach model from its Everett function, log
// creep), with this generator's own density, stroke and range; the mode, the settling, the drives
// and the repeats are written here.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "io/records.h"
#include "synth/reallike.h"

namespace pz::synth {

struct RingingOptions {
  RealLikeStack stack;    ///< defaults set by RingingDefaults: ±90 V, 35 µm
  RealLikeSensor sensor;  ///< defaults: 10 kHz, 0.0012 µm white, 0.02 µm wander over 0.1 s
  double mode_hz = 740, mode_zeta = 0.04;
  double step_um = 6;       ///< the step the record starts right after (to the rest), response
  double settle_um = 0.15;  ///< the step's relaxation left at the record's start …
  double settle_s = 0.08;   ///< … and its time constant
  double rest_s = 0.6;
  std::vector<double> train_loops_hz = {20, 40};
  double loops_s = 1.2;  ///< each growing-loop record's length after its rest
  std::vector<double> withheld_loops_hz = {100};
  int repeats = 3;        ///< recordings of each chatter drive (0: no chatter drives)
  double chatter_s = 0.8;
  double chatter_share = 0.01;  ///< the chatter's RMS, share of the drive range
  double chatter_hz = 8;        ///< the sine's and the triangle's frequency
  uint64_t seed = 1;
};
/// The options with this generator's plant and sensor.
RingingOptions RingingDefaults();

struct RingingSet {
  io::RecordSet set;
  std::vector<RealLikeRecordTruth> truth;  ///< in set order
  RingingOptions options;
  double sensor_floor_um = 0;  ///< the white noise's realised RMS (what a settled rest shows)
  /// The realised RMS of (measured − noise-free − offset), less its mean over each record's window,
  /// over every scored sample: what a perfect model of the stage (mode included) leaves with the
  /// record's offset fitted; the repeats scatter about each other by this.
  double realised_floor_um = 0;
};

/// Generates the set (deterministic in the seed). Throws InputError on bad options.
RingingSet GenerateRingingSet(const RingingOptions& options);

}  // namespace pz::synth
