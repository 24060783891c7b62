// The diagnosis of the sim-to-real gap on record sets of any drive, for every family (issue 14):
// the rules of diagnose/fin_diagnose.h (docs/diagnosis.md) on records instead of the nine-case
// grid.
//
//  1. Noise floor σ from what the records allow (records/noise_floor.h EstimateNoiseFloor: rest,
//     periods, repeats, the base model's residual; every available estimate is reported, and which
//     one was used; none below the quantisation floor q/√12).
//  2. The base family is fitted on the training records; each applicable effect (Family::
//     excluded_effects leaves out what the family already holds) is added and the model re-fitted
//     (global search + LM, with the base fit as extra starting points).
//  3. Withheld = the records with role validate or test (records or time windows). S = Σe² there,
//     S_floor = N_w σ². The decision is that of diagnose/decision.h (the same rules as the bench
//     diagnosis): significance, score, training ΔBIC, closed share, pattern (here the localised
//     excess over drive level × direction bins of the withheld samples), the best-ranked candidate
//     named if it qualifies.
//  4. Confidence, made honest: residuals are correlated in time, so two models are compared by a
//     paired test on blocks of the withheld samples (diagnose/decision.h,
//     model/model_comparison.h); when the runner-up qualifies too and cannot be separated, the
//     verdict is "cannot separate A from B", the confidence is shared among the candidates that
//     cannot be separated, and the next measurement is proposed: among sines, triangles and
//     square waves at 0.25 … 8× the training frequency and 0.5 or 1× its amplitude, the one where
//     the two fitted models' predictions differ most (RMS, offsets removed), with that difference
//     against σ.
//  5. Excitation (records/excitation.h), before any fit: what the training records excite and what
//     each withheld record needs beyond it; when the withheld records that need more carry the
//     gap, the verdict says it is an excitation gap rather than missing physics.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "io/records.h"
#include "diagnose/decision.h"
#include "records/excitation.h"
#include "records/fit.h"
#include "records/noise_floor.h"
#include "diagnose/synthetic.h"
#include "diagnose/verdict.h"

namespace pz::records {

struct ProposedExperiment {
  DriveShape shape;
  double rms_difference = 0;  ///< between the two models' predictions [response unit]
  double ratio_to_noise = 0;  ///< rms_difference / σ
  std::string description;
};

/// One effect added to the base family, fitted and scored by the rules of diagnose/decision.h.
struct RecordCandidate : CandidateScore {
  EffectKind kind;
  FitResult fit;
  double z_vs_base = 0;  ///< paired block test against the base model (> 0: better)
};

struct RecordDiagnoseOptions {
  std::string family = "backlash-like";
  std::vector<EffectKind> candidates;  ///< empty = every effect that applies to the family
  FitOptions fit;                      ///< family options, search and polish of every fit
  DecisionRules rules;                 ///< the decision rules: the same for every effect
  bool propose = true;
};

struct RecordDiagnosis {
  NoiseFloor noise;
  FitResult base;
  size_t withheld_samples = 0, train_samples = 0;
  double s0 = 0, s_floor = 0, rms_ratio = 0;
  bool significant = false;
  std::vector<RecordCandidate> candidates;  ///< ranked by score, best first
  int named = -1;                           ///< index into candidates
  int runner_up = -1;  ///< a qualifying candidate that cannot be separated, or −1
  double z_runner_up = 0;
  double confidence = 0;
  std::string verdict_kind;  ///< "effect", "inseparable", "none", "unexplained"
  std::string verdict;
  std::optional<ProposedExperiment> next;
  ExcitationReport excitation;  ///< what training excites, what each withheld record needs
                                ///< (records/excitation.h)
  std::string excitation_note;  ///< the excitation-gap sentence, also at the end of the verdict
                                ///< (empty: none)
  /// Candidates left out because their fitted model's prediction is not finite on a withheld
  /// record (it diverges there: no score to rank), named at the end of the verdict.
  std::vector<std::string> diverged;
};

/// Throws InputError when the set has no training or no withheld record, on bad options, or when
/// the base model's prediction is not finite on a withheld record (no gap to measure).
RecordDiagnosis DiagnoseRecords(const io::RecordSet& set, const RecordDiagnoseOptions& options);

/// What a diagnosis said, as a calibration check counts it (diagnose/verdict.h).
TrialVerdict TrialVerdictOf(const RecordDiagnosis& diagnosis);

/// The drive shape / experiment where two fitted models differ most (used by DiagnoseRecords).
ProposedExperiment ProposeExperiment(const io::RecordSet& set, const FitResult& a,
                                     const FitResult& b, double sigma);

/// Simulates a fitted model on a drive shape (the record's rest and excitation, window = the
/// excitation after its first period), output with polarity; offsets not applied.
std::vector<double> PredictOnShape(const FitResult& fit, const DriveShape& shape,
                                   io::Record* record = nullptr);

}  // namespace pz::records
