// `piezoid fit --family auto` (issue 37): the family, its effects, its resolution (plays /
// Preisach levels) and its initial state chosen by blocked cross-validation on the training
// records alone; the withheld records are scored only after the choice.
//
// Folds: each training record's scored window is cut into K contiguous blocks (K = folds). Fold k
// fits the candidate on every training record with its block k masked — the record is split into
// the pieces before and after the block, each simulated from the record's rest as the record is
// (so the model's state there is the record's), only the scoring masked — and scores block k: the
// model's output over the whole window, its offset fitted on the fold's training samples of that
// record (offset `fit`; `rest` / a fixed offset as the record has it), the error on the block. The
// fold's RMSE pools every record's block; a candidate's CV RMSE is the mean over the folds, its
// standard error their standard deviation / √K. Every candidate is made for the data scale of the
// whole training set (its search box, the Preisach grid, the effects' ranges), so that the folds
// differ in the scored samples alone.
//
// Rounds: a screening round fits every candidate of the grid (families × effect sets; a linear
// family at the first rung of the resolutions' ladder) in every fold with a small search budget
// (the linear families without effects search nothing and are exact already). A linear family's
// resolution is then chosen by the same folds: its weights re-solved in each fold at the next
// rungs with its effects where the fold's fit put them (no search: records/preisach_family.h
// FitPreisachLevels for a Preisach grid), climbing while the finest rung tried has the lowest CV
// RMSE, and the fewest within one paired SE of the lowest kept (SelectOptions::levels). The
// `finalists` best of the screening and the simplest candidate within one standard error of its
// best are cross-validated again with the search of `piezoid fit` (one repetition of its sized
// budget, its swarm ≤ 15 × 40 iterations, a polish of ≤ 30 iterations) at their chosen
// resolutions (with effects at a finer one than the first rung: the effects searched at the first,
// the weights re-solved at theirs, as the refits after the choice) — the best of the screening
// also with the other initial state worth trying (the records' first branches show one, the
// rest-level rule another). The one-standard-error rule picks among those: the candidate with
// the fewest parameters (searched parameters + solved weights) whose CV RMSE is within one standard
// error of the lowest; ties by CV RMSE, then grid order. The standard error is the paired one (as
// records/regularisation.h's): of the candidate's fold RMSEs less the best's, over the folds — the
// blocks of a record differ in difficulty (the first holds the jump from rest and the creep after
// it) far more than two candidates differ on one block, and the unpaired SE would let any model
// through. The winner is refitted on all the
// training records (an ordinary fit: its fit.json loads in export / compensate); the other
// finalists too, to show their withheld errors after the choice.
//
// The initial state from the data (DetectInitialStates): a Prandtl–Ishlinskii operator (12 plays,
// weights by NNLS; with a transport delay where it lowers the training RMSE by 30 % or more: a
// sensor's lag at the jump from rest would swamp the branch) is fitted on the training records;
// each record's first branch — from the end of its rest until its drive has been within 5 % of both
// ends of the training range, when the memory at rest is wiped out — is then simulated from each
// memory at rest (centred, descended, ascended) with those weights, and the memory whose branch
// matches the measured one best is the record's (a demagnetised stack rises on its virgin curve,
// one that came down to rest rises on its major loop's ascending branch).
//
// Deterministic: the choice and the refitted model are functions of (records, options) alone, bit
// for bit, whatever the number of threads or whether the searches run on a master's workers (the
// folds run side by side, each fit with one thread; with a service, one after another).
#pragma once

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include "io/records.h"
#include "records/fit.h"
#include "records/noise_floor.h"

namespace pz::records {

/// One model of the grid.
struct Candidate {
  std::string family;
  std::vector<EffectKind> effects;
  int levels = 12;  ///< plays (prandtl-ishlinskii, asymmetric-pi) or Preisach levels; 0: none
  model::InitialState initial_state = model::InitialState::kAuto;
  /// "preisach (12 levels) + delay, descended".
  std::string Describe() const;
  /// The fit options of this candidate on top of `base` (family, effects, levels, initial state).
  FitOptions Options(const FitOptions& base) const;
};

/// A candidate's cross-validation.
struct ModelScore {
  Candidate candidate;
  size_t parameters = 0;  ///< searched parameters + solved weights
  int round = 1;          ///< 1: screened only; 2: cross-validated with the full search
  double cv_rmse = std::numeric_limits<double>::infinity();
  double cv_se = 0;  ///< standard error of the fold RMSEs
  std::vector<double> fold_rmse;
  /// Set by OneStandardErrorChoice: the standard error of (fold RMSEs − the best's), and whether
  /// the CV RMSE is within one of it above the best's.
  double se_vs_best = 0;
  bool within_one_se = false;
  double screen_cv_rmse = std::numeric_limits<double>::infinity();  ///< its screening round's
  /// After the choice: the candidate refitted on every training record (finalists only; NaN else).
  double train_rmse = std::numeric_limits<double>::quiet_NaN();
  double withheld_rmse = std::numeric_limits<double>::quiet_NaN();
  /// Finalists, where the withheld drives need excitation the training lacks: the RMS of this
  /// finalist's prediction less the finalists' median prediction over those samples (NaN else).
  double parting = std::numeric_limits<double>::quiet_NaN();
  /// A linear family: its resolution chosen by the screening's folds (SelectOptions::levels) —
  /// the levels tried, each one's CV RMSE (+inf: a fold could not support it), the lowest's index
  /// and the chosen one's (the fewest within one paired SE or 1 % of the lowest); empty: one
  /// resolution.
  std::vector<int> level_candidates;
  std::vector<double> level_cv_rmse;
  size_t level_best = 0, level_chosen = 0;
  /// "12 levels by the folds (the fewest within one SE of the best, 20): 8 → 0.31, 12 → 0.2, 20 →
  /// 0.19" ("" without a choice).
  std::string LevelsDescribe() const;
  std::string error;  ///< why it could not be fitted ("" when it was)
};

/// The memory at rest a record's first branch shows.
struct InitialStateEvidence {
  std::string record;
  model::CaseRole role = model::CaseRole::kTrain;
  size_t from = 0, to = 0;  ///< the first branch: samples [from, to)
  double rise = 0;          ///< the drive at its end less the rest level (drive unit)
  /// The branch's RMSE from each memory: centred, descended, ascended (response unit).
  double rmse[3] = {0, 0, 0};
  model::InitialState state = model::InitialState::kCentred;  ///< the best of the three
  std::string note;  ///< why there was no choice (no branch), "" else
  /// "centred 0.41, descended 0.052, ascended 0.93 µm over 0.24 s: descended".
  std::string Describe(const std::string& unit) const;
};

/// Each record's memory at rest from its first branch (training and withheld records; the
/// withheld ones are reported, never used). Throws InputError as FitRecords does on bad training.
std::vector<InitialStateEvidence> DetectInitialStates(const io::RecordSet& set,
                                                      const FitOptions& base);
/// The memory the training records show: the one most of them show (ties: centred first, then
/// descended); kCentred without training evidence.
model::InitialState TrainingInitialState(const std::vector<InitialStateEvidence>& evidence);

struct SelectOptions {
  /// Families tried (default: every family of records/families.h but bimorph-fin, whose
  /// geometry is a fin's).
  std::vector<std::string> families;
  /// Effect sets tried (default: none, delay, creep, creep + delay, creep-spectrum, creep-spectrum
  /// + delay; the spectrum on the linear families only, and no delay on a training drive of one
  /// rate: GridNote); a set a family excludes or the data cannot support is left out.
  std::vector<std::vector<EffectKind>> effect_sets;
  /// Resolutions of the linear families (plays / Preisach levels), ascending: the ladder the
  /// screening climbs. Each linear candidate is fitted at the first in every fold; its weights are
  /// then re-solved in the same fold at the next `levels_first` − 1 with its effects where that fit
  /// put them (no search), and at the next rung while the finest tried is lower than the others by
  /// more than 1 %. The fewest rungs within one paired SE or 1 % of the lowest CV RMSE are the
  /// candidate's resolution, with which it is ranked and cross-validated again as a finalist. One
  /// entry (or
  /// kAutoLevels alone: the default ladder): that resolution only.
  std::vector<int> levels = {8, 12, 20, 28, 40};
  int levels_first = 3;
  int folds = 5;
  size_t finalists = 3;
  /// The screening round's search: PSO particles × iterations × 1 repetition, LM iterations, the
  /// line search's grid.
  int screen_particles = 8, screen_iterations = 10, screen_lm_iterations = 5, screen_line_grid = 9;
  /// The finalists' folds: `fit`'s search with at most this many repetitions and LM iterations (the
  /// chosen model's refit on every training record has `fit`'s own).
  int final_repetitions = 1, final_lm_iterations = 30;
  /// …and (the sized budget) at most this swarm and these iterations.
  int final_particles = 15, final_iterations = 40;
  /// "" (detect: the first branches, DetectInitialStates) or a state given by the user (an
  /// override: every candidate takes it).
  bool initial_state_given = false;
  /// The full search and everything else of `piezoid fit` (its family, effects and
  /// family_options.pi_operators / initial_state are the candidates'; threads as given).
  FitOptions fit;
  /// --master: the evaluator factory of a candidate's fits (its family options); null: threads.
  std::function<RecordEvaluatorFactory(const FamilyOptions&)> service;
  std::function<void(const std::string&)> progress;
};

struct SelectionResult {
  std::vector<ModelScore> ranking;  ///< round 2 first by CV RMSE, then round 1 by CV RMSE
  size_t chosen = 0;                ///< index in ranking
  double best_cv_rmse = 0;          ///< the lowest round-2 CV RMSE
  std::vector<InitialStateEvidence> initial_states;  ///< per record (every record of the set)
  model::InitialState detected = model::InitialState::kCentred;  ///< TrainingInitialState
  FitResult fit;           ///< the chosen candidate refitted on all training records
  FitOptions fit_options;  ///< its options
  NoiseFloor noise;        ///< the records' noise floor (EstimateNoiseFloor), beside the errors
  /// "" or, when the withheld drives need excitation the training lacks, how the finalists'
  /// predictions part there and how that weighed in the choice.
  std::string unexcited;
  std::string grid_note;  ///< GridNote
  int folds = 0;
  size_t fold_fits = 0;  ///< fits run for the cross-validation
  double wall_time_s = 0;
};

/// Why the default grid leaves a rate effect out ("" when it does not): a training drive of one
/// rate (records/excitation.h rate span under kMinRateSpan) and withheld drives with reversals or
/// range the training lacks — a delay there is a phase that a hysteretic family's loop width gives
/// as well, which no fold can tell apart, and fitted for the width it mispredicts other loops.
std::string GridNote(const io::RecordSet& set, const SelectOptions& options);

/// The grid of candidates for `set`'s training records (families × effect sets × resolutions,
/// the initial state `state`), in grid order.
std::vector<Candidate> CandidateGrid(const io::RecordSet& set, const SelectOptions& options,
                                     model::InitialState state);

/// The blocked K-fold cross-validation of one candidate on the training records (options.fit
/// the fit's options: search budget, threads; `service` as SelectOptions'). Throws InputError when
/// a training window has fewer than 2 K samples.
ModelScore CrossValidate(
    const io::RecordSet& set, const Candidate& c, const FitOptions& fit, int folds,
    const std::function<RecordEvaluatorFactory(const FamilyOptions&)>& service = {});

/// The one-standard-error rule over scores: the index of the candidate with the fewest parameters
/// whose CV RMSE ≤ the lowest + the paired standard error of its fold RMSEs less the lowest's (the
/// best's cv_se where the fold RMSEs are missing or not as many); ties: lower CV RMSE, then the
/// lower index. Sets each score's se_vs_best and within_one_se. Throws InputError when no score is
/// finite.
size_t OneStandardErrorChoice(std::vector<ModelScore>& scores);

/// The whole selection. Throws InputError on no training records or no candidate that fits.
SelectionResult SelectModel(const io::RecordSet& set, const SelectOptions& options);

}  // namespace pz::records
