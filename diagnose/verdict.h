// The verdict sentence of a diagnosis, composed once for every data shape: the records diagnosis
// (diagnose/diagnose.h) and the nine-case bench diagnosis (diagnose/fin_diagnose.h, its rounds and
// its summary) state what the rules of diagnose/decision.h decided in the same words, from the gap,
// the ranked candidates and the naming; each supplies only its unit, where its floor comes from and
// what it alone knows (the next measurement, the parameters that absorb an effect, a second
// effect).
//
//   none         "No significant gap: the withheld RMS error of M is r × the noise floor (σ u, from
//                 S), at most R." [+ the best candidate, when it scores above 0, and what absorbs
//                 it]
//   unexplained  "A significant gap (withheld RMS e u = r × the noise floor of σ u, from S) that no
//                 candidate explains by the rules." [+ the best candidate and why it does not
//                 qualify]
//   effect       "The gap is A (confidence c %)[, with a second effect: B (confidence d %)]: adding
//                 it closes x % of the excess withheld gap; withheld RMS e → e' u against a noise
//                 floor of σ u (S)."
//   inseparable  "The data cannot separate A from B: both bring the withheld gap to the noise floor
//                 (…) and the paired block test does not separate them (z = … < Z); confidence in A
//                 c %." [+ "A second effect on top of A: …"] [+ "Next measurement: …."]
// followed by the protocol's closing sentence (the excitation-gap note of records), if any.
// Numbers: three significant digits; thresholds as given.
//
// The calibration checks speak once too: a trial's line and the tally (CalibrationTally of
// diagnose/decision.h) of every `diagnose-check`.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "diagnose/decision.h"

namespace pz::diagnose {

/// A ranked candidate as the verdict names it.
struct VerdictCandidate {
  std::string name;  ///< the effect's name
  const CandidateScore* score = nullptr;
};

/// What only the protocol knows.
struct VerdictText {
  std::string
      model;  ///< the starting model, as the sentence names it ("backlash-like", "the base model")
  std::string unit;  ///< of the response ("deg", "µm")
  std::string
      floor_source;   ///< where the floor comes from ("rest", "rounding and scatter per case")
  double floor = -1;  ///< σ as the protocol states it (< 0: √(S_floor / N_w))
  std::string next;   ///< inseparable: what would separate the two ("": nothing said)
  std::vector<std::string> absorbed;  ///< no gap: base parameters that absorb the best candidate
                                      ///< ("α (1 without it, 2 with it)")
  std::string second;                 ///< a second effect named on top of the first ("": none)
  double second_confidence = 0;
  double s_final =
      -1;  ///< withheld Σe² of the model with every named effect (< 0: the named one's)
  std::string closing;  ///< a last sentence ("": none)
};

/// The verdict of a gap, its ranked candidates (best first, as NameEffect saw them) and their
/// naming.
std::string ComposeVerdict(const Gap& gap, std::span<const VerdictCandidate> ranked,
                           const Naming& naming, const DecisionRules& rules,
                           const VerdictText& text);

// ---- the calibration checks (`diagnose-check`: benches, records, real-like record sets)
// -----------

/// What a diagnosis said on one trial of a check.
struct TrialVerdict {
  std::string verdict_kind;    ///< "effect", "inseparable", "none", "unexplained"
  std::string named = "none";  ///< the (first) named effect
  double confidence = 0;       ///< stated for the named effect
  double rms_ratio = 0;        ///< the starting model's withheld RMS / floor
  bool significant = false;    ///< the gap was significant
};

/// One trial of a check as a line: "trial   3 right  DESCRIPTION -> effect      delay
/// ratio   2.31 conf 0.99EXTRA". `mark`: "right" / "WRONG", or "" for a check without one truth;
/// the description padded to `width`; `after_named` right after the named effect.
std::string TrialLine(int index, const std::string& mark, const std::string& description, int width,
                      const TrialVerdict& verdict, const std::string& after_named = "",
                      const std::string& extra = "");

/// The counts and the reliability table of a check, one line each; `noun` names the trials
/// ("benches", "records").
std::string TallyText(const CalibrationTally& tally, const std::string& noun);

/// The confusion matrix of a check, a line a row: its title (`trials` `noun`), the named results
/// (`columns`, cut to 11 characters), then each truth (`columns` but the last) with its counts.
std::string ConfusionText(std::span<const std::string> columns,
                          const std::vector<std::vector<int>>& confusion, size_t trials,
                          const std::string& noun);

/// The distribution of the share of the gap closed where the right effect was named: min, 10 %,
/// median, 90 %, max (linear between order statistics; "n/a" without any), one line.
std::string ClosedText(std::vector<double> closed, const std::string& noun);

}  // namespace pz::diagnose
