// The calibration check of the diagnosis on data whose effect is withheld from it (issues 14, 38;
// `piezoid diagnose-check`): for seeds seed, seed + 1, …, a trial is drawn (synth/synthetic.h,
// one of its forms: the fin bench or records of a family), diagnosed as real data would be
// (diagnose/diagnose.h DiagnoseRecords, with the options of its form) and tallied against its
// truth: how often the right effect is named, the false alarms on clean trials, the calibration of
// the stated confidence (when it says 90 %, is it right 90 % of the time?), the confusion matrix of
// the true effect against the named one ("none" when no significant gap is found, "unexplained"
// when a significant gap is not attributed) and the distribution of the share of the gap closed.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "diagnose/decision.h"
#include "diagnose/diagnose.h"
#include "diagnose/verdict.h"
#include "synth/synthetic.h"

namespace pz::diagnose {
struct DiagnoseOptions;
}

namespace pz::diagnose {

/// A trial: its truth and what the diagnosis said of it (diagnose/verdict.h).
struct CheckTrial : TrialVerdict {
  uint64_t seed = 0;
  model::EffectKind truth;  ///< none: a clean trial
  std::string description;  ///< the truth in words (SyntheticTrial::description)
  double magnitude = 0;     ///< SyntheticTrial::magnitude
  double closed = 0;        ///< share of the withheld gap closed by the named effect(s) (NaN:
                            ///< no excess over the floor)
  double wall_time_s = 0;   ///< draw and diagnosis
  bool correct = false;     ///< named the truth (or "none" on a clean trial)
};

/// How a check's text reads its trials.
struct CheckText {
  std::string noun = "benches";  ///< the trials' noun ("benches", "records")
  int description_width = 70;    ///< a trial line's description, padded
  bool closed_per_trial = true;  ///< a trial line ends with its share closed and wall time
};

/// The tally of a check. The counts and the reliability table are those of every calibration
/// check (diagnose/decision.h).
struct CheckSummary : CalibrationTally {
  CheckText text;
  /// The named results: "none", the effects the trials may hold or the diagnosis name, then
  /// "unexplained". The confusion matrix's rows are these but the last (the truths).
  std::vector<std::string> columns;
  std::vector<std::vector<int>> confusion;  ///< [truth][named]
  std::vector<double> closed;               ///< share closed, over correctly named effects
  std::vector<CheckTrial> trials;
  double wall_time_s = 0;

  CheckSummary() = default;
  /// An empty tally over "none", these effects and "unexplained".
  CheckSummary(CheckText text, const std::vector<model::EffectKind>& effects);
  /// The column (or row) of an effect. Throws std::logic_error for an effect outside the columns
  /// (a form whose effects miss one that its trials draw or its diagnosis names).
  int EffectColumn(const std::string& effect) const;
  /// The column of a result: "unexplained", the named effect, or "none".
  int Column(const std::string& verdict_kind, const std::string& named) const;
  /// Counts a trial (its truth, verdict, confidence and share closed); sets trial.correct.
  void Tally(CheckTrial trial);
};

/// One form of the check: how its trials are drawn and diagnosed.
struct CheckForm {
  CheckText text;
  std::vector<model::EffectKind> effects;  ///< the confusion matrix's (CheckSummary's columns)
  synth::TrialDraw draw;
  /// The options of trial `index`'s diagnosis.
  std::function<RecordDiagnoseOptions(int index)> options;
};

/// The fin bench's check: its trials (FinTrialDraw) diagnosed as `diagnose --cases` diagnoses a
/// bench (diagnose/fin_diagnose.h RecordOptionsOf), trial i with the search seed
/// options.seed + i. Throws InputError on bad options.
CheckForm FinCheckForm(const diagnose::DiagnoseOptions& options,
                       const synth::FinTrialOptions& trials);

struct RecordsCheckOptions {
  synth::RecordsTrialOptions trials;  ///< family and share of clean trials
  RecordDiagnoseOptions diagnose;  ///< the family set, every effect a candidate, no proposal
};

/// The records check of a family: its trials (RecordsTrialDraw) diagnosed by `diagnose --records`.
/// Throws InputError on a family without a nominal set.
CheckForm RecordsCheckForm(const RecordsCheckOptions& options);

/// Runs `trials` trials with seeds seed, seed + 1, …; `on_trial` sees each tallied trial.
CheckSummary RunCheck(const CheckForm& form, int trials, uint64_t seed,
                      const std::function<void(const CheckTrial&, int index)>& on_trial = {});

}  // namespace pz::diagnose
