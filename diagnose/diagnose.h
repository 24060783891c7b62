// The diagnosis of the sim-to-real gap on record sets of any drive, for every family (issue 14;
// docs/diagnosis.md). It is the one engine: the nine-case fin bench (diagnose/fin_diagnose.h) is
// diagnosed by it, its cases turned into records and its choices given as options.
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
//  6. The nine-case bench's choices, each an option (RecordDiagnoseOptions; off by default, so a
//     record set's diagnosis is as above): per-record floors (a case's rounding, scatter and
//     saturation plateaus), the residual analysis's localised excess as the pattern, the greedy
//     second round, the absorbed parameters in the verdict and the V × f trends
//     (diagnose/trends.h). The absorbed parameters and each record's gap before / after are
//     reported whatever the options.
#pragma once

#include <functional>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "diagnose/decision.h"
#include "diagnose/trends.h"
#include "diagnose/verdict.h"
#include "io/records.h"
#include "model/residual_analysis.h"
#include "records/excitation.h"
#include "records/fit.h"
#include "records/noise_floor.h"
#include "synth/synthetic.h"

namespace pz::diagnose {

struct ProposedExperiment {
  synth::DriveShape shape;
  double rms_difference = 0;  ///< between the two models' predictions [response unit]
  double ratio_to_noise = 0;  ///< rms_difference / σ
  std::string description;
};

/// One effect added to the base family, fitted and scored by the rules of diagnose/decision.h.
struct RecordCandidate : CandidateScore {
  model::EffectKind kind;
  records::FitResult fit;
  double z_vs_base = 0;  ///< paired block test against the base model (> 0: better)
};

/// The floor a gap is measured against.
enum class RecordFloor {
  kPooled,     ///< one σ for every record (EstimateNoiseFloor: rest, periods, repeats, residual)
  kPerRecord,  ///< σ_c per record, as the bench's cases: see RecordDiagnoseOptions::floor
};

/// The features whose localised excess a candidate must remove (the rules' pattern share).
enum class RecordPattern {
  kDriveBins,         ///< drive level (10 bins) × direction of the withheld samples
  kResidualAnalysis,  ///< model/residual_analysis.h: see RecordDiagnoseOptions::pattern
};

struct RecordDiagnoseOptions {
  std::string family = "backlash-like";
  std::vector<model::EffectKind> candidates;  ///< empty = every effect that applies to the family
  records::FitOptions fit;                    ///< family options, search and polish of every fit
  DecisionRules rules;                 ///< the decision rules: the same for every effect
  bool propose = true;
  /// kPerRecord (the bench's floor): each record's rounding and scatter over its scored window
  /// (records/noise_floor.h EstimateCaseNoise, its stated frequency giving the cycles: without
  /// one, or under 2 whole cycles, the scatter term is 0), made saturation-aware where the model
  /// that fits the training records best (the base or a first-round candidate) sits on the
  /// record's measured extremes (SaturationAwareFloor); S_floor = Σ_withheld N_c σ_c², the
  /// training part likewise. The pooled σ is still estimated and reported.
  RecordFloor floor = RecordFloor::kPooled;
  /// kResidualAnalysis (the bench's pattern): the withheld group of model/residual_analysis.h over
  /// each record's scored window, read as whole cycles of u = V sin(2π f t) from its first scored
  /// sample (phase bins, branches, reversals, saturation, first / later cycles, each as
  /// n · max(0, rms² − σ²), and the odd, even and low-frequency groups as N/2 · max(0, a² −
  /// noise²): ResidualFeatureExcess). Needs every record's stated frequency (InputError naming the
  /// record).
  RecordPattern pattern = RecordPattern::kDriveBins;
  /// The greedy second round: with the named effect in the model, every other candidate is fitted
  /// on top of it and scored against its gap by the same rules — only while that gap is still
  /// significant (otherwise nothing could be named and no fit is run).
  bool second_effect = false;
  /// The verdict names the base parameters that absorb what the best candidate would explain
  /// when there is no significant gap (RecordDiagnosis::absorbed is filled either way).
  bool absorbed_in_verdict = false;
  /// The grid add-on (diagnose/trends.h): each record fitted alone from the base fit, each
  /// parameter regressed over the records' drive amplitude and stated frequency.
  bool trends = false;
  /// The starting model as the verdict names it (empty: the family's name).
  std::string model_label;
  /// A model with effects as a round's verdict names it: this + " + " + each effect (empty: the
  /// family's name, RecordModel::Describe; the bench's: "base").
  std::string base_name;
  /// A tie's next measurement as a sentence from the two effects (the bench's physics of their
  /// difference), in place of the simulated proposal (`propose`); null: none.
  std::function<std::string(model::EffectKind, model::EffectKind)> next_hint;
  /// The excitation-gap sentence at the end of a significant verdict (records/excitation.h).
  bool excitation_note = true;
  /// Candidate fits as the nine-case bench's (diagnose/fin_diagnose.cc FitStructure), for a
  /// family in its bench form (bimorph-fin's FamilyOptions::bench_form): the starting fit extended
  /// with the new effect at zero (x0); a model with a beam effect refined from x0 with the new
  /// effect's magnitude at fit.beam's start fractions (no search, records/fit.h FitOptions::beam);
  /// any other a DE search (`de`, its seed `seed` + 1000 (the effect's place in the fin library
  /// + 1) + 17 × the model's effects) seeded with x0 and those magnitudes, and polished from x0
  /// and the search's best; a fit that ends above the starting model on the training records is
  /// replaced by x0 (the nested model: the effect at zero). Off: the search of `fit` with the
  /// starting fit and the effect at small magnitudes as extra starts.
  struct BenchFits {
    bool enabled = false;
    opt::DeOptions de{.population = 40, .generations = 60, .stall_generations = 15};
    uint64_t seed = 1;
  } bench_fits;
  /// Where the verdict says its floor comes from (empty: the pooled estimate's method, or
  /// "rounding, scatter and saturation plateaus per record" with per-record floors).
  std::string floor_source;
};

/// A greedy round on top of the named effect (RecordDiagnoseOptions::second_effect).
struct RecordRound {
  std::vector<model::EffectKind> start;     ///< the effects of the starting model
  Gap gap;                                  ///< the starting model's gap, as the rules measured it
  std::vector<RecordCandidate> candidates;  ///< ranked by score, best first
  int named = -1, runner_up = -1;
  double z_runner_up = 0, confidence = 0;
  std::string verdict;  ///< the round's own verdict (diagnose/verdict.h)
};

/// A base parameter that moves when the best first-round candidate is added (what absorbed it):
/// |shift| > 2 combined σ and > 5 % of the larger value.
struct Absorption {
  std::string name, unit;
  double without = 0, with = 0;  ///< base model / model with the effect
  double z = 0;                  ///< shift / combined σ
};

/// One record's gap before (the base) and after (the final model: every named effect).
struct RecordGap {
  std::string name;
  model::CaseRole role = model::CaseRole::kTrain;
  double amplitude = 0, frequency_hz = 0;  ///< of the drive over the window (0: not stated)
  double floor_rms = 0;                    ///< σ_c [response unit]
  double rms_before = 0, rms_after = 0;    ///< [response unit]
  double pi_before = 0, pi_after = 0;      ///< Σe² over the scored window
  double closed = 0;  ///< (PI_b − PI_a)/(PI_b − N σ_c²), clamped to [−9, 1]; 0 without an excess
};

struct RecordDiagnosis {
  records::NoiseFloor noise;
  records::FitResult base;
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
  std::string round_verdict;  ///< the first round's own verdict (no absorbed, second or closing)
  std::optional<ProposedExperiment> next;
  records::ExcitationReport excitation;  ///< what training excites, what each withheld record needs
                                         ///< (records/excitation.h)
  std::string excitation_note;  ///< the excitation-gap sentence, also at the end of the verdict
                                ///< (empty: none)
  /// Candidates left out because their fitted model's prediction is not finite on a withheld
  /// record (it diverges there: no score to rank), named at the end of the verdict.
  std::vector<std::string> diverged;

  /// σ_c of every record (set order): the pooled σ, or per record (RecordDiagnoseOptions::floor).
  std::vector<double> record_floor;
  std::string floor_model;  ///< per-record floors: the model whose saturations they use
  /// The residual analysis (RecordDiagnoseOptions::pattern kResidualAnalysis) of the base model
  /// and of the final one; empty otherwise.
  model::ResidualAnalysis base_residuals, final_residuals;
  std::optional<RecordRound> second;      ///< the greedy round, when one was run
  std::vector<model::EffectKind> named_effects;  ///< every effect named, in order
  /// The base model plus every named effect (the base fit when nothing is named): a copy of that
  /// fit, or null before the diagnosis ran.
  std::shared_ptr<const records::FitResult> final_fit;
  double withheld_after = 0;  ///< Σe² of the final model over the withheld samples
  double closed_total = 0;    ///< ClosedShare(s0, withheld_after, s_floor) (NaN without excess)
  std::vector<Absorption> absorbed;              ///< against the best first-round candidate
  std::string absorbed_by;                       ///< that candidate
  std::vector<RecordGap> gaps;                   ///< per record, set order
  std::vector<pz::diagnose::ParamTrend> trends;  ///< RecordDiagnoseOptions::trends
  int64_t trend_evaluations = 0;                 ///< of the trends' per-record fits
};

/// The first `count` parameters (a base model's) that move by more than 2 combined σ and 5 % of
/// the larger value from `without` to `with` (the base model plus an effect), largest |z| first.
std::vector<Absorption> AbsorbedParameters(std::span<const opt::ParamEstimate> without,
                                           std::span<const opt::ParamEstimate> with, size_t count);

/// The localised excess of a group of the residual analysis over its floor, one entry a feature:
/// n · max(0, rms² − σ²) over the phase bins, rising, falling, near the reversals, in saturation,
/// first and later cycles; N/2 · max(0, a² − noise²) over the odd, even and low-frequency groups.
std::vector<double> ResidualFeatureExcess(const model::GroupResidual& group);

/// Throws InputError when the set has no training or no withheld record, on bad options, or when
/// the base model's prediction is not finite on a withheld record (no gap to measure).
RecordDiagnosis DiagnoseRecords(const io::RecordSet& set, const RecordDiagnoseOptions& options);

/// The options of the nine-case fin bench's diagnosis on its records (io/fin_records.h): the
/// bimorph-fin family in its bench form, the fin library's effects as the candidates, the fin
/// engine's searches (DE 40 × 80 for the base, 40 × 60 for a candidate, LM 40; the bench's
/// candidate fits), per-record floors, the residual analysis as the pattern, the greedy second
/// round, the absorbed parameters in the verdict, the V × f trends, and the verdict's words of the
/// bench ("the base model", floors "per case").
RecordDiagnoseOptions FinBenchOptions();

/// What would separate two effects that the nine-case bench cannot: the physics of their difference
/// (its nine sinusoids; `diagnose --records` simulates candidate drives instead).
std::string FinNextMeasurementHint(model::EffectKind a, model::EffectKind b);

/// A model as the diagnosis names it: RecordModel::Describe, or options.base_name + its effects.
std::string ModelLabel(const records::RecordModel& model, const RecordDiagnoseOptions& options);

/// What a diagnosis said, as a calibration check counts it (diagnose/verdict.h).
TrialVerdict TrialVerdictOf(const RecordDiagnosis& diagnosis);

/// The drive shape / experiment where two fitted models differ most (used by DiagnoseRecords).
ProposedExperiment ProposeExperiment(const io::RecordSet& set, const records::FitResult& a,
                                     const records::FitResult& b, double sigma);

/// Simulates a fitted model on a drive shape (the record's rest and excitation, window = the
/// excitation after its first period), output with polarity; offsets not applied.
std::vector<double> PredictOnShape(const records::FitResult& fit, const synth::DriveShape& shape,
                                   io::Record* record = nullptr);

}  // namespace pz::diagnose
