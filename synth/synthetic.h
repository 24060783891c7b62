// The one synthetic truth draw (issues 14, 38): trials whose truth is known, for the calibration
// checks (`piezoid diagnose-check`, diagnose/check.h) and the tests. A trial draws a plant around
// its nominal parameters and an effect of the library (kind, form, magnitude) or none, simulates
// it, reads it through a measurement (offset, noise, quantisation: `Measure`, the one reading of
// every synthetic record) and hands the diagnosis an io::RecordSet with the truth beside it. Two
// forms:
//
//  - the fin bench (`FinTrialDraw`): the bench plant (spec "bimorph-fin model") with parameters
//    drawn around the physical bench's, an effect drawn from the fin library — in its library form
//    or in another functional form the library does not have (a second-order amplifier, creep with
//    two relaxations: the effect's fin truth, synth/truth_draw.h) — the paper's nine cases and
//    split, saturations from the paper's regression (Appendix B) with a random spread, read through
//    the bench's encoder (2048-line quadrature, quantum 360/8192 deg) after a vibration jitter (RMS
//    0.003 deg); its records are the bench's (io/fin_records.h), as `diagnose --cases` reads a
//    folder;
//  - records of a family (`RecordsTrialDraw`): parameters drawn around the family's nominal set, a
//    random drive (a sine from an arbitrary phase after a rest, a multisine or a triangle), an
//    offset, white noise and quantisation, one record cut into a training and a withheld window.
//
// The building blocks are those of synthetic records in general, in the shape of real recordings:
// a rest segment, a drive that starts at an arbitrary phase (a sine, a multisine, a triangle, a
// square wave with finite slew, a sweep), a response offset, white noise and quantisation.
#pragma once

#include <cmath>
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "io/bench_data.h"
#include "io/records.h"
#include "model/bimorph.h"
#include "opt/random.h"
#include "records/fin_effects.h"
#include "records/model.h"
#include "synth/truth_draw.h"

namespace pz::synth {

enum class Waveform : int { kSine, kMultisine, kTriangle, kSquare, kSweep };
const char* WaveformName(Waveform w);

struct DriveShape {
  Waveform waveform = Waveform::kSine;
  double amplitude = 100;   ///< peak of the oscillating part [V]
  double bias = 0;          ///< mean drive [V] (also the rest level)
  double frequency_hz = 1;  ///< sine / triangle / square; multisine: the lowest line; sweep: start
  double frequency_end_hz = 10;  ///< sweep: end frequency; multisine: the highest line
  double phase_rad = 0;          ///< of the first excited sample (arbitrary phase: the drive jumps)
  double rest_s = 0.5;           ///< rest at `bias` before the excitation
  double duration_s = 3;         ///< excitation length
  double fs_hz = 1000;
  double slew_s = 0;  ///< square: rise time (0 = one sample)
  int lines = 8;      ///< multisine: log-spaced lines, random phases from seed
  uint64_t seed = 1;
};
/// The drive samples (t_k = k / fs from 0, rest then excitation). Throws InputError on bad shapes.
std::vector<double> MakeDrive(const DriveShape& shape);
/// A record of that drive: u = MakeDrive(shape), t_k = k / fs, the leading rest (the samples at
/// u[0]) counted; nothing scored, no response yet.
io::Record RecordOfDrive(const DriveShape& shape);

/// The data scale of the project's synthetic stack records (±100 V drive, ±10 µm response, gain
/// 0.1 µm/V, 1 Hz, 500 Hz sampling, 4 s): the truth models of tests and diagnose-check use it.
records::DataScale SyntheticStackScale();

/// Which uniform feeds Box–Muller's logarithm: 1 − u (never 0), or u as drawn (kept above 1e-300).
/// The same distribution from other draws; the fin bench's trials are pinned on kDrawn.
enum class NormalForm { kComplement, kDrawn };
/// A standard normal draw (Box–Muller on two of the generator's uniforms, u then v:
/// √(−2 ln u') cos(2π v)).
double NormalDraw(opt::Rng& rng, NormalForm form = NormalForm::kComplement);
/// A uniform draw in [lo, hi) (one Uniform01): the synthetic draws of every check (records, fin
/// benches, real-like stacks).
inline double UniformDraw(opt::Rng& rng, double lo, double hi) {
  return lo + (hi - lo) * rng.Uniform01();
}

/// x rounded to a multiple of q (q > 0), or x.
inline double Quantise(double x, double q) { return q > 0 ? q * std::round(x / q) : x; }

/// How a synthetic response is read.
struct Measurement {
  double offset = 0;     ///< added to the response
  double noise_std = 0;  ///< white Gaussian noise (none drawn when 0)
  double quantum = 0;    ///< response rounded to multiples of it (0 = none)
  uint64_t seed = 1;     ///< SynthesizeRecord's generator (Measure takes the caller's)
  NormalForm normal = NormalForm::kComplement;
};

/// Reads a response in place: y_k ← Quantise(y_k + (offset + noise_std n_k), quantum), n_k drawn
/// from rng in sample order (only when noise_std > 0).
void Measure(std::span<double> y, const Measurement& measurement, opt::Rng& rng);

/// A record of the truth model (polarity +1) on the drive: y = round_q(ŷ + offset + noise), read by
/// Measure with the generator of measurement.seed.
/// Window: the whole excitation (or [t0, t1] when t1 > t0); offset mode fit.
io::Record SynthesizeRecord(const records::RecordModel& truth, std::span<const double> params,
                            std::span<const double> weights, const DriveShape& shape,
                            const Measurement& measurement, const std::string& name,
                            model::CaseRole role, double t0_s = 0, double t1_s = 0);

// ---- the trials of a calibration check -------------------------------------------------------

/// One drawn trial: what it holds (never shown to the diagnosis) and its records.
struct SyntheticTrial {
  uint64_t seed = 0;
  records::EffectKind truth;           ///< the effect drawn (none: a clean trial)
  std::string form;                    ///< its form where it has several ("first-order", …)
  std::vector<records::Effect> effects;  ///< the fin bench: as simulated (library building blocks)
  double magnitude = 0;                ///< fin: the drawn magnitude (physical units); records:
                                       ///< the effect's last drawn parameter
  std::string description;             ///< the truth in words (effect, form, parameters, drive)
  io::RecordSet set;                   ///< what the diagnosis sees
};

/// One form of the draw: a trial for a seed (deterministic in it). Throws InputError if the truth
/// cannot be simulated (a bug: the drawn ranges are valid).
using TrialDraw = std::function<SyntheticTrial(uint64_t seed)>;

/// The effect of a trial: one of `kinds`, uniformly (InputError for none to draw from).
records::EffectKind DrawEffectKind(opt::Rng& rng, std::span<const records::EffectKind> kinds);
/// The effects' truth draws (synth/truth_draw.h) on the trial's generator.
TruthDraw TruthDrawOf(opt::Rng& rng);

// The fin bench.

struct FinTrialOptions {
  double quantum_deg = 360.0 / 8192;     ///< encoder quantum [deg], ≥ 0 (0: no quantisation)
  double jitter_rms_deg = 0.003;         ///< vibration jitter before quantisation [deg], ≥ 0
  double none_probability = 0.2;         ///< share of clean benches, in [0, 1]
  double other_form_probability = 0.3;   ///< share of effects drawn in a form the library lacks
  std::vector<model::EffectKind> kinds;  ///< effects to draw from; empty = the whole library
  /// "" or the field, its value and the rule.
  std::string Validate() const;
};

/// Simulates a bench with given plant parameters and effects (the paper's nine cases and split,
/// saturations per case b1 = sat[c].first, b2 = sat[c].second), read through the encoder with the
/// jitter drawn from rng: the cases as a bench folder holds them ("case<N>", a withheld case
/// validates; io::MakeBenchCase). Throws InputError naming the case that cannot be simulated.
io::CaseSet SimulateBench(const model::BimorphPlant& plant, const model::BimorphParams& params,
                          const std::vector<records::Effect>& effects,
                          const std::vector<std::pair<double, double>>& saturations,
                          const FinTrialOptions& options, opt::Rng& rng);

/// The fin bench's trials (one plant, built once): the bench's records (io::RecordsFromCaseSet of
/// SimulateBench). Throws InputError on bad options.
TrialDraw FinTrialDraw(const FinTrialOptions& options);

// Records of a family.

struct RecordsTrialOptions {
  std::string family = "backlash-like";  ///< a family with a CheckNominal set
  double none_probability = 0.25;        ///< share of clean trials, in [0, 1]
};

/// The effects a records trial of `family` draws: every records effect the family does not hold,
/// but those that only records at several rates identify (records/excitation.h NeedsRateCoverage:
/// the trials' sine and triangle drives run at one rate).
std::vector<records::EffectKind> RecordsTrialEffects(const records::Family& family);

/// The families a records trial can draw: those with a nominal set (Family::CheckNominal), in the
/// registry's order.
std::vector<std::string> RecordsTrialFamilies();

/// The records trials of a family: one record (rest, then a drive of 6 s at 500 Hz), its first 60 %
/// after 0.2 s of excitation the training window, the rest withheld. Throws InputError on a family
/// without a nominal parameter set (Family::CheckNominal), naming those with one.
TrialDraw RecordsTrialDraw(const RecordsTrialOptions& options);

// A bench whose truth has a mode (issue 45).

/// Records of a stack whose output rings: the family at its nominal set (Family::CheckNominal) on
/// the synthetic stack's scale, its output through the library's `resonance` (f_n, ζ, share), read
/// with white noise. Each record starts with a rest just after a step to the rest level (the rest
/// rings, as a real stack's first 0.2 s do), then its drive: the training record a slow sine with
/// band-limited noise riding on it (a flat comb of sines between the band's ends, random phases,
/// its RMS given), the withheld one the same shape from another seed, or a compensator's chatter
/// (a triangle with a random telegraph of ±chatter_v switching on one sample in five: broadband).
struct ModeBenchOptions {
  std::string family = "backlash-like";
  double f_n_hz = 740, zeta = 0.03, share = 0.9;
  double fs_hz = 10000;
  double sine_hz = 20, sine_v = 70;  ///< the slow drive (amplitude about the range's middle)
  double band_lo_hz = 50, band_hi_hz = 1500, band_rms_v = 8;  ///< the band-limited noise
  double chatter_v = 4;  ///< the withheld chatter's half step (0: noise instead)
  double rest_s = 0.25, train_s = 1.2, withheld_s = 0.8;
  double noise_std = 0.003;  ///< of the reading
  uint64_t seed = 1;
};
struct ModeBench {
  io::RecordSet set;
  std::vector<double> params, weights;  ///< the truth's (RecordModel(family, {resonance}) order)
  std::string description;
};
/// Throws InputError for a family without a nominal set or a mode outside (0, 0.45 fs).
ModeBench MakeModeBench(const ModeBenchOptions& options);

}  // namespace pz::synth
