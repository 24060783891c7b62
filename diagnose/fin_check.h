// The check of the diagnosis on data whose effect is withheld from it: random synthetic benches
// (diagnose/fin_synthetic.h), each diagnosed as a real bench would be, and the confusion matrix of
// the true effect against the named one ("none" when no significant gap is found, "unexplained"
// when a significant gap is not attributed), with the distribution of the share of the gap closed.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "diagnose/fin_diagnose.h"
#include "diagnose/fin_synthetic.h"

namespace pz::diagnose {

/// Rows: true effect (none, then the fin's effects: model::FinIndex); columns: named (the same,
/// then "unexplained").
int CheckRows();
inline int CheckCols() { return CheckRows() + 1; }
inline int UnexplainedColumn() { return CheckRows(); }
/// The effect of a row or column ("unexplained" for the last column).
std::string CheckColumnName(int column);

struct CheckTrial {
  uint64_t seed = 0;
  model::EffectKind truth;        ///< none: a clean bench
  std::string truth_description;  ///< form and parameters
  double magnitude = 0;
  std::string verdict_kind;  ///< "effect", "none", "unexplained"
  model::EffectKind named;   ///< first named effect (none otherwise)
  double confidence = 0;
  bool significant = false;  ///< the diagnosis found a significant gap
  double rms_ratio = 0;      ///< base withheld RMS / floor
  double closed = 0;         ///< share of the withheld gap closed by the named effect(s)
  double wall_time_s = 0;
  bool correct() const;  ///< named the true effect (or "none" on a clean bench)
};

/// The counts (effect_trials: benches with one effect whose gap was significant, effect_right: …
/// where that effect was named, clean, clean_alarms) and the reliability table are those of every
/// calibration check (diagnose/decision.h); the confusion matrix and the shares closed are the
/// bench's.
struct CheckSummary : records::CalibrationTally {
  std::vector<CheckTrial> trials;
  /// [truth][named], CheckRows() × CheckCols().
  std::vector<std::vector<int>> confusion = std::vector<std::vector<int>>(
      static_cast<size_t>(CheckRows()), std::vector<int>(static_cast<size_t>(CheckCols()), 0));
  std::vector<double> closed;  ///< share closed, over correctly named effects
  double wall_time_s = 0;
};

/// Column index of a named result.
int CheckColumn(const CheckTrial& t);

/// Runs `trials` benches with seeds seed, seed + 1, …, each diagnosed by the one driver
/// (DiagnoseBench); `on_trial` sees each finished trial.
CheckSummary RunCheck(int trials, uint64_t seed, const DiagnoseOptions& diagnose,
                      const SyntheticOptions& synthetic,
                      const std::function<void(const CheckTrial&, int index)>& on_trial = {});

/// Adds a trial to the counters of a summary (RunCheck uses it; exposed for tests).
void Tally(CheckSummary& summary, const CheckTrial& trial);

}  // namespace pz::diagnose
