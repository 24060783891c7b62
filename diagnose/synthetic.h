// Synthetic records from the project's own plants (issue 14), in the shape of real recordings: a
// rest segment, a drive that starts at an arbitrary phase (a sine, a multisine, a triangle, a
// square wave with finite slew, a sweep), a response offset, white noise and quantisation. Tests
// and `piezoid diagnose-check` identify and diagnose these, so every figure can be checked against
// the truth that made them.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "io/records.h"
#include "opt/random.h"
#include "records/model.h"

namespace pz::records {

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

struct Measurement {
  double offset = 0;     ///< added to the response
  double noise_std = 0;  ///< white Gaussian noise
  double quantum = 0;    ///< response rounded to multiples of it (0 = none)
  uint64_t seed = 1;
};

/// The data scale of the project's synthetic stack records (±100 V drive, ±10 µm response, gain
/// 0.1 µm/V, 1 Hz, 500 Hz sampling, 4 s): the truth models of tests and diagnose-check use it.
DataScale SyntheticStackScale();

/// A standard normal draw (Box–Muller on the generator's uniform grid).
double NormalDraw(opt::Rng& rng);
/// A uniform draw in [lo, hi) (one Uniform01): the synthetic draws of every check (records, fin
/// benches, real-like stacks).
inline double UniformDraw(opt::Rng& rng, double lo, double hi) {
  return lo + (hi - lo) * rng.Uniform01();
}

/// A record of the truth model (polarity +1) on the drive: y = round_q(ŷ + offset + noise).
/// Window: the whole excitation (or [t0, t1] when t1 > t0); offset mode fit.
io::Record SynthesizeRecord(const RecordModel& truth, std::span<const double> params,
                            std::span<const double> weights, const DriveShape& shape,
                            const Measurement& measurement, const std::string& name,
                            model::CaseRole role, double t0_s = 0, double t1_s = 0);

}  // namespace pz::records
