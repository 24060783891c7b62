// An independent check plant for the `preisach` family (issue 37), never tuned on: a classical
// Preisach model of discrete relays, written here from its definition and sharing nothing with
// model/preisach.h (no plays, no cells) or synth/reallike.h (no Everett table, no log creep).
//
//  - Drive nonlinearity: the relays and the reversible part see u_q = u + q (u − u_lo)² / (u_hi −
//  u_lo)
//    (monotone on the range for q > −½: a quadratic drive).
//  - Hysteresis: K × K relays R_{α,β}, α_a = q_lo + (a + ½) h ≥ β_b = q_lo + (b + ½) h over the
//  range
//    of u_q (h = range / K), on when u_q ≥ α, off when u_q ≤ β, else unchanged; all off at the rest
//    at u_lo (negative saturation). Weights: a density falling with the width (α − β) and skewed
//    with the centre, exp(−(α − β)/(width · range)) · exp(skew · c'), c' ∈ [−½, ½] the centre's
//    place in the range; the relays carry `hysteresis_share` of the stroke. Plus a reversible part
//    linear in u_q: the rest of the stroke.
//  - Creep: three relaxations of the output, y_c = y + Σ_j g_j x_j, τ_j ẋ_j = (y − y_rest) − x_j,
//    discretised exactly on the samples (x_j follows y's change since the rest).
//  - Sensor: the reading of sample k is the plant's output at k − lag (whole samples), plus white
//    Gaussian noise and a constant offset per record.
//
// Records at `fs_hz`, each a rest at u_lo then its excitation: training ("rich"): a sine whose
// amplitude decays over the range and whose centre wanders (nested minor loops at every level), a
// random reversal sequence and a staircase with holds; withheld, inside that excitation: nested
// minor loops (a ramped sine at another rate and phase) and random reversals with holds (another
// seed). The noise floor of each record is its realised noise RMS over its scored window.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "io/records.h"

namespace pz::synth {

struct RelayPreisachCheckOptions {
  int relay_levels =
      160;  ///< K: relays per axis, K (K + 1)/2 relays (their staircase well under the noise)
  double u_lo = 0, u_hi = 120;  ///< drive range [V]
  double quadratic = 0.25;      ///< q of the drive nonlinearity
  double stroke_um =
      30;  ///< output over the range on the rising branch from the rest (approximately)
  double hysteresis_share = 0.3;  ///< of the stroke, carried by the relays
  double width = 0.35;            ///< the density's decay width, share of the range
  double skew = 1.5;              ///< the density's skew with the centre
  std::array<double, 3> creep_tau_s = {0.3, 3, 25};
  std::array<double, 3> creep_gain = {0.01, 0.012,
                                      0.015};  ///< share of the output change per relaxation
  int lag_samples = 1;
  double noise_um = 0.04;
  double offset_range_um = 2;  ///< each record's offset is uniform in ± this
  double fs_hz = 100;
  double rest_s = 2;
  double train_s = 120;    ///< the training excitation (after its rest)
  double withheld_s = 40;  ///< each withheld record's excitation
  uint64_t seed = 1;
  std::string Validate() const;  ///< "" or the field, its value and the rule
};

struct RelayPreisachCheckSet {
  io::RecordSet set;                 ///< "rich" (train), "nested" and "reversals" (validate)
  std::vector<double> noise_rms_um;  ///< per record: the realised noise RMS over the scored window
};

/// The plant's noise-free readings (lag applied, no offset) for a drive from the rest at u_lo.
std::vector<double> RelayPreisachCheckResponse(const RelayPreisachCheckOptions& o,
                                               const std::vector<double>& u);

/// Generates the set (deterministic in the seed). Throws InputError on bad options.
RelayPreisachCheckSet GenerateRelayPreisachCheck(const RelayPreisachCheckOptions& o);

}  // namespace pz::synth
