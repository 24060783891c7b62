// The decision of a diagnosis (docs/diagnosis.md section 4): the rules that turn a starting
// model's gap and its candidates' fits into a ranking and a verdict. They exist once and are the
// same for every effect, every family and every data shape: the records diagnosis
// (diagnose/diagnose.h) and the nine-case bench diagnosis (diagnose/fin_diagnose.h) call them, each
// supplying what only its data shape knows (the floor, the localised excess, the squared errors).
//
//   significant gap  ⇔  √(S0 / S_floor) > significance_ratio
//   score            =  (S0 − S_c)/σ²_w − k ln N_w            (held-out χ² gain − BIC penalty)
//   train ΔBIC       =  (T_c − T0)/σ²_t + k ln N_t            (< 0: better on the training data
//   too) closed           =  (S0 − S_c)/(S0 − S_floor)             (share of the excess gap;
//   undefined
//                                                              without an excess)
//   pattern          =  share of the localised excess removed (PatternExplained)
//   qualifies        ⇔  significant, score > 0, ΔBIC < 0, closed ≥ min_closed, pattern ≥
//   min_pattern ranking          :  by score, best first (stable); posterior weights against "none"
//   named            ⇔  the best-ranked candidate qualifies; its confidence is Π Φ(z) of paired
//                       block tests of the withheld squared errors against the starting model and
//                       every other qualifying candidate, tied or not (Φ(z): the probability that
//                       the named one is the better of the two; a tie at z = 0 states ½); a
//                       qualifying rival is practically equivalent (cannot be separated: verdict
//                       "inseparable") only when both bring the withheld gap within the
//                       significance threshold of the floor (√(S_c / S_floor) ≤ significance_ratio)
//                       and the paired test does not separate them (z < separation_z).
//   verdict kind     :  "none" (no significant gap), "unexplained" (significant, nothing named),
//                       "effect", "inseparable" (named with a rival it cannot be separated from).
#pragma once

#include <algorithm>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "model/model_comparison.h"
#include "model/status.h"

namespace pz::diagnose {

/// The thresholds of the rules: the same for every effect.
struct DecisionRules {
  double significance_ratio = 1.25;  ///< withheld RMS / floor above which a gap is significant, > 1
  double min_closed = 0.5;    ///< share of the excess gap a named effect must close, in (0, 1]
  double min_pattern = 0.5;   ///< share of the localised excess it must remove, in [0, 1]
  double separation_z = 2.0;  ///< a qualifying rival within this paired z, both at the floor:
                              ///< cannot separate
  int blocks = 20;            ///< of the paired block tests, ≥ 4
  Status Validate() const;
};

/// The gap of a starting model over the withheld and the training data, against the floor.
struct Gap {
  double s0 = 0, t0 = 0;        ///< withheld / training Σe² of the starting model
  double s_floor = 0;           ///< withheld floor Σ N σ²
  double nw = 0, nt = 0;        ///< withheld / training samples
  double var_w = 0, var_t = 0;  ///< floor variance per sample σ²_w, σ²_t
  double rms_ratio = 0;         ///< √(s0 / s_floor)
  bool significant = false;
};
/// The gap from the starting model's Σe² (withheld s0, training t0), the withheld floor Σ N σ²
/// and the per-sample floor variances of both parts.
Gap MeasureGap(double s0, double t0, double s_floor, double var_w, double var_t, double nw,
               double nt, const DecisionRules& rules);

/// The share of the excess gap closed: (s0 − s_c)/(s0 − s_floor); NaN when s0 ≤ s_floor (no
/// excess).
double ClosedShare(double s0, double s_c, double s_floor);

/// What the rules say of one candidate. Protocols' candidate types derive from it.
struct CandidateScore {
  double s_withheld = 0, s_train = 0;  ///< Σe² of the candidate on the withheld / training data
  double score = 0;                    ///< held-out χ² gain − penalty
  double train_delta_bic = 0;  ///< (T_c − T_0)/σ²_t + k ln N_t (< 0: better on training too)
  double closed = 0;           ///< share of the excess withheld gap closed (NaN without an excess)
  double raw_reduction = 0;    ///< (S0 − S_c)/S0
  double pattern = 0;          ///< share of the localised excess removed
  double weight = 0;           ///< posterior weight exp(score/2φ) against the others and "none"
  double confidence = 0;       ///< if named: Π Φ(z) of the paired block tests
  bool qualifies = false;      ///< passes every rule but the ranking
  std::string note;            ///< why it does not qualify
};

/// Scores a fitted candidate with `added_params` parameters more than the starting model and the
/// given pattern share.
void ScoreCandidate(const Gap& gap, double s_withheld, double s_train, int added_params,
                    double pattern, const DecisionRules& rules, CandidateScore& c);
/// A candidate whose fit failed: ranked last, never named.
void FailCandidate(const std::string& message, CandidateScore& c);

/// Share of the localised excess removed: features (bins) are the protocol's (phase bins and
/// spectral groups of a bench, drive level × direction bins of records); only features that
/// carried excess before count, and a feature's excess after is capped at 10 × before:
/// 1 − Σ min(after, 10 before) / Σ before (≤ 1; negative when the excess grows elsewhere).
double PatternExplained(std::span<const double> before, std::span<const double> after);

/// Ranks candidates by score, best first (stable).
template <class Candidate>
void RankByScore(std::vector<Candidate>& candidates) {
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
}

/// The ranked candidates' scores, as the rules see them.
template <class Candidate>
std::vector<CandidateScore*> Scores(std::vector<Candidate>& candidates) {
  std::vector<CandidateScore*> out;
  for (Candidate& c : candidates) out.push_back(&c);
  return out;
}

/// Posterior weights against "none" (score 0), tempered by the best model's over-dispersion.
void AssignWeights(const Gap& gap, std::span<CandidateScore* const> ranked);

/// Whether a candidate brings the withheld gap within the significance threshold of the floor.
bool AtFloor(const Gap& gap, const CandidateScore& c, const DecisionRules& rules);

/// The named effect of a ranked list and what it cannot be separated from.
struct Naming {
  int named = -1;          ///< index into the ranked candidates, −1 if none
  int runner_up = -1;      ///< a qualifying candidate the data cannot separate from the named one
  double z_runner_up = 0;  ///< its paired block z against the named one
  double confidence = 0;   ///< of the named one (also written into its CandidateScore)
};
/// Squared withheld errors of the starting model (index −1) or of the ranked candidate i, in the
/// same sample order for every model.
using SquaredErrors = std::function<std::vector<double>(int)>;
Naming NameEffect(const Gap& gap, std::span<CandidateScore* const> ranked,
                  const SquaredErrors& squares, const DecisionRules& rules);

/// "none" (no significant gap), "unexplained" (nothing named), "effect" or "inseparable".
std::string VerdictKind(bool significant, const Naming& naming);

/// The tally of a calibration check (`diagnose-check`, benches or records) over trials whose truth
/// is known: the same counts and reliability table for every data shape.
struct CalibrationTally {
  int effect_trials = 0;           ///< trials with an effect whose gap was significant
  int effect_right = 0;            ///< … where that effect was named
  int clean = 0;                   ///< trials without an effect
  int clean_alarms = 0;            ///< … where something was named or called unexplained
  int inseparable = 0;             ///< verdicts "inseparable"
  std::vector<double> confidence;  ///< stated confidence, over trials with a named effect
  std::vector<char> right;         ///< … 1 when the named effect was the truth
  /// Counts one trial (`named_is_truth`: an effect was named and it is the truth); returns whether
  /// the verdict is right: the truth named, or "none" on a clean trial.
  bool Add(bool clean_truth, bool significant, const std::string& verdict_kind, bool named_is_truth,
           double stated_confidence);
  double accuracy() const { return effect_trials ? double(effect_right) / effect_trials : 0; }
  double false_alarm_rate() const { return clean ? double(clean_alarms) / clean : 0; }
  /// Is a stated confidence of 90 % right 90 % of the time (model/model_comparison.h)?
  std::vector<model::ReliabilityBin> Reliability() const;
};

}  // namespace pz::diagnose
