// The diagnosis of the sim-to-real gap of the nine-case fin bench (issue 6): where the gap lies,
// which unmodelled effect causes it, and how far it shrinks once that effect is in the model. The
// bench is a record set (a bench folder read by io::LoadRecordSet, or io/fin_records.h) diagnosed
// by the records engine (diagnose/diagnose.h DiagnoseRecords with FinBenchOptions: bimorph-fin's
// bench form), with the facts of its V × f grid computed from its records, in these steps:
//
//  1. Base fit: ONE parameter set (μ, δ, α, β, γ, a1, a2) for every case, b1/b2 per case from the
//     measured extremes, fitted on the training cases (global search + Levenberg–Marquardt).
//  2. Every candidate effect of the library is added to the base model and re-identified on the
//     training cases (drive/output effects on the fast path with a global search; beam effects on
//     CVODE, refined from the base fit with a few starting magnitudes).
//  3. Noise floor per case (records/noise_floor.h): rounding and scatter, and on the saturation
//     plateaus of the best-fitting model (lowest training PI) the rounding of the plateau: σ_c.
//     Withheld floor S_floor = Σ_withheld N_c σ_c². Gap of a model: its withheld Σe² = S.
//  4. Where: the residual analysis of the base model (model/residual_analysis.h), and per-case
//     fits (each case alone) whose parameter trends over the V × f grid are regressed (OLS with
//     t statistics): a trend a global model lacks is evidence of an unmodelled effect.
//  5. Which: each candidate is scored on the withheld cases by the decision rules of
//     diagnose/decision.h (the same for every effect, family and data shape: significance, score,
//     training BIC, closed share, pattern, ranking, paired block tests, separation, verdict kind);
//     what the bench supplies is its floor (σ_c per case), its localised excess (phase bins,
//     branches, reversals, saturation, first/later cycles, odd/even harmonics, low frequency: the
//     pattern features) and the withheld squared errors of each model.
//     Otherwise: "no significant gap" (and which parameters absorbed what the best candidate would
//     have explained: the base parameters that move by more than 2 σ when it is added), or "a
//     significant gap that no candidate explains". The sentences are those of every diagnosis
//     (diagnose/verdict.h ComposeVerdict); the bench adds the absorbed parameters, the second
//     effect and, for a tie, what would separate the two on its sinusoids.
//  6. Greedy: with the first effect in the model, the others are tried again on top of it (only if
//     the gap left is still significant: otherwise nothing could be named and no fit is run).
//  7. How far: per case and in total, the withheld gap before and after, the share closed, what
//     remains above the floor; the effect parameters with σ; the identifiability table.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "diagnose/decision.h"
#include "diagnose/diagnose.h"
#include "diagnose/trends.h"
#include "io/records.h"
#include "model/residual_analysis.h"
#include "records/noise_floor.h"

namespace pz::diagnose {

struct DiagnoseOptions {
  std::vector<model::EffectKind> candidates;  ///< empty = the whole library
  int threads = 2;                            ///< ≥ 1
  uint64_t seed = 1;
  /// The evaluators on the service: given the bench form's family options, the factory of every
  /// fit's evaluators (svcclient/complete_service.h RecordsServiceFactory: complete_model
  /// sessions); null = local threads.
  std::function<records::RecordEvaluatorFactory(const records::FamilyOptions&)> records_service;
  opt::DeOptions de_base{.population = 40, .generations = 80, .stall_generations = 15};
  opt::DeOptions de_candidate{.population = 40, .generations = 60, .stall_generations = 15};
  opt::LmOptions lm{.max_iterations = 40};
  int cvode_lm_iterations = 15;  ///< LM iterations of a beam (CVODE) candidate, ≥ 1
  /// Starting magnitudes of a beam candidate, as fractions of the upper end of its magnitude range
  /// (a parameter of either sign: the first fraction on each side), ≥ 1 entry, in (0, 1].
  std::vector<double> cvode_start_fractions = {0.03, 0.15};
  records::EffectSimOptions sim;
  DecisionRules rules;  ///< the decision rules: the same for every effect (diagnose/decision.h)
  bool second_effect = true;                         ///< greedy search for a second effect
  bool trends = true;                                ///< per-case fits and their V × f trends
  std::function<void(const std::string&)> progress;  ///< one line per step (may be null)
  Status Validate() const;
};

/// The bench's options as the records engine's: FinBenchOptions with these candidates (empty: the
/// whole library), searches (DE base and candidate, their seed, LM, the beam refinement), simulator
/// options, rules, rounds, trends, threads and progress.
RecordDiagnoseOptions RecordOptionsOf(const DiagnoseOptions& options);

/// A bench case as the V × f grid reads it, from its record (GridCaseOf): its place in the grid,
/// its role, its noise (rounding and scatter, before the saturations) and its saturations from
/// the measured extremes.
struct BenchCase {
  int number = 0;
  bool training = false;
  double amplitude_v = 0, frequency_hz = 0;
  records::CaseNoise noise;
  double b1 = 0, b2 = 0;  ///< [deg]
};

/// The grid's facts of a fin bench's record (its stated sinusoid, io::Record::sinusoid): the case
/// number, V, f and the role; the noise of its whole record over its stated cycles
/// (records::EstimateCaseNoise); b1, b2 from its measured extremes (model::SaturationFromExtremes).
/// Throws InputError naming the record when it states no sinusoid or its extremes give no
/// saturation.
BenchCase GridCaseOf(const io::Record& record);

/// The bench's diagnosis: the records engine's result on the bench's records, and what only the
/// nine-case grid adds. Each record's gap before / after and its saturation-aware floor are the
/// records result's (`records.gaps`, `records.record_floor`, set order = case order).
struct BenchDiagnosis {
  std::string bench;  ///< the folder or a label (the set's source)
  io::RecordSet set;  ///< the bench's records, in case order
  RecordDiagnosis records;
  std::vector<BenchCase> cases;  ///< set order
  double quantum_deg = 0;        ///< the largest encoder quantum of the cases
  /// The per-case floors' RMS over the training and the withheld samples [deg].
  double floor_train = 0, floor_withheld = 0;
  DecisionRules rules;  ///< the options' decision rules (the report's thresholds)
  double wall_time_s = 0;
};

/// The model evaluations of one fit: its search and polish, and its uncertainty table.
int64_t FitEvaluations(const records::FitResult& f);
/// Every model evaluation of a bench diagnosis: its fits' (FitEvaluations) and the per-case fits
/// of the trends.
int64_t BenchEvaluations(const RecordDiagnosis& d);

/// The one driver of the bench's diagnosis: its records (a fin bench's: each states its sinusoid)
/// diagnosed by the records engine (diagnose/diagnose.h DiagnoseRecords with RecordOptionsOf),
/// with the grid's facts computed from them (GridCaseOf). Throws InputError on invalid options,
/// a record that states no sinusoid, or a set without training or withheld records.
BenchDiagnosis DiagnoseBench(const io::RecordSet& set, const DiagnoseOptions& options);

}  // namespace pz::diagnose
