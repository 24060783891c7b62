// Identification of a record model (records/model.h) on the training records of a record set
// (issue 14): the least-squares output error over the scored windows, with each record's offset
// handled explicitly (io::OffsetMode): the one fit of opt/fit.h over the model's parameter box — a
// global search (PSO / real GA / binary GA / DE of opt/param_search.h, through the evaluator seam:
// threads here, the service's workers with --master), a bounded Levenberg–Marquardt polish (its
// Jacobians one batch of a residual evaluator, through the same seam) and the uncertainty table (σ,
// sensitivity, identifiability, singular values) at the solution. A linear-in-parameters family
// (the Prandtl–Ishlinskii operator) has its weights solved exactly by non-negative least squares
// inside every evaluation (variable projection), so only effect parameters are searched.
//
// Deterministic: the result is a function of (records, model, options) alone, bit for bit,
// whatever the evaluator or its thread count.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "io/records.h"
#include "opt/fit.h"
#include "opt/param_search.h"
#include "records/fitness.h"

namespace pz::records {

struct FitOptions {
  std::string family = "backlash-like";
  std::vector<EffectKind> effects;
  FamilyOptions family_options;
  opt::SearchOptions search = [] {
    opt::SearchOptions s;
    s.repetitions = 3;
    s.pso.particles = 30;
    s.pso.iterations = 150;
    s.pso.stall_iterations = 40;
    return s;
  }();
  /// Size the PSO search by SizedSearchBudget(the searched parameters) — `piezoid fit`'s default —
  /// except the fields marked kept, which stay as `search` has them (the user's explicit flags).
  /// With one searched parameter and neither the algorithm nor any of the PSO budget kept, the
  /// search is the line search of `search.line` (its repetitions 1).
  struct Sizing {
    bool enabled = false;
    bool keep_particles = false, keep_iterations = false, keep_stall = false,
         keep_repetitions = false;
    bool keep_algorithm = false;  ///< `--algorithm` given (pso stays pso)
    /// The line search's budget was given (`--line-grid` …): an error where it is not the search.
    bool line_given = false;
  } sizing;
  bool polish = true;  ///< Levenberg–Marquardt after the search
  /// Polish also each other repetition's best, keeping the lowest
  /// (opt::FitOptions::polish_repetitions: a better basin replaces the search's best's polish only
  /// by more than 1e-4 of its cost).
  bool polish_repetitions = false;
  opt::LmOptions lm{.max_iterations = 60, .fd_step = 1e-4};
  /// The polish's differences chosen by the search (`--lm-differences auto`): forward throughout
  /// after the line search (one searched parameter, already located to its tolerance: the central
  /// finish only adds serial evaluations), else forward until the polish converges, then central
  /// (lm.central = false, lm.central_to_finish set here). False: lm's as given.
  bool lm_differences_auto = false;
  int threads = 2;
  RecordEvaluatorFactory evaluator_factory;
  /// Starting points for the polish besides the search's best (unit coordinates, e.g. a base fit
  /// with an effect at small magnitudes); the best polished one is kept.
  std::vector<std::vector<double>> extra_starts;
  /// Non-empty (physical values of every parameter): no global search; the polish starts here (a
  /// Preisach grid at the levels chosen by validation, from the coarsest grid's fit).
  std::vector<double> polish_from;
  /// Physical points (every parameter) seeding the global search's first population, after
  /// search.seeds; and physical starts of the polish besides the search's best, before
  /// extra_starts (the fin bench's seeds and starts of a candidate, diagnose::FinBenchOptions).
  std::vector<std::vector<double>> seed_points, start_points;
  /// A model with a beam effect (bimorph-fin's bench form: each run on CVODE) is refined from
  /// polish_from (needed), not searched: one polish from each start, the last effect's magnitude
  /// at a fraction of the upper end of its range (a parameter of either sign: the first fraction on
  /// each side), of lm_iterations Levenberg–Marquardt iterations with forward differences (lm's
  /// other options as given). The fin bench's DiagnoseOptions::cvode_lm_iterations and
  /// cvode_start_fractions (diagnose/fin_diagnose.h).
  struct BeamRefinement {
    int lm_iterations = 15;                              ///< ≥ 1
    std::vector<double> start_fractions = {0.03, 0.15};  ///< ≥ 1 entry, each in (0, 1]
  } beam;
  /// creep-spectrum: its weights' roughness penalty chosen by validation at the solution (false:
  /// the weights unpenalised, as the search has them; for comparisons).
  bool spectrum_roughness = true;
  /// The uncertainty table at the solution (2p + 1 evaluations, on this machine; its Jacobian
  /// steps are lm.fd_step of each parameter's unit range).
  bool uncertainty = true;
  std::function<void(const std::string&)> progress;
};

struct FitResult {
  std::shared_ptr<RecordModel> model;
  std::vector<double> params;   ///< physical values, model().params() order
  std::vector<double> weights;  ///< linear family: the solved weights
  WeightValidation
      regularisation;  ///< a regularised linear family: the strength and its validation
  /// preisach with FamilyOptions::pi_operators = kAutoLevels: the levels chosen by validation
  /// (records/preisach_family.h ChoosePreisachLevels); unused otherwise.
  ResolutionChoice resolution;
  WeightValidation spectrum_regularisation;  ///< creep-spectrum: its roughness penalty's strength
  /// creep-spectrum: each weight's standard error from the training records alone
  /// (RecordFitness::spectrum_sigma; empty without the penalty's validation).
  std::vector<double> spectrum_sigma;
  /// creep-spectrum: "" or which relaxations the training excitation does not identify (σ above
  /// the mean fitted weight: the data cannot tell whether they are there).
  std::string SpectrumIdentification() const;
  /// resonance: where its start came from and whether the polish from there was kept
  /// (records/resonance.h; "" without the effect or without a band in the data).
  std::string mode_start;
  double train_mse = 0;
  double train_sse = 0;
  std::vector<RecordMetrics> metrics;     ///< every record of the set, set order
  std::vector<std::vector<double>> yhat;  ///< every record: the model output [0, end_scored)
  opt::SearchResult search;               ///< empty when nothing was searched
  /// The global search as run (records of it in fit.json and report.md): the PSO budget, whether it
  /// was sized, for how many searched parameters; the polishes run and the one kept.
  opt::SearchAlgorithm algorithm = opt::SearchAlgorithm::kPso;
  /// The polish's Jacobian differences as run: "forward-central", "forward" or "central".
  std::string lm_differences;
  SearchBudget budget;
  opt::LineOptions line;  ///< the line search's budget (algorithm kLine)
  /// The creep spectrum's weights were solved with the family's weights in every evaluation
  /// (records/spectrum_solve.h), not searched: `solved_parameters` of them.
  bool spectrum_solved = false;
  size_t solved_parameters = 0;
  bool budget_sized = false;
  size_t searched_parameters = 0;
  int polishes = 0;
  int best_polish_repetition =
      -1;  ///< the repetition whose best the kept polish started from (−1: other)
  std::string polish_message;
  int lm_iterations = 0;
  int64_t evaluations = 0;  ///< search and polish
  /// σ, sensitivity (RMS change of the output, response unit, per scale: the unit range of a
  /// linear parameter, ∂x/∂u of a log-scaled one), identifiability, singular values, weakest
  /// direction; empty without options.uncertainty or parameters. Its evaluations are its own.
  opt::Uncertainty uncertainty;
  double wall_time_s = 0;
  std::string stop_reason;
};

/// Fits on the set's training records and evaluates on every record. Throws InputError on no
/// training records, an unknown family / effect or invalid options. preisach with
/// FamilyOptions::pi_operators = kAutoLevels: the grid's levels chosen by validation on the
/// training records (ChoosePreisachLevels over PreisachLevelCandidates; with effects, those are
/// searched on the coarsest grid first, the levels chosen at them, and the chosen grid polished
/// from there).
FitResult FitRecords(const io::RecordSet& set, const FitOptions& options);
/// A fit's model re-made at another resolution, its weights re-solved at its effects (`r`'s
/// model, params and weights those): every record of the set evaluated again (metrics, yhat, the
/// training MSE and SSE), the uncertainty table dropped (the other resolution's).
void EvaluateResolved(const io::RecordSet& set, FitResult& r);
/// The same for a given model (its scale already measured).
FitResult FitModel(const io::RecordSet& set, std::shared_ptr<RecordModel> model,
                   const FitOptions& options);

/// Evaluates a fitted model on any record (output with polarity and offset, metrics).
RecordMetrics Evaluate(const RecordModel& model, std::span<const double> params,
                       std::span<const double> weights, const io::Record& r,
                       std::vector<double>* yhat = nullptr);

}  // namespace pz::records
