// One case of a bimorph-fin bench, ready to simulate and score: what the HGANN fitness
// (hgann/hgann_fitness.h) works on (the diagnosis reads records: io/fin_records.h). The same
// case exists as a file record (io/bench_data.h BenchCase: t, u, angle as read) and in a job spec
// (job/job_spec.h HgannCaseSpec: what travels on the wire); both become this form through
// MakeFinCase (a BenchCase through io::MakeFinCase), the one builder.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "model/saturation.h"
#include "model/signal.h"

namespace pz::model {

struct FinCase {
  int number = 0;                    ///< case number (> 0)
  Sinusoid drive;                    ///< V sin(2π f t) on the record's grid
  std::vector<double> measured_deg;  ///< y_meas,k [deg], drive.NumSamples() values, finite
  double b1 = 1.0;       ///< saturation [deg], > 0 (from the measured extremes, or given)
  double b2 = -1.0;      ///< saturation [deg], < 0
  bool training = true;  ///< fitted (counted in the cost); else withheld
};

/// The one builder of a fin case: the measured angle on the drive's grid (as many samples as
/// drive.NumSamples()) and the saturations — `given`, or the one rule, b1 and b2 from the
/// measured extremes (SaturationFromExtremes). Throws InputError naming `where` (empty: "case
/// <number>").
FinCase MakeFinCase(int number, const Sinusoid& drive, std::vector<double> measured_deg,
                    bool training, const std::optional<SaturationPair>& given = std::nullopt,
                    const std::string& where = "");

}  // namespace pz::model
