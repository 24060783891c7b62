#include "model/lm_train.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <numeric>
#include <optional>
#include <sstream>

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include "model/dense_kernels.h"

namespace pz::model {

// ---------------------------------------------------------------------------------------------
// Data, split, options

Status RegressionData::Validate() const {
  if (t.size() < 3) return InvalidArgument(FieldError("samples", t.size(), "need at least 3"));
  if (x.rows() != t.size())
    return InvalidArgument(FieldError(
        "x rows", x.rows(), "must equal the number of targets (" + std::to_string(t.size()) + ")"));
  if (x.cols() < 1) return InvalidArgument(FieldError("x columns", x.cols(), "must be >= 1"));
  for (Eigen::Index i = 0; i < t.size(); ++i) {
    if (!std::isfinite(t(i)))
      return InvalidArgument(FieldError("t[" + std::to_string(i) + "]", t(i), "must be finite"));
    for (Eigen::Index k = 0; k < x.cols(); ++k)
      if (!std::isfinite(x(i, k)))
        return InvalidArgument(FieldError("x[" + std::to_string(i) + "][" + std::to_string(k) + "]",
                                          x(i, k), "must be finite"));
  }
  return Status::Ok();
}

Status DataSplit::Validate(int n) const {
  if (train.empty()) return InvalidArgument(FieldError("split.train size", 0, "must be > 0"));
  std::vector<char> used(static_cast<size_t>(std::max(n, 0)), 0);
  const std::pair<const char*, const std::vector<int>*> sets[] = {
      {"split.train", &train}, {"split.val", &val}, {"split.test", &test}};
  for (const auto& [name, rows] : sets) {
    for (size_t i = 0; i < rows->size(); ++i) {
      const int r = (*rows)[i];
      const std::string field = std::string(name) + "[" + std::to_string(i) + "]";
      if (r < 0 || r >= n)
        return InvalidArgument(FieldError(field, r, "must be in [0, " + std::to_string(n) + ")"));
      if (i > 0 && r <= (*rows)[i - 1])
        return InvalidArgument(FieldError(field, r, "must be ascending"));
      if (used[static_cast<size_t>(r)])
        return InvalidArgument(FieldError(field, r, "is in two subsets"));
      used[static_cast<size_t>(r)] = 1;
    }
  }
  return Status::Ok();
}

Status SplitRatios::Validate() const {
  const std::pair<const char*, double> r[] = {
      {"ratios.train", train}, {"ratios.val", val}, {"ratios.test", test}};
  for (const auto& [name, v] : r)
    if (!(std::isfinite(v) && v >= 0 && v <= 1))
      return InvalidArgument(FieldError(name, v, "must be in [0, 1]"));
  if (!(train > 0)) return InvalidArgument(FieldError("ratios.train", train, "must be > 0"));
  if (std::abs(train + val + test - 1.0) > 1e-9)
    return InvalidArgument(
        FieldError("ratios sum", train + val + test, "train + val + test must be 1"));
  return Status::Ok();
}

DataSplit DivideRand(int n, const SplitRatios& ratios, std::mt19937_64& rng) {
  ThrowIfError(ratios.Validate());
  if (n < 1) throw InputError(FieldError("samples", n, "must be >= 1"));
  std::vector<int> perm(static_cast<size_t>(n));
  std::iota(perm.begin(), perm.end(), 0);
  // Fisher–Yates with our own index draw (std::shuffle's use of the engine is unspecified, so it
  // would not give the same split on another standard library).
  for (int i = n - 1; i > 0; --i) {
    const uint64_t j = rng() % static_cast<uint64_t>(i + 1);
    std::swap(perm[static_cast<size_t>(i)], perm[static_cast<size_t>(j)]);
  }
  const int n_val = static_cast<int>(std::lround(ratios.val * n));
  const int n_test = static_cast<int>(std::lround(ratios.test * n));
  const int n_train = n - n_val - n_test;
  if (n_train < 1) throw InputError(FieldError("training samples", n_train, "must be >= 1"));
  DataSplit s;
  s.train.assign(perm.begin(), perm.begin() + n_train);
  s.val.assign(perm.begin() + n_train, perm.begin() + n_train + n_val);
  s.test.assign(perm.begin() + n_train + n_val, perm.end());
  std::sort(s.train.begin(), s.train.end());
  std::sort(s.val.begin(), s.val.end());
  std::sort(s.test.begin(), s.test.end());
  return s;
}

void PinToTraining(DataSplit& split, const std::vector<int>& rows, std::mt19937_64& rng) {
  auto contains = [](const std::vector<int>& v, int r) {
    return std::binary_search(v.begin(), v.end(), r);
  };
  for (int r : rows) {
    if (contains(split.train, r)) continue;
    std::vector<int>* from = contains(split.val, r)    ? &split.val
                             : contains(split.test, r) ? &split.test
                                                       : nullptr;
    if (from == nullptr) throw InputError(FieldError("pinned row", r, "is in no subset"));
    // A training sample that is not itself pinned takes r's place.
    std::vector<int> candidates;
    for (int t : split.train)
      if (std::find(rows.begin(), rows.end(), t) == rows.end()) candidates.push_back(t);
    if (candidates.empty())
      throw InputError(FieldError("pinned row", r, "no training sample to swap with"));
    const int swap = candidates[static_cast<size_t>(rng() % candidates.size())];
    split.train.erase(std::lower_bound(split.train.begin(), split.train.end(), swap));
    split.train.insert(std::lower_bound(split.train.begin(), split.train.end(), r), r);
    from->erase(std::lower_bound(from->begin(), from->end(), r));
    from->insert(std::lower_bound(from->begin(), from->end(), swap), swap);
  }
}

Status LmOptions::Validate() const {
  if (epochs < 0 || epochs > 1000000000)
    return InvalidArgument(FieldError("epochs", epochs, "must be in [0, 1e9]"));
  if (!(std::isfinite(goal) && goal >= 0))
    return InvalidArgument(FieldError("goal", goal, "must be finite and >= 0"));
  if (!(std::isfinite(min_grad) && min_grad >= 0))
    return InvalidArgument(FieldError("min_grad", min_grad, "must be finite and >= 0"));
  if (max_fail < 0)
    return InvalidArgument(FieldError("max_fail", max_fail, "must be >= 0 (0 disables)"));
  if (!(std::isfinite(mu) && mu > 0))
    return InvalidArgument(FieldError("mu", mu, "must be finite and > 0"));
  if (!(mu_dec > 0 && mu_dec < 1))
    return InvalidArgument(FieldError("mu_dec", mu_dec, "must be in (0, 1)"));
  if (!(std::isfinite(mu_inc) && mu_inc > 1))
    return InvalidArgument(FieldError("mu_inc", mu_inc, "must be finite and > 1"));
  if (!(std::isfinite(mu_max) && mu_max > mu))
    return InvalidArgument(
        FieldError("mu_max", mu_max, "must be finite and > mu (" + std::to_string(mu) + ")"));
  if (!(time_limit_s > 0))
    return InvalidArgument(FieldError("time_limit_s", time_limit_s, "must be > 0"));
  if (block_rows < 1 || block_rows > 1000000)
    return InvalidArgument(FieldError("block_rows", block_rows, "must be in [1, 1e6]"));
  return Status::Ok();
}

const char* TrainMethodName(TrainMethod m) {
  return m == TrainMethod::kBayesianRegularization ? "BR" : "LM";
}

const char* TrainTerminationName(TrainTermination t) {
  switch (t) {
    case TrainTermination::kMaxEpochs:
      return "max_epochs";
    case TrainTermination::kGoalMet:
      return "goal_met";
    case TrainTermination::kMinGradient:
      return "min_gradient";
    case TrainTermination::kMuMax:
      return "mu_max";
    case TrainTermination::kValidationStop:
      return "validation_stop";
    case TrainTermination::kTimeLimit:
      return "time_limit";
    case TrainTermination::kNonFinite:
      return "non_finite";
  }
  return "unknown";
}

namespace {
const char* TerminationMessage(TrainTermination t) {
  switch (t) {
    case TrainTermination::kMaxEpochs:
      return "maximum epoch reached";
    case TrainTermination::kGoalMet:
      return "performance goal met";
    case TrainTermination::kMinGradient:
      return "minimum gradient reached";
    case TrainTermination::kMuMax:
      return "maximum mu reached";
    case TrainTermination::kValidationStop:
      return "validation stop";
    case TrainTermination::kTimeLimit:
      return "maximum time elapsed";
    case TrainTermination::kNonFinite:
      return "the initial network gives a non-finite error or Jacobian";
  }
  return "unknown";
}
}  // namespace

std::string TrainSummary::BriefReport() const {
  std::ostringstream o;
  o.precision(4);
  o << TrainMethodName(method) << ": " << TrainTerminationName(termination) << " after " << epochs
    << " epochs (best " << best_epoch << "); MSE train " << train.mse << " val " << val.mse
    << " test " << test.mse << "; R " << all.r << "; gradient " << gradient << ", mu " << mu;
  if (method == TrainMethod::kBayesianRegularization) o << ", gamma " << gamma << ", ssw " << ssw;
  o << "; " << wall_time_s << " s (" << (epochs > 0 ? 1e3 * jtj_time_s / (epochs + 1) : 0.0)
    << " ms JtJ per epoch)";
  return o.str();
}

// ---------------------------------------------------------------------------------------------
// Evaluation helpers

namespace {

struct Subset {
  Eigen::MatrixXd xn;  // normalised inputs, rows = samples
  Eigen::VectorXd t;
  int n() const { return static_cast<int>(t.size()); }
};

Subset Gather(const Eigen::MatrixXd& xn, const Eigen::VectorXd& t, const std::vector<int>& rows) {
  Subset s;
  s.xn.resize(static_cast<Eigen::Index>(rows.size()), xn.cols());
  s.t.resize(static_cast<Eigen::Index>(rows.size()));
  for (size_t i = 0; i < rows.size(); ++i) {
    s.xn.row(static_cast<Eigen::Index>(i)) = xn.row(rows[i]);
    s.t(static_cast<Eigen::Index>(i)) = t(rows[i]);
  }
  return s;
}

double Mse(const FeedForwardNet& net, const Subset& s) {
  if (s.n() == 0) return std::numeric_limits<double>::quiet_NaN();
  return (net.PredictNormalised(s.xn) - s.t).squaredNorm() / s.n();
}

SplitFit FitOf(const Eigen::VectorXd& y, const Eigen::VectorXd& t) {
  SplitFit f;
  f.n = static_cast<int>(t.size());
  if (f.n == 0) return f;
  f.mse = (y - t).squaredNorm() / f.n;
  const Eigen::ArrayXd dy = y.array() - y.mean();
  const Eigen::ArrayXd dt = t.array() - t.mean();
  const double den = std::sqrt((dy * dy).sum() * (dt * dt).sum());
  f.r = den > 0 ? (dy * dt).sum() / den : std::numeric_limits<double>::quiet_NaN();
  return f;
}

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

using Clock = std::chrono::steady_clock;
double Since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Solves (scale·JJ + shift·I) δ = −rhs by Cholesky; false if the factorisation fails, is
// ill-conditioned (rcond < ε, MATLAB's singular-matrix warning) or δ is not finite.
bool DampedSolve(const Eigen::MatrixXd& JJ, double scale, double shift, const Eigen::VectorXd& rhs,
                 Eigen::MatrixXd& work, Eigen::VectorXd& delta) {
  const Eigen::Index p = JJ.rows();
  work.resize(p, p);
  work.triangularView<Eigen::Lower>() = scale * JJ;
  work.diagonal().array() += shift;
  double rcond = 0;
  if (!CholeskyLower(work, &rcond)) return false;
  if (!(rcond >= std::numeric_limits<double>::epsilon())) return false;
  delta = -rhs;
  CholeskySolve(work, delta);
  return delta.allFinite();
}

}  // namespace

NormalEquations::NormalEquations(int block_rows, int num_params)
    : block_(std::max(block_rows, 1)),
      J_(std::max(block_rows, 1), num_params),
      y_(std::max(block_rows, 1)) {}

bool NormalEquations::Form(const FeedForwardNet& net, const Eigen::Ref<const Eigen::MatrixXd>& Xn,
                           const Eigen::Ref<const Eigen::VectorXd>& t, Eigen::MatrixXd& JJ,
                           Eigen::VectorXd& JE, double& mse) {
  const Eigen::Index n = Xn.rows(), p = J_.cols();
  PZ_CHECK(t.size() == n && n > 0 && JJ.rows() == p && JJ.cols() == p && net.num_params() == p);
  JE.setZero(p);
  double sse = 0;
  for (Eigen::Index r0 = 0; r0 < n; r0 += block_) {
    const Eigen::Index m = std::min<Eigen::Index>(block_, n - r0);
    auto J = J_.topRows(m);
    auto y = y_.head(m);
    net.JacobianNormalised(Xn.middleRows(r0, m), y, J);
    y -= t.segment(r0, m);  // e = y − t
    SyrkTnLower(J, 1.0, r0 == 0 ? 0.0 : 1.0, JJ);
    JE.noalias() += J.transpose() * y;
    sse += y.squaredNorm();
  }
  const double inv_n = 1.0 / static_cast<double>(n);
  JJ.triangularView<Eigen::Lower>() = JJ * inv_n;
  JE *= inv_n;
  mse = sse * inv_n;
  return std::isfinite(mse) && JE.allFinite() &&
         JJ.triangularView<Eigen::Lower>().toDenseMatrix().allFinite();
}

BayesianEstimate ReestimateBayesian(const Eigen::MatrixXd& JJ, double mse, double ssw, int n,
                                    double alpha, double beta) {
  PZ_CHECK(JJ.rows() == JJ.cols());
  const Eigen::Index p = JJ.rows();
  Eigen::MatrixXd A(p, p);
  A.triangularView<Eigen::Lower>() = beta * JJ;
  A.diagonal().array() += alpha;
  double trace_inv = 0;
  if (CholeskyLower(A)) {
    trace_inv = CholeskyInverseTrace(A);
  } else {  // rare: β JJ swamps α numerically; use the spectrum (negative rounding clipped to 0)
    Eigen::MatrixXd S = JJ.selfadjointView<Eigen::Lower>();
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(S, Eigen::EigenvaluesOnly);
    for (Eigen::Index i = 0; i < p; ++i)
      trace_inv += 1.0 / (beta * std::max(0.0, es.eigenvalues()(i)) + alpha);
  }
  BayesianEstimate e;
  e.gamma = static_cast<double>(p) - alpha * trace_inv;
  e.alpha = ssw == 0 ? 1.0 : e.gamma / (2.0 * ssw);
  e.beta = mse == 0 ? 1.0 : (static_cast<double>(n) - e.gamma) / (2.0 * mse);
  return e;
}

SplitFit EvaluateFit(const FeedForwardNet& net, const RegressionData& data,
                     const std::vector<int>& rows) {
  if (rows.empty()) return {};
  Subset s = Gather(net.input_map().Apply(data.x), data.t, rows);
  return FitOf(net.PredictNormalised(s.xn), s.t);
}

FitSetup SetUpFit(const RegressionData& data, int hidden, const SplitRatios& ratios,
                  uint64_t seed) {
  ThrowIfError(data.Validate());
  ThrowIfError(ratios.Validate());
  FfnetShape shape;
  shape.inputs = static_cast<int>(data.x.cols());
  shape.hidden = hidden;
  ThrowIfError(shape.Validate());
  std::mt19937_64 rng(seed);
  FitSetup f{FeedForwardNet(shape), {}};
  f.split = DivideRand(data.size(), ratios, rng);
  f.net.ConfigureMaps(data.x, data.t);
  f.net.InitNguyenWidrow(rng);
  return f;
}

// ---------------------------------------------------------------------------------------------
// The Levenberg–Marquardt loop, plain (trainlm) or Bayesian-regularised (trainbr).

namespace {

/// The stopping criteria, in trainlm's order (none: another epoch).
std::optional<TrainTermination> StopReason(const LmOptions& opt, bool finite0, double mse,
                                           int epoch, double elapsed, double scaled_gradient,
                                           double mu, bool has_validation, int val_fail) {
  std::optional<TrainTermination> stop;
  if (!finite0)
    stop = TrainTermination::kNonFinite;
  else if (mse <= opt.goal)
    stop = TrainTermination::kGoalMet;
  else if (epoch >= opt.epochs)
    stop = TrainTermination::kMaxEpochs;
  else if (elapsed >= opt.time_limit_s)
    stop = TrainTermination::kTimeLimit;
  else if (scaled_gradient <= opt.min_grad)
    stop = TrainTermination::kMinGradient;
  else if (mu >= opt.mu_max)
    stop = TrainTermination::kMuMax;
  else if (opt.max_fail > 0 && has_validation && val_fail >= opt.max_fail)
    stop = TrainTermination::kValidationStop;
  return stop;
}

/// The weights of the lowest validation error so far, and the epochs since it last fell.
struct BestOnValidation {
  Eigen::VectorXd w;
  double vperf;
  int fails = 0;

  void Update(double v, const Eigen::VectorXd& w_now, int epoch, TrainSummary& sum) {
    if (v < vperf) {
      vperf = v;
      w = w_now;
      sum.best_epoch = epoch;
      fails = 0;
    } else if (v > vperf) {
      ++fails;
    }
  }
};

/// The solve's work space and the trial network of the damped steps.
struct DampedStepScratch {
  Eigen::MatrixXd work;
  Eigen::VectorXd delta, rhs;
  FeedForwardNet trial;
};

/// One epoch: damped Gauss–Newton steps until one lowers the objective (w, its ‖w‖², the
/// objective and the network then updated, μ decreased) or μ exceeds μ_max.
void DampedSteps(bool br, double alpha, double beta, const Eigen::MatrixXd& JJ,
                 const Eigen::VectorXd& JE, const Subset& tr, const LmOptions& opt,
                 DampedStepScratch& s, FeedForwardNet& net, Eigen::VectorXd& w, double& ssw,
                 double& perf, double& mu, TrainSummary& sum) {
  while (mu <= opt.mu_max) {
    ++sum.solves;
    bool ok;
    if (br) {
      s.rhs = beta * JE + alpha * w;
      ok = DampedSolve(JJ, beta, mu + alpha, s.rhs, s.work, s.delta);
    } else {
      ok = DampedSolve(JJ, 1.0, mu, JE, s.work, s.delta);
    }
    if (ok) {
      Eigen::VectorXd w2 = w + s.delta;
      if (w2.allFinite()) {
        s.trial.set_params(w2);
        const double mse2 = Mse(s.trial, tr);
        const double ssw2 = w2.squaredNorm();
        const double perf2 = br ? beta * mse2 + alpha * ssw2 : mse2;
        if (std::isfinite(perf2) && perf2 < perf) {
          w = std::move(w2);
          ssw = ssw2;
          perf = perf2;
          net.set_params(w);
          mu = std::max(mu * opt.mu_dec, 1e-20);
          break;
        }
      }
    }
    ++sum.rejected_steps;
    mu *= opt.mu_inc;
  }
}

/// The fits of the trained network on the training, validation and test rows and on every row.
void SetSplitFits(const FeedForwardNet& net, const Eigen::MatrixXd& xn, const RegressionData& data,
                  const DataSplit& split, TrainSummary& sum) {
  const Eigen::VectorXd y_all = net.PredictNormalised(xn);
  auto fit_rows = [&](const std::vector<int>& rows) {
    Eigen::VectorXd y(static_cast<Eigen::Index>(rows.size())), t(y.size());
    for (size_t i = 0; i < rows.size(); ++i) {
      y(static_cast<Eigen::Index>(i)) = y_all(rows[i]);
      t(static_cast<Eigen::Index>(i)) = data.t(rows[i]);
    }
    return FitOf(y, t);
  };
  sum.train = fit_rows(split.train);
  sum.val = fit_rows(split.val);
  sum.test = fit_rows(split.test);
  sum.all = FitOf(y_all, data.t);
}

TrainSummary Train(TrainMethod method, FeedForwardNet& net, const RegressionData& data,
                   const DataSplit& split, const LmOptions& opt, const EpochCallback& on_epoch) {
  const auto t0 = Clock::now();
  const double cpu0 = ThreadCpuSeconds();
  ThrowIfError(opt.Validate());
  ThrowIfError(data.Validate());
  ThrowIfError(split.Validate(data.size()));
  if (data.x.cols() != net.inputs())
    throw InputError(
        FieldError("data inputs", data.x.cols(),
                   "must equal the network's inputs (" + std::to_string(net.inputs()) + ")"));
  const bool br = method == TrainMethod::kBayesianRegularization;
  const Eigen::MatrixXd xn = net.input_map().Apply(data.x);
  const Subset tr = Gather(xn, data.t, split.train);
  const Subset va = Gather(xn, data.t, split.val);
  const Subset te = Gather(xn, data.t, split.test);
  const int P = net.num_params();
  const int N = tr.n();
  const bool track_best = va.n() > 0 && (!br || opt.max_fail > 0);
  const bool need_test = opt.keep_history || static_cast<bool>(on_epoch);
  // ‖∇MSE‖ in normalised target units is gain² times the one in target units (e and J both scale
  // with the gain of the output map).
  const double out_gain = net.output_map().gain(0);
  const double min_grad_scale = opt.min_grad_normalised ? out_gain * out_gain : 1.0;

  TrainSummary sum;
  sum.method = method;
  NormalEquations ne(std::min(opt.block_rows, std::max(N, 1)), P);
  Eigen::MatrixXd JJ(P, P);
  Eigen::VectorXd JE(P);
  Eigen::VectorXd w = net.params();
  DampedStepScratch scratch{Eigen::MatrixXd(P, P), Eigen::VectorXd(P), Eigen::VectorXd(P), net};
  double mse = 0;

  auto form = [&](const FeedForwardNet& at) {
    const auto tj = Clock::now();
    const bool ok = ne.Form(at, tr.xn, tr.t, JJ, JE, mse);
    sum.jtj_time_s += Since(tj);
    ++sum.jacobians;
    return ok;
  };
  const bool finite0 = form(net);
  double gradient = 2.0 * JE.norm();
  double mu = opt.mu;
  double vperf = Mse(net, va);
  double tperf = need_test ? Mse(net, te) : std::numeric_limits<double>::quiet_NaN();
  double ssw = w.squaredNorm();
  double gamma = std::numeric_limits<double>::quiet_NaN(), alpha = gamma, beta = gamma;
  double perf = mse;  // objective the steps must lower (F for BR)
  if (br) {
    gamma = P;
    beta = mse == 0 ? 1.0 : (N - gamma) / (2.0 * mse);
    if (beta <= 0) beta = 1.0;
    alpha = ssw == 0 ? 1.0 : gamma / (2.0 * ssw);
    perf = beta * mse + alpha * ssw;
  }
  BestOnValidation best{w, vperf};
  int epoch = 0;

  for (;;) {
    const double elapsed = Since(t0);
    EpochRecord rec{epoch, elapsed, mse, vperf, tperf, mu, gradient, gamma, ssw, best.fails};
    if (opt.keep_history) sum.history.push_back(rec);
    if (on_epoch) on_epoch(rec);

    // Stopping criteria, in trainlm's order.
    const std::optional<TrainTermination> stop = StopReason(
        opt, finite0, mse, epoch, elapsed, gradient * min_grad_scale, mu, va.n() > 0, best.fails);
    if (stop) {
      sum.termination = *stop;
      sum.message = TerminationMessage(*stop);
      break;
    }

    // One epoch: damped Gauss–Newton steps until one lowers the objective or μ exceeds μ_max.
    DampedSteps(br, alpha, beta, JJ, JE, tr, opt, scratch, net, w, ssw, perf, mu, sum);
    ++epoch;
    form(net);
    gradient = 2.0 * JE.norm();
    if (br && mu <= opt.mu_max) {
      const BayesianEstimate e = ReestimateBayesian(JJ, mse, ssw, N, alpha, beta);
      gamma = e.gamma;
      alpha = e.alpha;
      beta = e.beta;
      perf = beta * mse + alpha * ssw;
    } else if (!br) {
      perf = mse;
    }
    vperf = Mse(net, va);
    if (need_test) tperf = Mse(net, te);
    if (track_best) best.Update(vperf, w, epoch, sum);
  }

  if (track_best) {
    net.set_params(best.w);
  } else {
    sum.best_epoch = epoch;
  }
  sum.epochs = epoch;
  sum.gradient = gradient;
  sum.mu = mu;
  sum.gamma = gamma;
  sum.alpha = alpha;
  sum.beta = beta;
  sum.ssw = net.params().squaredNorm();
  SetSplitFits(net, xn, data, split, sum);
  sum.wall_time_s = Since(t0);
  sum.cpu_time_s = ThreadCpuSeconds() - cpu0;
  return sum;
}

}  // namespace

TrainSummary TrainLm(FeedForwardNet& net, const RegressionData& data, const DataSplit& split,
                     const LmOptions& options, const EpochCallback& on_epoch) {
  return Train(TrainMethod::kLevenbergMarquardt, net, data, split, options, on_epoch);
}

TrainSummary TrainBr(FeedForwardNet& net, const RegressionData& data, const DataSplit& split,
                     const BrOptions& options, const EpochCallback& on_epoch) {
  return Train(TrainMethod::kBayesianRegularization, net, data, split, options, on_epoch);
}

}  // namespace pz::model
