// The residual spectrum of a records report (issue 45): where a record's residual under the base
// model has a dominant band (model/effect_library_resonance.h: half of its power or more, standing
// out from the rest — a mode, a chatter the model cannot follow), report.md says so per record,
// with the band, its share and, when the named model holds `resonance`, its fitted f_n and ζ and
// the share of the band it closed; the figures draw each such record's residual spectrum before
// and after, the mode marked. Nothing is written for a set whose residuals hold no band.
#pragma once

#include <filesystem>
#include <iosfwd>
#include <vector>

#include "io/records.h"
#include "records/fit.h"

namespace pz::reports {

/// The "## Residual spectrum" section (nothing without a dominant band). `after`: the named model's
/// fit, or null.
void WriteResidualSpectrumMarkdown(std::ostream& os, const io::RecordSet& set,
                                   const records::FitResult& base, const records::FitResult* after);

/// A fit holding `resonance`: its fitted mode and where its start came from, as a paragraph
/// (nothing for a fit without it); a mode among a periodic training drive's first harmonics
/// (records::ModeBandFloor) is said to act as a linear dynamics of the output, not a structure's.
void WriteFittedModeMarkdown(std::ostream& os, const io::RecordSet& set,
                             const records::FitResult& fit);

/// figures/residual_spectrum_<record>.csv (f_hz, base, after) and .gp for each record with a band,
/// and the mode's marker (residual_mode_<record>.csv); the scripts' paths appended to `scripts`.
void WriteResidualSpectrumFigures(const std::filesystem::path& dir, const io::RecordSet& set,
                                  const records::FitResult& base, const records::FitResult* after,
                                  std::vector<std::filesystem::path>& scripts);

}  // namespace pz::reports
