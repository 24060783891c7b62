// The record fitness of a record model (records/model.h) on a record set's windows (issue 14):
// the least-squares output error with each record's offset handled explicitly (io::OffsetMode), a
// linear family's weights solved exactly inside every evaluation (variable projection: the normal
// equations of RecordCentre / AddRecordRows, non-negative least squares of records/nnls.h, the
// creep spectrum's joint solve of records/spectrum_solve.h), its residuals for the polish
// (RecordResidualFitness), the parameter map of a model with search forms (RecordMap), the error
// figures of a window (RecordMetrics) and the default search budget. What the fit (records/fit.h)
// and the solvers stand on; deterministic, bit for bit whatever the evaluator's threads.
#pragma once

#include <Eigen/Dense>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "io/records.h"
#include "opt/evaluator.h"
#include "opt/fit.h"
#include "opt/param_search.h"
#include "records/model.h"
#include "records/record_rows.h"
#include "records/regularisation.h"
#include "records/spectrum_solve.h"

namespace pz::records {

/// The training criterion: mean squared output error over the scored samples of the records (the
/// sum of squared errors for a family whose cost is the sum, Family::sums_errors: the fin bench's
/// CF = Σ PI, Output::mse then holds that sum).
class RecordFitness final : public opt::FitnessFunction {
 public:
  /// The records and the model must outlive the fitness; each record's drive is prepared once
  /// (RecordModel::Prepare). A diverging parameter set costs `penalty`. Throws InputError on no
  /// records or a penalty that is not finite and > 0.
  RecordFitness(const RecordModel& model, std::vector<const io::Record*> records,
                double penalty = opt::kDefaultErrorCost, std::span<const double> validate_at = {});
  opt::FitnessResult Evaluate(const opt::Genome& genome) const override;
  /// A family that runs parameter sets side by side (Family::lanes; with any effects, each genome
  /// its own drive and output effects): that many genomes at once, each with Evaluate's result bit
  /// for bit.
  int lanes() const override;
  void EvaluateMany(std::span<const opt::Genome* const> genomes,
                    std::span<opt::FitnessResult> out) const override;

  /// Everything about one parameter vector: the weights of a linear family (solved), each record's
  /// output (polarity and offset applied) and offset, the mean squared error. Non-finite output
  /// gives mse = +inf. Thread-safe.
  struct Output {
    std::vector<double> weights;
    std::vector<std::vector<double>> yhat;  ///< per record, samples [0, end_scored)
    std::vector<double> offsets;
    double mse = 0;
  };
  /// keep_outputs = false: yhat left empty (the search's cost needs the MSE alone), the outputs
  /// simulated into a buffer kept per thread instead of a fresh vector per record.
  Output Run(std::span<const double> params, bool keep_outputs = true) const;
  /// Run for several parameter vectors, side by side in lanes() (out[l] = Run(ps[l], keep_outputs)
  /// bit for bit).
  void RunMany(std::span<const std::span<const double>> ps, std::span<Output> out,
               bool keep_outputs = true) const;
  /// The residuals (measured − model) over the scored samples of every record, divided by √N so
  /// that their sum of squares is the MSE; false if the output is not finite. `params`: every
  /// parameter, or the searched ones where spectrum_solved() (the spectrum's weights solved).
  bool Residuals(std::span<const double> params, std::vector<double>& r) const;
  /// Residuals for several parameter vectors side by side (ok[l] = Residuals(ps[l], rs[l]), bit for
  /// bit).
  void ResidualsMany(std::span<const std::span<const double>> ps, std::span<std::vector<double>> rs,
                     std::span<bool> ok) const;

  const RecordModel& model() const { return model_; }
  const std::vector<const io::Record*>& records() const { return records_; }
  /// A regularised linear family: the penalty kept and its strength chosen by validation at
  /// construction (the effects at `validate_at`, every parameter; empty: their neutral values), or
  /// by Revalidate.
  const WeightValidation& validation() const { return validation_; }
  /// Re-chooses the penalty and its strength by the same validation with the effects at `params` (a
  /// fit's solution: effects far from neutral — a creep, a lag — make the neutral model's misfit
  /// look like noise and its validation choose too strong a strength); true when either changed.
  /// Not thread-safe: call between fits.
  bool Revalidate(std::span<const double> params);
  /// A model with `creep-spectrum`: the strength μ of its weights' roughness penalty
  /// μ ‖D w‖² (records/regularisation.h SpectrumRoughness; added to the sum of squared errors, so
  /// μ ‖D w‖² / N to the cost of Evaluate, √(μ/N) D w as extra rows of Residuals when μ > 0). Zero
  /// (the search unpenalised) until RevalidateSpectrum.
  const WeightValidation& spectrum_validation() const { return spectrum_validation_; }
  /// Chooses μ by the blocked cross-validation of records/regularisation.h on the training
  /// records, linearised at `params` (a fit's solution): the output's Jacobian J with respect to
  /// every searched parameter (opt::ScaledJacobian over `map`, the fit's box; a linear family's
  /// weights re-solved inside, so its columns carry the trade-off with the loop's shape), the step
  /// p from `params` solved per left-out block as min ‖J p − (r + J p₀)‖² + μ ‖D w‖² with the
  /// spectrum's weights ≥ 0 and the other parameters free. True when μ changed. Not thread-safe:
  /// call between fits.
  bool RevalidateSpectrum(std::span<const double> params, const opt::ParameterMap& map,
                          int threads);
  /// The standard error of each spectrum weight from the training records alone (no penalty), at
  /// the last RevalidateSpectrum's point: s² (JᵀJ)⁺ of the same linearisation, s² = Σ r² / (N − p).
  /// Empty before it.
  const std::vector<double>& spectrum_sigma() const { return spectrum_sigma_; }
  /// The roughness penalty μ ‖D w‖² at `params` (0 without the spectrum or μ).
  double SpectrumPenalty(std::span<const double> params) const;
  /// A linear family with the creep spectrum (records/spectrum_solve.h SpectrumSolved): its weights
  /// are solved with the family's in every evaluation, so the search covers the other parameters
  /// only (searched()); Evaluate and Residuals take either those or every parameter.
  bool spectrum_solved() const { return spectrum_solved_; }
  /// The indices in model().params() of the searched parameters.
  const std::vector<size_t>& searched() const { return searched_; }
  /// Every parameter from the searched ones: the spectrum's weights solved jointly with the
  /// family's at the current strengths (SolveSpectrum; `cost`: its Σ e² + μ ‖D w‖² over N, +inf
  /// when not finite). Without spectrum_solved(): the values themselves.
  std::vector<double> Expand(std::span<const double> searched, double* cost = nullptr) const;
  size_t samples() const { return samples_; }
  double penalty() const { return penalty_; }
  /// The residuals' factor: 1/√N, so that Σ r² is the MSE; 1 for a family that sums its errors
  /// (Family::sums_errors).
  double ResidualWeight() const;

 private:
  /// `regs` (optional): each record's regressors, kept for the output when no linear output effect
  /// changes them (else untouched).
  std::vector<double> SolveWeights(std::span<const double> params,
                                   std::vector<std::vector<double>>* regs = nullptr) const;
  WeightValidation ValidateAt(std::span<const double> params) const;
  /// The family's parameters at 0, each effect's at 0 or, outside its box, at its lower bound.
  std::vector<double> NeutralParams() const;
  /// The joint solve's problem at the current strengths, from spectrum_start_.
  SpectrumProblem SpectrumProblemNow() const;
  /// The weights' normal equations over eq.G.size() contiguous blocks of the scored samples; `regs`
  /// as SolveWeights'.
  void Accumulate(std::span<const double> params, BlockedNormalEquations& eq,
                  std::vector<std::vector<double>>* regs = nullptr) const;
  /// Residuals from Run's output at `params`.
  bool ResidualsOf(const Output& o, std::span<const double> params, std::vector<double>& r) const;
  /// The MSE of a sum of squared errors over the scored samples (+inf when not finite).
  double MeanSquare(double sse) const;
  /// Evaluate's result for an MSE at `params` (the spectrum's penalty added; a penalty when not
  /// finite).
  opt::FitnessResult Cost(double mse, std::span<const double> params) const;
  const RecordModel& model_;
  std::vector<const io::Record*> records_;
  std::vector<std::shared_ptr<const Family::Prepared>> prepared_;  ///< per record (null: none)
  size_t samples_ = 0;
  double penalty_;
  std::vector<Eigen::MatrixXd> penalties_;  ///< the family's candidate penalties R_k (empty: none)
  std::vector<std::string> penalty_names_;
  Eigen::MatrixXd regularisation_;  ///< the one the validation keeps (empty: none)
  /// Many weights (records/nnls.h kIncrementalNnlsFrom): where every solve of them starts, the
  /// weights at the neutral parameters (empty: from 0).
  Eigen::VectorXd weights_start_;
  WeightValidation validation_;
  size_t spectrum_first_ = 0,
         spectrum_count_ = 0;           ///< the creep spectrum's weights in params (count 0: none)
  Eigen::MatrixXd spectrum_roughness_;  ///< D
  WeightValidation spectrum_validation_;
  std::vector<double> spectrum_sigma_;
  bool spectrum_solved_ = false;
  std::vector<size_t> searched_;
  /// Where every joint solve starts: the spectrum solved from w = 0 and from log creep at the
  /// neutral parameters, once (empty: those two starts in every solve).
  std::vector<double> spectrum_start_, spectrum_start_theta_;
  std::shared_ptr<const SpectrumMetric> spectrum_metric_;  ///< at the reference (null: none)
};

/// Error figures of a model on one record's window.
struct RecordMetrics {
  std::string name;
  model::CaseRole role = model::CaseRole::kTrain;
  size_t samples = 0;
  double rmse = 0;      ///< [response unit]
  double max_abs = 0;   ///< largest |error|
  double max_at_s = 0;  ///< the record's time of the largest |error| [s] (the first, on ties)
  double nrmse_pct =
      0;             ///< RMSE / measured range over the window × 100; infinite when the range is 0
  double range = 0;  ///< measured max − min over the window
  double offset = 0;  ///< the offset used
  double sse = 0;     ///< Σ error² over the window (a fin bench case's PI [deg²])
};

/// The default global search of `piezoid fit`, sized by the number of parameters the search
/// actually searches (a linear family's weights are solved in every evaluation, so with effects
/// only the effects' parameters are searched): a one-parameter search needs neither a swarm of 30
/// nor 150 iterations, and a swarm that has collapsed onto its best has converged (the polish does
/// the rest). d searched parameters:
///
///   particles   = min(30, 10 + 5 (d − 1))        10, 15, 20, 25, 30 …
///   iterations  = min(150, 30 + 30 (d − 1))      30, 60, 90, 120, 150 …
///   stall       = min(40, 10 d)                  10, 20, 30, 40 …
///   repetitions = d ≤ 2 ? 2 : 3
///   converged   = every particle within 1e-3 of the best (unit box): stop the repetition.
///
/// One searched parameter (d = 1) takes the line search instead of a swarm (opt::SearchAlgorithm::
/// kLine: a grid of 17 points over its range, one batch, then the grid's lowest two local minima
/// refined by Brent's method side by side to 1e-4 of the range; no random choice): the cost of one
/// bounded scalar (a delay) is cheap to bracket, and ≈ 40 evaluations find what a swarm of 10 × ≤
/// 30 × 2 finds in ≈ 460 (docs/performance.md, "The 10 s target on the 150 V recording").
///
/// docs/performance.md, "The 10 s target on the 150 V recording".
struct SearchBudget {
  int particles = 30, iterations = 150, stall = 40, repetitions = 3;
  double converged_spread = 0;
  /// "PSO 10 particles × ≤ 30 iterations, stall 10, converged at a spread of 0.001, 2 repetitions".
  std::string Describe() const;
};
SearchBudget SizedSearchBudget(size_t searched);
/// The PSO budget of `search` (its repetitions and PSO options).
SearchBudget BudgetOf(const opt::SearchOptions& search);

/// One coordinate of a box ↔ [0, 1] (log scale: lower > 0), clamped: the arithmetic of RecordMap.
double UnitCoordinate(double lower, double upper, bool log_scale, double x);
double PhysicalCoordinate(double lower, double upper, bool log_scale, double u);

/// The parameter map of a record model whose parameters have search forms (RecordModel::
/// search_forms: bimorph-fin's bench form): each parameter in its box (linear, or log where
/// marked), mapped to [0, 1]; a ratio parameter (SearchForm::ratio_of = j) searched as the ratio
/// x_i / x_j in its box, so its bounds at a point are the box's times x_j; the typical scale of
/// the form where it gives one, else the box's (as opt::BoxMap). The former fin engine's
/// arithmetic for the same box, bit for bit (tests/diagnose/fin_records_test.cc pins it). The
/// genomes are unit coordinates
/// (physical_genomes() false): FitModel hands its evaluators the physical values. The model must
/// outlive the map.
class RecordMap final : public opt::ParameterMap {
 public:
  /// Throws InputError on a ratio of a ratio or out of range.
  explicit RecordMap(const RecordModel& model);
  int size() const override { return static_cast<int>(params_.size()); }
  std::string name(int i) const override { return params_[i].name; }
  std::string unit(int i) const override { return params_[i].unit; }
  std::vector<double> ToPhysical(std::span<const double> unit) const override;
  std::vector<double> ToUnit(std::span<const double> physical) const override;
  void Bounds(std::span<const double> x, int i, double* lower, double* upper) const override;
  double Scale(std::span<const double> x, int i) const override;
  bool physical_genomes() const override { return false; }
  opt::ParamBox SearchBox() const override { return opt::UnitBox(*this); }

 private:
  const std::vector<ParamInfo>& params_;
  const std::vector<Family::SearchForm>& forms_;
};

/// The residuals of the training records at physical values (FitnessResult::residuals:
/// RecordFitness::Residuals; cost Σ r², the MSE; a penalty and "diverged" when an output is not
/// finite), the polish's fitness: locally, and on a worker for a complete_model spec with
/// `residuals` (complete/job_kind.h), bit for bit. Runs the fitness's lanes (a Jacobian's columns
/// side by side, each Evaluate's bit for bit). The fitness must outlive it.
class RecordResidualFitness final : public opt::FitnessFunction {
 public:
  explicit RecordResidualFitness(const RecordFitness& fitness) : fitness_(fitness) {}
  opt::FitnessResult Evaluate(const opt::Genome& genome) const override;
  int lanes() const override { return fitness_.lanes(); }
  void EvaluateMany(std::span<const opt::Genome* const> genomes,
                    std::span<opt::FitnessResult> out) const override;

 private:
  const RecordFitness& fitness_;
};

/// What a records fit's evaluator returns: the global search's costs (RecordFitness) or the
/// Levenberg–Marquardt polish's residual vectors (RecordResidualFitness over the fitness).
enum class RecordEvaluation { kCost, kResiduals };

/// Builds the evaluator of a global search (kCost) or of one polish (kResiduals: a Jacobian per
/// batch; called once per polish, concurrently where polishes run side by side) over the fitness
/// (null factory = a thread pool of `threads`). The genomes are physical values.
using RecordEvaluatorFactory =
    std::function<std::unique_ptr<opt::BatchEvaluator>(const RecordFitness&, RecordEvaluation)>;

}  // namespace pz::records
