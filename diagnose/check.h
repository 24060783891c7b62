// The check of the records diagnosis on data whose effect is withheld from it (issue 14): random
// synthetic records of a family (parameters drawn around a nominal set, a random drive — a sine
// from an arbitrary phase after a rest, a multisine or a triangle — noise and quantisation) with
// one effect of the library at a random magnitude, or none; each diagnosed as a real record would
// be. Reports how often the right effect is named, the false alarms on clean records, and the
// calibration of the stated confidence (when it says 90 %, is it right 90 % of the time?).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "diagnose/decision.h"
#include "diagnose/diagnose.h"

namespace pz::records {

struct RecordsCheckOptions {
  std::string family =
      "backlash-like";  ///< stack-bouc-wen, backlash-like, duhem, prandtl-ishlinskii
  int trials = 40;
  uint64_t seed = 1;
  double none_probability = 0.25;
  RecordDiagnoseOptions diagnose;  ///< family and candidates are set per trial
};

/// A trial: its truth and what the diagnosis said of it (diagnose/verdict.h).
struct RecordsCheckTrial : TrialVerdict {
  uint64_t seed = 0;
  std::string truth = "none";  ///< effect name or "none"
  std::string description;     ///< effect, magnitude, drive
  bool correct = false;        ///< named the truth (or "none" on a clean record)
};

/// The counts and the reliability table are those of every calibration check (diagnose/decision.h).
struct RecordsCheckSummary : CalibrationTally {
  std::vector<RecordsCheckTrial> trials;
  double wall_time_s = 0;
};

/// Runs the trials (seeds seed, seed + 1, …). Throws InputError on a family without a nominal set.
RecordsCheckSummary RunRecordsCheck(
    const RecordsCheckOptions& options,
    const std::function<void(const RecordsCheckTrial&, int)>& on_trial = {});

}  // namespace pz::records
