// The normal equations of the Preisach grid's cell regressors without the regressors (issue 37):
// what AddRecordRows adds for model::PreisachRegressors' rows, in O(n²) per sample instead of
// O(m²) (n levels, m = n(n+1)/2 cells: 820 at 40 levels).
//
// On a sample, width i's play p_i sits at level L_i = (p_i − u_min − r_i)/Δ of its n − i cells,
// clamped to [0, n − i]: with J = ⌊L_i⌋ and f = L_i − J its cells read (without their constants
// k_i)
//
//   v_ij = Δ (1[j < J] + f 1[j = J])                                           (a step, one partial
//   cell)
//
// so a block of Σ v vᵀ between widths i and i' is Δ² times
//
//   #{J > j, J' > j'} + Σ_{J > j, J' = j'} f' + Σ_{J = j, J' > j'} f + Σ_{J = j, J' = j'} f f'
//
// — suffix sums of four histograms over (J_i, J_i') filled with 1, f', f, f f' (four additions per
// pair of widths and sample), turned into the block once per record and validation block. Σ v and
// Σ v t (t the target) come the same way from histograms per width. The rows' centre (the record's
// offset mode: the mean row, the rest row or none; io::OffsetMode) and the constants k_i enter
// as the rank-2 correction Σ (v − c)(v − c)ᵀ = Σ v vᵀ − (Σ v) cᵀ − c (Σ v)ᵀ + N c cᵀ. The result
// equals the dense rows' normal equations to rounding (tests/records/preisach_test.cc).
#pragma once

#include <span>

#include "io/records.h"
#include "model/preisach.h"
#include "records/regularisation.h"

namespace pz::records {

/// Adds record r's scored samples to `builder` as AddRecordRows(r, from, PreisachRegressors(grid,
/// u, start), m, pol, builder) would: u is the drive of rows from `from` (records/model.h
/// RegressorRow), `start` resolved. False (nothing added) when the drive is not finite: the dense
/// path then makes what it makes of it.
bool AddPreisachRecordRows(const model::PreisachGrid& grid, model::InitialState start,
                           const io::Record& r, size_t from, std::span<const double> u, int pol,
                           NormalEquationsBuilder& builder);

}  // namespace pz::records
