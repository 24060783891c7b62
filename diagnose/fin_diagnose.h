// The diagnosis of the sim-to-real gap of the nine-case fin bench (issue 6): where the gap lies,
// which unmodelled effect causes it, and how far it shrinks once that effect is in the model. The
// bench's cases are records (io/fin_records.h) diagnosed by the records engine (diagnose/diagnose.h
// DiagnoseRecords with records::FinBenchOptions: bimorph-fin's bench form), in these steps:
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

#include "diagnose/problem.h"
#include "model/residual_analysis.h"
#include "diagnose/decision.h"
#include "diagnose/diagnose.h"
#include "diagnose/trends.h"
#include "io/records.h"

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
  model::EffectSimOptions sim;
  records::DecisionRules
      rules;  ///< the decision rules: the same for every effect (diagnose/decision.h)
  bool second_effect = true;                         ///< greedy search for a second effect
  bool trends = true;                                ///< per-case fits and their V × f trends
  std::function<void(const std::string&)> progress;  ///< one line per step (may be null)
  Status Validate() const;
};

/// One candidate structure, fitted and scored by the rules of diagnose/decision.h.
struct CandidateResult : records::CandidateScore {
  model::EffectKind kind;  ///< the effect added in this round (none: the base)
  FitResult fit;
  int added_params = 0;
};

/// One greedy round: the model it starts from, its gap, the candidates on top of it.
struct RoundResult {
  std::vector<model::EffectKind> base_structure;
  double s0 = 0;         ///< withheld Σe² of the starting model [deg²]
  double s_floor = 0;    ///< withheld floor Σ N σ² [deg²]
  double rms_ratio = 0;  ///< √(s0 / s_floor)
  bool significant = false;
  std::vector<CandidateResult> candidates;  ///< ranked by score, best first
  int named = -1;                           ///< index into candidates, −1 if none named
  int runner_up = -1;      ///< a qualifying candidate the data cannot separate from the named one
  double z_runner_up = 0;  ///< its paired block z against the named one
  records::Gap gap;        ///< the starting model's gap, as the rules measured it
  std::string verdict;     ///< the round's verdict (diagnose/verdict.h)
};

using pz::diagnose::ParamTrend;
using records::Absorption;

/// Per-case before/after of the final model.
struct CaseGap {
  int number = 0;
  bool training = false;
  double amplitude_v = 0, frequency_hz = 0;
  double floor_rms = 0;                  ///< σ_c [deg]
  double rms_before = 0, rms_after = 0;  ///< [deg]
  double pi_before = 0, pi_after = 0;    ///< [deg²]
  double closed = 0;  ///< (PI_b − PI_a)/(PI_b − N σ²), clamped to [−9, 1]
};

struct Diagnosis {
  std::string bench;  ///< the folder or a label
  std::vector<DiagCase> cases;
  double quantum_deg = 0;
  double floor_train = 0, floor_withheld = 0;  ///< pooled saturation-aware floor [deg]
  std::string floor_model;                     ///< the model whose saturations the floor uses
  FitResult base;
  model::ResidualAnalysis base_residuals;
  std::vector<ParamTrend> trends;
  std::vector<RoundResult> rounds;
  std::vector<model::EffectKind> named;  ///< effects named, in order
  double confidence = 0;                 ///< of the first named effect (or of "none")
  FitResult final_fit;                   ///< the base model plus the named effects
  model::ResidualAnalysis final_residuals;
  std::vector<CaseGap> gaps;
  double withheld_before = 0, withheld_after = 0;  ///< Σe² [deg²]
  double withheld_floor = 0;                       ///< S_floor [deg²]
  double closed_total = 0;                         ///< share of the excess closed
  double remaining_ratio = 0;                      ///< √(after / floor)
  std::vector<Absorption> absorbed;                ///< when an effect is mimicked by the base terms
  std::string absorbed_by;                         ///< the candidate whose addition shows it
  std::string verdict_kind;  ///< "effect", "inseparable" (named, but a runner-up explains it as
                             ///< well), "none" (no significant gap), "unexplained"
  std::string verdict;       ///< the summary sentence(s)
  double wall_time_s = 0;
  int64_t evaluations = 0;
};

/// The diagnosis of the bench's records (io/fin_records.h; diagnose/diagnose.h DiagnoseRecords
/// with FinBenchOptions) as the bench's report reads it: `set` the records of `model`'s cases, in
/// case order. Each fit's figures are its records' (per-case PI, σ and identifiability from the
/// uncertainty table, evaluations with the table's).
Diagnosis DiagnosisOfRecords(const DiagnosisModel& model, const io::RecordSet& set,
                             const records::RecordDiagnosis& diagnosis);

/// The bench's options as the records engine's: FinBenchOptions with these candidates (empty: the
/// whole library), searches (DE base and candidate, their seed, LM, the beam refinement), simulator
/// options, rules, rounds, trends, threads and progress.
records::RecordDiagnoseOptions RecordOptionsOf(const DiagnoseOptions& options);

/// The bench's cases as records (io/fin_records.h; a withheld case validates).
io::RecordSet RecordsOfCases(const std::vector<DiagCase>& cases);

/// The one driver of the bench's diagnosis: its cases as records, diagnosed by the records engine
/// (diagnose/diagnose.h DiagnoseRecords with RecordOptionsOf) and read back as the bench's
/// Diagnosis (DiagnosisOfRecords). Throws InputError on invalid options.
Diagnosis DiagnoseBench(const DiagnosisModel& model, const DiagnoseOptions& options);

}  // namespace pz::diagnose
