// A record's rows in a linear family's normal equations (issue 22): what its offset mode removes
// from the regressors and the measured output (RecordCentre), and the rows of its scored window
// accumulated into the blocked normal equations (AddRecordRows). Used by the record fitness
// (records/fitness.h) and the creep spectrum's joint solve (records/spectrum_solve.h).
#pragma once

#include <cstddef>
#include <span>
#include <vector>

#include "io/records.h"
#include "records/model.h"
#include "records/regularisation.h"

namespace pz::records {

/// What record r's offset mode removes from the rows of `reg` (rows of samples from.., row-major, m
/// columns; row 0 at rest, before it the rest row): c (m values: the means over the scored window,
/// the rest row, or zeros) and, returned, d from the measured output (its mean over the scored
/// window, or the given offset).
double RecordCentre(const io::Record& r, size_t from, std::span<const double> reg, size_t m,
                    std::vector<double>& c);
/// Adds the scored samples of record r to `builder`: the rows pol · (reg row − c) with target y − d
/// (RecordCentre).
void AddRecordRows(const io::Record& r, size_t from, std::span<const double> reg, size_t m, int pol,
                   NormalEquationsBuilder& builder);

}  // namespace pz::records
