// The scores of a model against a bench case set (`piezoid pi`; the scoring: client/case_models.h
// ScoreCaseSet): the model's fin angle against the measured one on the same grid, reported as the
// paper's PI per case, the cost CF (Σ PI over the training cases, paper eq. 6), RMSE and max |e|,
// as a text table, in the paper's amplitude × frequency grid, as CSV and as JSON.
#pragma once

#include <ostream>
#include <string>
#include <vector>

#include "io/bench_data.h"
#include "model/metrics.h"
#include "model/simulation.h"

namespace pz::reports {

struct CaseScore {
  int case_number = 0;
  double amplitude_v = 0;   ///< [V]
  double frequency_hz = 0;  ///< [Hz]
  io::CaseRole role = io::CaseRole::kTrain;
  double b1 = 0, b2 = 0;  ///< saturations used [deg]
  std::string saturation_source;
  model::SimulationSummary summary;  ///< of the simulation
  bool scored = false;               ///< false if the simulation failed (metrics unset)
  model::ErrorMetrics metrics;       ///< angle [deg]: pi [deg²], rmse, max_abs [deg]
};

struct PiReport {
  std::string case_set;         ///< the folder scored
  std::string solver;           ///< "modal" / "cvode"
  std::string saturation_mode;  ///< the --saturation policy
  std::vector<CaseScore> cases;
  double cf_train = 0;      ///< Σ PI over the scored training cases [deg²] (the paper's CF)
  double sum_validate = 0;  ///< Σ PI over the scored validation cases [deg²]
  double sum_test = 0;      ///< Σ PI over the scored test cases [deg²]
  int failed = 0;           ///< cases whose simulation failed (they are not in the sums)
};

/// Per-case table, the amplitude × frequency grid of PI, and the sums.
void PrintPiReport(std::ostream& out, const PiReport& report);
/// CSV, one row per case under the header case, amplitude_V, frequency_Hz, role, b1_deg, b2_deg,
/// saturation, status, pi_deg2, rmse_deg, max_abs_error_deg, r2 (commas without spaces; the
/// metrics empty where the simulation failed).
void WritePiCsv(std::ostream& out, const PiReport& report);
/// JSON object with the settings, one object per case and the sums: proto::PiScores
/// (proto/pi.proto) printed by io/proto_json.h (keys sorted, non-finite numbers as null).
void WritePiJson(std::ostream& out, const PiReport& report);

}  // namespace pz::reports
