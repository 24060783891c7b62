// The quantum of a quantised series: the grid its readings lie on (an encoder's step, a recorder's
// least significant digit). The record reader measures it for every record (io/records.h
// Record::quantum), and the noise floor takes its rounding q/√12 as the least error a continuous
// model has on a moving signal (records/noise_floor.h, which holds every estimator of the floor;
// this piece lives here because io/, its lowest user, cannot include records/). Pure: no I/O.
#pragma once

#include <span>

namespace pz::io {

/// The quantum of a quantised series: the largest q such that every value is an integer multiple
/// of q (to 1e-6 q), found from the smallest step between distinct values and its integer divisors
/// (1 … 16). A recorder that prints a few decimals rounds its grid (0.0076294 µm steps written as
/// -1.6174316): when no exact grid fits, q is refined by least squares over the values taken in
/// order of magnitude and accepted when every value is within 1e-3 q of a multiple of it. 0 when
/// the series is not on a grid (continuous data) or has fewer than 2 distinct values.
double EstimateQuantum(std::span<const double> y);

}  // namespace pz::io
