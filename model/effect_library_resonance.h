// The resonance effect's spectral arithmetic (model/effect_library.cc `resonance`, issue 45): where
// a residual or a rest holds a mode. One power spectrum (Welch: Hann-windowed segments, half
// overlapping, each mean-removed), one rule for a dominant band, and the mode it suggests — the
// start values of a fit with `resonance` (records/fit.cc), the diagnosis's reason to try the
// effect (diagnose/diagnose.cc), and the spectrum the records report draws (client/).
//
// A band is the neighbourhood [0.6, 1.4] × f_peak of the highest bin above f_min (440–1040 Hz
// around a mode at 740 Hz); it is dominant when it holds at least half of the power of every bin
// but DC and its power per bin is at least 4 × that outside it (white noise spreads its power
// evenly: a wide band near Nyquist holds half of it without standing out). Its mode: f_n at the
// peak (a parabola through the log powers of the three bins about it), ζ from the half-power width
// Δf = 2 ζ f_n (at least half a bin's worth, at most 0.5): what a lightly damped mode's |H|² looks
// like in the spectrum of a broadband drive's response.
//
// Pure: no I/O.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace pz::model {

/// A one-sided power spectrum: p[i] the power in the bin at f[i] = i df (Σ p = the signal's mean
/// square, DC included, as Parseval has it for the window's power).
struct PowerSpectrum {
  double df = 0;
  std::vector<double> f, p;
};
/// Welch's estimate of x sampled at fs: segments of the largest power of two ≤ min(n, max_segment)
/// (at least 16 samples: fewer give an empty spectrum), Hann-windowed, half overlapping.
PowerSpectrum WelchSpectrum(std::span<const double> x, double fs, size_t max_segment = 4096);

/// The dominant band of a spectrum above f_min (found: a peak was there at all).
struct SpectralBand {
  bool found = false;
  double f_peak = 0;          ///< [Hz] the peak, interpolated
  double f_lo = 0, f_hi = 0;  ///< [Hz] the band: 0.6 and 1.4 × f_peak
  double share = 0;           ///< of the power of every bin but DC
  double contrast = 0;        ///< power per bin in the band over that outside it
  double zeta = 0;            ///< the half-power width's damping, in [df / 2 f_peak, 0.5]
  bool dominant() const {
    return found && share >= kDominantShare && contrast >= kDominantContrast;
  }
  /// A dominant band as narrow as a lightly damped mode's (ζ from its width under kModeZeta): what
  /// a structure's mode leaves; a wider one is a spread of the drive's harmonics or a lag the
  /// model lacks (on the 150 V / 1 Hz actuator record: 4–10 Hz, ζ 0.5).
  bool mode_like() const { return dominant() && zeta < kModeZeta; }
  static constexpr double kDominantShare = 0.5, kDominantContrast = 4, kModeZeta = 0.3;
};
SpectralBand DominantBand(const PowerSpectrum& s, double f_min);

/// Powers summed into the band [lo, hi] of a spectrum (for a report's figures).
double BandPower(const PowerSpectrum& s, double lo, double hi);

/// The ringing of a rest that follows a step: the dominant band of the rest's samples (each
/// record's, at fs) above f_min, with a linear trend removed (the rest's settling and creep).
/// Not found: the rest is too short (under 64 samples) or holds no peak.
SpectralBand RingingBand(std::span<const double> rest, double fs, double f_min);

}  // namespace pz::model
