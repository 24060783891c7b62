// Levenberg–Marquardt (MATLAB trainlm) and Bayesian-regularised Levenberg–Marquardt (trainbr, after
// MacKay and Foresee & Hagan) training of a FeedForwardNet on a data set divided into training,
// validation and test samples (MATLAB dividerand).
//
// With e = y − t over the N training samples, MSE = Σe²/N, JJ = JᵀJ/N, JE = Jᵀe/N (the toolbox's
// normalised "perfsJEJJ"), the gradient reported is ‖∇MSE‖ = 2‖JE‖. As in the toolbox, e, MSE, JJ
// and JE are in target units: the network's output passes through the reverse mapminmax before the
// error is taken (mse's 'normalization' parameter defaults to 'none'); see min_grad_normalised.
//
// LM epoch:  solve (JJ + μI) δ = −JE by Cholesky; accept w + δ if the training MSE drops (μ ← μ
// μ_dec,
//            floor 1e−20), else μ ← μ μ_inc and retry (a failed or ill-conditioned factorisation,
//            rcond < ε, counts as a rejected step). Stops on: epochs, goal, min_grad, μ > μ_max,
//            max_fail successive epochs without a new best validation MSE, time. Returns the
//            weights of the best validation MSE (the last weights if there is no validation set).
// BR epoch:  the same loop on F = β MSE + α Σw² with (β JJ + (μ + α) I) δ = −(β JE + α w), then
//            γ = P − α tr((β JJ + α I)⁻¹),  α = γ / (2 Σw²),  β = (N − γ) / (2 MSE)
//            (MacKay's re-estimation; with E_D = SSE the same as β' = β/N = (N − γ)/(2 E_D)).
//            No validation stop by default (max_fail = 0); returns the last weights.
//
// An epoch's cost is dominated by JJ: N P² flops as a symmetric rank-k update (7,001 × 301² ≈ 0.63
// GFLOP for the default Dahl network), formed in row blocks of J (block_rows) so a block stays in
// cache (model/dense_kernels.h). Deterministic: no randomness inside the trainers; the split and
// the initial weights come from SetUpFit's single seeded generator.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "model/ffnet.h"
#include "model/status.h"

namespace pz::model {

/// A regression data set: n samples, inputs as rows of x (n × R), scalar targets t (n).
struct RegressionData {
  Eigen::MatrixXd x;
  Eigen::VectorXd t;
  int size() const { return static_cast<int>(t.size()); }
  /// n ≥ 3, x has n rows and ≥ 1 column, all values finite (the message names the first bad entry).
  Status Validate() const;
};

/// Sample indices (0-based, ascending) of each subset.
struct DataSplit {
  std::vector<int> train, val, test;
  /// Disjoint, in [0, n), ascending, train non-empty.
  Status Validate(int n) const;
};

/// Fractions of the samples in each subset (MATLAB's divideParam), each in [0, 1], train > 0,
/// summing to 1 within 1e−9.
struct SplitRatios {
  double train = 0.70;
  double val = 0.15;
  double test = 0.15;
  Status Validate() const;
};

/// MATLAB dividerand: a random permutation of 0..n−1 from rng; n_val = round(val n), n_test =
/// round(test n), the rest train; each subset returned sorted. Throws InputError on bad ratios.
DataSplit DivideRand(int n, const SplitRatios& ratios, std::mt19937_64& rng);

/// Moves each of `rows` that landed in val or test into train, swapping it with a training sample
/// drawn from rng (which takes its place), so the subset sizes stay. Rows already in train are
/// left; the subsets stay sorted. Throws InputError if a row is out of range or the swap is
/// impossible.
void PinToTraining(DataSplit& split, const std::vector<int>& rows, std::mt19937_64& rng);

/// Options shared by both trainers (MATLAB trainlm defaults).
struct LmOptions {
  int epochs = 1000;  ///< maximum epochs, in [0, 1e9]
  double goal = 0.0;  ///< stop when the training MSE ≤ goal [target unit²], finite, ≥ 0
  double min_grad = 1e-7;  ///< stop when ‖∇MSE‖ ≤ min_grad [target unit² per weight unit], ≥ 0
  /// Units of the min_grad test. false (MATLAB's): the gradient as reported, of the MSE in target
  /// units, so it scales with the square of the targets' range (targets 10 × smaller ⇒ gradients
  /// 100 × smaller, and a min_grad stop 100 × sooner). true: the gradient of the MSE in the
  /// mapminmax-normalised target units the network works in (‖∇MSE‖ · gain², gain = 2/(tmax −
  /// tmin)), the same test whatever the unit and scale of the targets. The reported gradient stays
  /// in target units either way.
  bool min_grad_normalised = false;
  int max_fail = 6;      ///< successive epochs without a new best validation MSE before
                         ///< stopping, ≥ 0; 0 disables the validation stop
  double mu = 1e-3;      ///< initial μ, finite, > 0
  double mu_dec = 0.1;   ///< μ factor after an accepted step, in (0, 1)
  double mu_inc = 10.0;  ///< μ factor after a rejected step, finite, > 1
  double mu_max = 1e10;  ///< stop when μ exceeds this, finite, > mu
  double time_limit_s = std::numeric_limits<double>::infinity();  ///< wall-time budget [s], > 0
  int block_rows = 256;      ///< rows of J formed per JᵀJ update, in [1, 1e6]
  bool keep_history = true;  ///< record one EpochRecord per epoch in the summary
  Status Validate() const;
};

/// trainbr defaults: μ = 0.005, no validation stop.
struct BrOptions : LmOptions {
  BrOptions() {
    mu = 5e-3;
    max_fail = 0;
  }
};

enum class TrainMethod : int { kLevenbergMarquardt = 0, kBayesianRegularization = 1 };
const char* TrainMethodName(TrainMethod m);  ///< "LM" / "BR"

enum class TrainTermination : int {
  kMaxEpochs = 0,       ///< epochs reached
  kGoalMet = 1,         ///< training MSE ≤ goal
  kMinGradient = 2,     ///< ‖∇MSE‖ ≤ min_grad
  kMuMax = 3,           ///< μ > mu_max
  kValidationStop = 4,  ///< max_fail epochs without validation improvement
  kTimeLimit = 5,       ///< time_limit_s spent
  kNonFinite = 6,       ///< the initial network gives a non-finite error or Jacobian
};
const char* TrainTerminationName(TrainTermination t);

/// State after an epoch (epoch 0 = the initial network).
struct EpochRecord {
  int epoch = 0;
  double time_s = 0;     ///< wall time since the start [s]
  double mse_train = 0;  ///< [target unit²]
  double mse_val = 0;    ///< NaN without a validation set
  double mse_test = 0;   ///< NaN without a test set
  double mu = 0;
  double gradient = 0;  ///< ‖∇MSE‖
  double gamma = 0;     ///< BR effective number of parameters (NaN for LM)
  double ssw = 0;       ///< Σ w² (sum squared parameters)
  int val_fail = 0;     ///< successive epochs without a new best validation MSE
};

/// MSE and regression coefficient R (Pearson correlation of output and target) on one subset.
struct SplitFit {
  int n = 0;
  double mse = std::numeric_limits<double>::quiet_NaN();
  double r = std::numeric_limits<double>::quiet_NaN();
};

/// Result of one training run.
struct TrainSummary {
  TrainMethod method = TrainMethod::kLevenbergMarquardt;
  TrainTermination termination = TrainTermination::kMaxEpochs;
  std::string message;                                      ///< why it stopped, in words
  int epochs = 0;                                           ///< epochs run
  int best_epoch = 0;                                       ///< epoch of the returned weights
  SplitFit train, val, test, all;                           ///< of the returned weights
  double gradient = 0;                                      ///< ‖∇MSE‖ at the last epoch
  double mu = 0;                                            ///< μ at the last epoch
  double gamma = std::numeric_limits<double>::quiet_NaN();  ///< BR γ (effective parameters)
  double alpha = std::numeric_limits<double>::quiet_NaN();  ///< BR α
  double beta = std::numeric_limits<double>::quiet_NaN();   ///< BR β (per MSE)
  double ssw = 0;                                           ///< Σ w² of the returned weights
  double wall_time_s = 0;   ///< whole run, including the final evaluation [s]
  double cpu_time_s = 0;    ///< CPU time of the calling thread [s]
  double jtj_time_s = 0;    ///< wall time forming J, JᵀJ and Jᵀe [s]
  long jacobians = 0;       ///< JᵀJ formations (one per epoch plus the initial one)
  long solves = 0;          ///< Cholesky factorisations of the damped system
  long rejected_steps = 0;  ///< trial steps that did not lower the objective
  std::vector<EpochRecord> history;
  /// One line: method, termination, epochs, MSE per subset, R, gradient, μ (γ), time.
  std::string BriefReport() const;
};

/// Called after every epoch (and for epoch 0); never from another thread.
using EpochCallback = std::function<void(const EpochRecord&)>;

/// Trains net (maps configured, weights initialised) with MATLAB trainlm's algorithm. The
/// returned weights are set in net. Throws InputError if options, data or split are invalid, or
/// the network's input count does not match the data.
TrainSummary TrainLm(FeedForwardNet& net, const RegressionData& data, const DataSplit& split,
                     const LmOptions& options = {}, const EpochCallback& on_epoch = {});

/// Trains net with MATLAB trainbr's algorithm (see the file comment); as TrainLm otherwise.
TrainSummary TrainBr(FeedForwardNet& net, const RegressionData& data, const DataSplit& split,
                     const BrOptions& options = {}, const EpochCallback& on_epoch = {});

/// Forms JJ = JᵀJ/N (lower triangle), JE = Jᵀe/N and the MSE of net over the rows of normalised
/// inputs Xn (N × R) with targets t, J built block_rows rows at a time (one SYRK per block). The
/// trainers' per-epoch kernel, exposed for the benchmark.
class NormalEquations {
 public:
  NormalEquations(int block_rows, int num_params);
  /// JJ must be P × P (its upper triangle is left alone). Returns false if an error or a
  /// Jacobian entry is not finite.
  bool Form(const FeedForwardNet& net, const Eigen::Ref<const Eigen::MatrixXd>& Xn,
            const Eigen::Ref<const Eigen::VectorXd>& t, Eigen::MatrixXd& JJ, Eigen::VectorXd& JE,
            double& mse);

 private:
  Eigen::Index block_;
  Eigen::MatrixXd J_;
  Eigen::VectorXd y_;
};

/// One BR re-estimation step (exposed for tests): given JJ = JᵀJ/N (only the lower triangle is
/// read), the training MSE, Σw², N and the current α, β, returns γ, α_new, β_new.
struct BayesianEstimate {
  double gamma = 0;
  double alpha = 0;
  double beta = 0;
};
BayesianEstimate ReestimateBayesian(const Eigen::MatrixXd& JJ, double mse, double ssw, int n,
                                    double alpha, double beta);

/// The network, split and maps of a fit, all from one generator seeded with `seed`: the split is
/// drawn first (DivideRand), then the Nguyen–Widrow weights; both maps are fitted on all samples
/// (MATLAB's configure). Throws InputError on invalid data, shape or ratios.
struct FitSetup {
  FeedForwardNet net;
  DataSplit split;
};
FitSetup SetUpFit(const RegressionData& data, int hidden, const SplitRatios& ratios, uint64_t seed);

/// MSE and R of net on the given rows of data (n = 0 and NaN for an empty list).
SplitFit EvaluateFit(const FeedForwardNet& net, const RegressionData& data,
                     const std::vector<int>& rows);

}  // namespace pz::model
