// The V × f trends of a grid of sinusoidal records (the nine-case bench's, or any record set whose
// records state their frequency): each record is fitted alone, from a fit on the whole set, and
// each parameter's per-record estimates are regressed over the grid (OLS on amplitude and
// frequency with t statistics, model/saturation.h FitPlane). A parameter that follows the operating
// point where the model holds it constant is evidence of an unmodelled effect (docs/diagnosis.md).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "io/records.h"
#include "records/fit.h"

namespace pz::diagnose {

/// A parameter trend over the V × f grid from the per-record (per-case) fits.
struct ParamTrend {
  std::string name, unit;
  std::vector<double> per_case;     ///< value per record / case (set order)
  double slope_v = 0, slope_f = 0;  ///< per drive unit, per Hz
  double p_v = 1, p_f = 1;          ///< two-sided p-values
  double r2 = 0;
  double relative_range = 0;  ///< (max − min)/|mean|
  bool significant = false;   ///< p < 0.01 on V or f and relative range > 10 %
};

/// The trend of one parameter's per-case values over the cases' amplitudes and frequencies (the
/// same length): no trend (p = 1) when the plane cannot be fitted (collinear or too few cases).
ParamTrend TrendOver(std::string name, std::string unit, std::vector<double> per_case,
                     const std::vector<double>& amplitude, const std::vector<double>& frequency_hz);

/// The amplitude of a record's drive: its stated sinusoid's (a fin bench case, io/fin_records.h),
/// else (max u − min u)/2 over its scored window.
double DriveAmplitude(const io::Record& record);

/// The grid add-on: every record of `set` fitted alone (no global search: a Levenberg–Marquardt
/// polish of `iterations` from `from`'s parameters, on that record as its only training record),
/// and each of `from`'s parameters regressed over the records' drive amplitude and stated
/// frequency. Throws InputError naming the record when one states no frequency (a manifest's
/// frequency_Hz column; a bench's is stated), or when fewer than 4 records are given.
/// `evaluations` (optional): the per-record fits' model evaluations are added to it.
std::vector<ParamTrend> RecordTrends(const io::RecordSet& set, const records::FitResult& from,
                                     const records::FitOptions& options, int iterations = 25,
                                     int64_t* evaluations = nullptr);

}  // namespace pz::diagnose
