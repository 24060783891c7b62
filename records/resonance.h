// The resonance effect's plumbing in a records fit (model/effect_library.cc `resonance`, issue 45):
// where its start values come from. A mode's f_n is a narrow basin of the cost (a lightly damped
// mode's response is large only within ζ f_n of its frequency), which a global search over two
// decades of f_n seldom lands in; the data say where it is:
//   * the residual: the training records' error of the fitted model with the mode's share at zero
//     (the model without its mode) holds the mode's band — the dominant band of its spectrum
//     (model/effect_library_resonance.h: at least half of its power, standing out from the rest);
//   * else a rest's ringing: the response over a rest that follows a step (the first 0.2 s of a
//     stack's rest ring at its mode), its dominant band with the rest's trend removed.
// FitModel (records/fit.cc) polishes from the fitted model with the mode placed there (share ½ and
// 1) and keeps the better; the diagnosis offers the effect where a record's residual has a
// dominant band (diagnose/diagnose.cc CandidateEffects).
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "io/records.h"
#include "model/effect_library_resonance.h"

namespace pz::records {

/// The spectrum of a record's residual y − ŷ over its scored window (yhat: [0, end_scored), the
/// model's output with polarity and offset).
model::PowerSpectrum ResidualSpectrum(const io::Record& r, std::span<const double> yhat);

/// The lowest frequency where a record's residual band can be a mode's: f_min, and above the first
/// five harmonics of a periodic drive (5.5 × its fundamental, where one spectral line — its bin and
/// two each side, the window's main lobe — holds half of the drive's power over the scored window:
/// a hysteresis model's error on a periodic drive lies at the drive's first harmonics, not in a
/// mode). A drive without such a line (band-limited noise, chatter) adds nothing.
double ModeBandFloor(const io::Record& r, double f_min);
/// The dominant band of record r's residual above ModeBandFloor(r, f_min) (not found: none).
model::SpectralBand ResidualBand(const io::Record& r, std::span<const double> yhat, double f_min,
                                 model::PowerSpectrum* spectrum = nullptr);

/// A mode's start: the band and where it was found.
struct ModeStart {
  model::SpectralBand band;
  std::string source;  ///< "the residual of 'rec'" or "the ringing of the rest of 'rec'"
};
/// The strongest mode-like band (SpectralBand::mode_like: dominant and narrow) among the records'
/// residuals (ResidualBand; yhats: one per record, as ResidualSpectrum takes them; empty: none),
/// else among their rests' ringing above f_min (a rest of 64 samples at least); nothing when none
/// has one.
std::optional<ModeStart> FindModeStart(const std::vector<const io::Record*>& records,
                                       const std::vector<std::vector<double>>& yhats, double f_min);

}  // namespace pz::records
