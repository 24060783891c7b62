#include "records/fit.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <tuple>

#include "io/csv.h"
#include "model/format.h"
#include "opt/thread_pool_evaluator.h"
#include "records/excitation.h"
#include "records/nnls.h"
#include "records/preisach_family.h"
#include "records/resonance.h"
#include "records/spectrum_solve.h"

namespace pz::records {

Eigen::VectorXd NonNegativeLeastSquares(const Eigen::MatrixXd& G, const Eigen::VectorXd& h) {
  const Eigen::Index n = h.size();
  Eigen::VectorXd w = Eigen::VectorXd::Zero(n);
  std::vector<char> passive(static_cast<size_t>(n), 0);
  const double tol = 1e-12 * std::max(1.0, G.diagonal().cwiseAbs().maxCoeff()) *
                     std::max(1.0, h.cwiseAbs().maxCoeff());
  auto solve_passive = [&](Eigen::VectorXd& s) {
    std::vector<Eigen::Index> idx;
    for (Eigen::Index i = 0; i < n; ++i)
      if (passive[static_cast<size_t>(i)]) idx.push_back(i);
    const Eigen::Index m = static_cast<Eigen::Index>(idx.size());
    Eigen::MatrixXd Gp(m, m);
    Eigen::VectorXd hp(m);
    for (Eigen::Index a = 0; a < m; ++a) {
      hp(a) = h(idx[static_cast<size_t>(a)]);
      for (Eigen::Index b = 0; b < m; ++b)
        Gp(a, b) = G(idx[static_cast<size_t>(a)], idx[static_cast<size_t>(b)]);
    }
    // A tiny ridge keeps nearly collinear plays solvable.
    Gp.diagonal().array() += 1e-13 * std::max(1.0, Gp.diagonal().maxCoeff());
    const Eigen::VectorXd sp = Gp.ldlt().solve(hp);
    s.setZero(n);
    for (Eigen::Index a = 0; a < m; ++a) s(idx[static_cast<size_t>(a)]) = sp(a);
  };
  for (int outer = 0; outer < 3 * n + 10; ++outer) {
    const Eigen::Index best = EnteringVariable(h - G * w, passive, tol);
    if (best < 0) break;
    passive[static_cast<size_t>(best)] = 1;
    for (int inner = 0; inner < 3 * n + 10; ++inner) {
      Eigen::VectorXd s;
      solve_passive(s);
      bool feasible = true;
      for (Eigen::Index i = 0; i < n; ++i)
        if (passive[static_cast<size_t>(i)] && s(i) <= 0) feasible = false;
      if (feasible) {
        w = s;
        break;
      }
      double alpha = 1;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (passive[static_cast<size_t>(i)] && s(i) <= 0)
          alpha = std::min(alpha, w(i) / (w(i) - s(i)));
      }
      w += alpha * (s - w);
      for (Eigen::Index i = 0; i < n; ++i) {
        if (passive[static_cast<size_t>(i)] &&
            w(i) <= 1e-15 * std::max(1.0, w.cwiseAbs().maxCoeff())) {
          passive[static_cast<size_t>(i)] = 0;
          w(i) = 0;
        }
      }
    }
  }
  return w;
}

RecordFitness::RecordFitness(const RecordModel& model, std::vector<const io::Record*> records,
                             double penalty, std::span<const double> validate_at)
    : model_(model), records_(std::move(records)), penalty_(penalty) {
  if (records_.empty()) throw InputError("no training records to fit on");
  if (!(std::isfinite(penalty_) && penalty_ > 0))
    throw InputError(FieldError("penalty", penalty_, "must be finite and > 0"));
  for (const io::Record* r : records_) {
    samples_ += r->scored();
    try {
      prepared_.push_back(model_.Prepare(*r, r->end_scored));
    } catch (const InputError& e) {
      throw InputError(r->Label() + ": " + e.what());
    }
  }
  const Family& fam = model_.family();
  fam.CheckTraining(records_);
  // A regularised linear family: its strength chosen by validation with the effects at their
  // neutral values (records/regularisation.h), re-chosen at a fit's solution (FitModel); every
  // evaluation uses the strength of the moment.
  // With several candidate penalties, the validation keeps one too (records/regularisation.h
  // ChoosePenalty).
  const std::vector<Family::Penalty> penalties =
      fam.linear() ? fam.regularisation() : std::vector<Family::Penalty>{};
  if (!penalties.empty()) {
    const auto m = static_cast<Eigen::Index>(fam.regressors());
    for (const Family::Penalty& pen : penalties) {
      if (pen.gram.size() != fam.regressors() * fam.regressors())
        throw InputError(fam.name() + ": regularisation size mismatch (" + pen.name + ")");
      penalties_.push_back(
          Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
              pen.gram.data(), m, m));
      penalty_names_.push_back(pen.name);
    }
    if (!validate_at.empty() && validate_at.size() != model_.params().size())
      throw InputError("RecordFitness: " + std::to_string(validate_at.size()) +
                       " parameters to validate at, " + std::to_string(model_.params().size()) +
                       " expected");
    validation_ =
        ValidateAt(validate_at.empty() ? std::span<const double>(NeutralParams()) : validate_at);
    regularisation_ = penalties_[validation_.penalty];
  }
  if (fam.linear() && fam.regressors() >= static_cast<size_t>(kIncrementalNnlsFrom)) {
    const std::vector<double> w = SolveWeights(NeutralParams());  // from no start
    weights_start_ =
        Eigen::Map<const Eigen::VectorXd>(w.data(), static_cast<Eigen::Index>(w.size()));
  }
  std::tie(spectrum_first_, spectrum_count_) =
      model_.EffectParams(EffectKind::Named("creep-spectrum"));
  if (spectrum_count_ > 0) {
    spectrum_roughness_ = SpectrumRoughness(spectrum_count_);
    spectrum_validation_.used = true;  // μ = 0 until RevalidateSpectrum
  }
  spectrum_solved_ = SpectrumSolved(model_);
  searched_ = SearchedParams(model_);
  if (spectrum_solved_) {  // the reference every evaluation's solve starts from: both starts, once
    const SpectrumSolution s = SolveSpectrum(SpectrumProblemNow(), NeutralParams());
    if (s.ok) {
      spectrum_start_ = s.w;
      spectrum_start_theta_ = s.theta;
      spectrum_metric_ = std::make_shared<const SpectrumMetric>(
          BuildSpectrumMetric(SpectrumProblemNow(), NeutralParams(), spectrum_start_));
    }
  }
}

std::vector<double> RecordFitness::NeutralParams() const {
  std::vector<double> p(model_.family_param_count(), 0.0);
  for (size_t i = model_.family_param_count(); i < model_.params().size(); ++i) {
    const ParamInfo& q = model_.params()[i];
    p.push_back(q.lower <= 0 && q.upper >= 0 ? 0.0 : q.lower);
  }
  return p;
}

SpectrumProblem RecordFitness::SpectrumProblemNow() const {
  SpectrumProblem sp;
  sp.model = &model_;
  sp.records = records_;
  sp.samples = samples_;
  sp.first = spectrum_first_;
  sp.count = spectrum_count_;
  sp.regularisation = validation_.used ? &regularisation_ : nullptr;
  sp.lambda = validation_.used ? validation_.lambda : 0;
  sp.roughness = &spectrum_roughness_;
  sp.mu = spectrum_validation_.lambda;
  sp.start = spectrum_start_;
  sp.start_theta = spectrum_start_theta_;
  sp.metric = spectrum_metric_.get();
  return sp;
}

std::vector<double> RecordFitness::Expand(std::span<const double> q, double* cost) const {
  if (q.size() != searched_.size())
    throw InputError(model_.Describe() + ": " + std::to_string(q.size()) +
                     " searched parameters given, " + std::to_string(searched_.size()) +
                     " expected");
  std::vector<double> p(model_.params().size(), 0.0);
  for (size_t i = 0; i < q.size(); ++i) p[searched_[i]] = q[i];
  if (!spectrum_solved_) {
    if (cost) *cost = Run(p).mse + SpectrumPenalty(p) / static_cast<double>(samples_);
    return p;
  }
  const SpectrumSolution s = SolveSpectrum(SpectrumProblemNow(), p);
  for (size_t i = 0; i < spectrum_count_; ++i) p[spectrum_first_ + i] = s.w[i];
  if (cost)
    *cost = s.ok ? (s.sse + s.roughness) / static_cast<double>(samples_)
                 : std::numeric_limits<double>::infinity();
  return p;
}

namespace {

// The creep spectrum's rule: the strongest roughness penalty whose CV RMSE is within one standard
// error or 1 % of the best's. On a periodic training record every block sees the same excitation,
// so the blocks agree on a small, consistent gain of a ragged spectrum (its fast relaxations
// shaping the loop and standing in for the lag) that only extrapolation shows to be wrong.
constexpr StrengthRule kSpectrumRule{.contiguous = false, .rmse_tolerance = 0.01};

}  // namespace

double RecordFitness::SpectrumPenalty(std::span<const double> p) const {
  if (spectrum_count_ == 0 || spectrum_validation_.lambda == 0) return 0;
  const Eigen::Map<const Eigen::VectorXd> w(p.data() + spectrum_first_,
                                            static_cast<Eigen::Index>(spectrum_count_));
  return spectrum_validation_.lambda * (spectrum_roughness_ * w).squaredNorm();
}

bool RecordFitness::RevalidateSpectrum(std::span<const double> p0, const opt::ParameterMap& map,
                                       int threads) {
  if (spectrum_count_ == 0) return false;
  const size_t P = model_.params().size(), n = spectrum_count_;
  if (p0.size() != P || static_cast<size_t>(map.size()) != P)
    throw InputError("RevalidateSpectrum: parameter count mismatch");
  // The output's Jacobian over the training records' scored samples (a column of zeros — an
  // evaluation that failed, or a parameter the output does not see — is left out).
  const opt::ResidualFunction outputs = [&](std::span<const double> p, std::vector<double>& y) {
    const Output o = Run(p);
    y.clear();
    y.reserve(samples_);
    for (size_t i = 0; i < records_.size(); ++i)
      for (size_t k = records_[i]->first_scored; k < records_[i]->end_scored; ++k)
        y.push_back(o.yhat[i][k]);
    return std::isfinite(o.mse);
  };
  std::vector<double> y0;
  if (!outputs(p0, y0)) return false;
  const auto N = static_cast<Eigen::Index>(samples_);
  Eigen::MatrixXd J;
  std::vector<double> scale;
  opt::ScaledJacobian(map, outputs, p0, y0, 1e-4, std::max(1, threads), J, scale);
  std::vector<char> ok(P, 1);
  for (size_t c = 0; c < P; ++c) {
    const auto col = static_cast<Eigen::Index>(c);
    J.col(col) /= scale[c];
    ok[c] = J.col(col).squaredNorm() > 0;
  }
  // A Jacobian of no column (every perturbed evaluation failed: the bimorph fin on issue 37's
  // random records) or one that overflowed has no strength to choose: the strength stays (Eigen's
  // decomposition of the 0 × 0 covariance below crashed).
  if (!J.allFinite() || std::none_of(ok.begin(), ok.end(), [](char c) { return c != 0; }))
    return false;
  // Unknowns: the spectrum's weights (≥ 0), then every other parameter as a difference of two
  // non-negative ones (free); target t = r + J p₀, r = y − ŷ.
  std::vector<Eigen::Index> cols;  // column of J of each unknown, its sign
  std::vector<double> sign;
  for (size_t i = 0; i < n; ++i) {
    cols.push_back(static_cast<Eigen::Index>(spectrum_first_ + i));
    sign.push_back(1);
  }
  for (size_t c = 0; c < P; ++c) {
    if (c >= spectrum_first_ && c < spectrum_first_ + n) continue;
    if (!ok[c]) continue;
    for (double sg : {1.0, -1.0}) {
      cols.push_back(static_cast<Eigen::Index>(c));
      sign.push_back(sg);
    }
  }
  {  // each weight's standard error from the data alone (the unpenalised linearisation)
    std::vector<Eigen::Index> used;
    for (size_t c = 0; c < P; ++c)
      if (ok[c]) used.push_back(static_cast<Eigen::Index>(c));
    Eigen::MatrixXd Ju(N, static_cast<Eigen::Index>(used.size()));
    for (size_t j = 0; j < used.size(); ++j) Ju.col(static_cast<Eigen::Index>(j)) = J.col(used[j]);
    double sse = 0;
    size_t idx = 0;
    for (const io::Record* r : records_)
      for (size_t k = r->first_scored; k < r->end_scored; ++k, ++idx)
        sse += (r->y[k] - y0[idx]) * (r->y[k] - y0[idx]);
    const double dof =
        std::max<double>(1, static_cast<double>(samples_) - static_cast<double>(used.size()));
    const Eigen::MatrixXd cov =
        (Ju.transpose() * Ju).completeOrthogonalDecomposition().pseudoInverse() * (sse / dof);
    spectrum_sigma_.assign(n, std::numeric_limits<double>::infinity());
    for (size_t j = 0; j < used.size(); ++j) {
      const auto c = static_cast<size_t>(used[j]);
      if (c >= spectrum_first_ && c < spectrum_first_ + n)
        spectrum_sigma_[c - spectrum_first_] = std::sqrt(
            std::max(0.0, cov(static_cast<Eigen::Index>(j), static_cast<Eigen::Index>(j))));
    }
  }
  const auto m = static_cast<Eigen::Index>(cols.size());
  Eigen::MatrixXd A(N, m);
  for (Eigen::Index j = 0; j < m; ++j)
    A.col(j) = sign[static_cast<size_t>(j)] * J.col(cols[static_cast<size_t>(j)]);
  const Eigen::Map<const Eigen::VectorXd> x0(p0.data(), static_cast<Eigen::Index>(P));
  Eigen::VectorXd t = J * x0;
  {
    size_t idx = 0;
    for (const io::Record* r : records_)
      for (size_t k = r->first_scored; k < r->end_scored; ++k, ++idx)
        t(static_cast<Eigen::Index>(idx)) += r->y[k] - y0[idx];
  }
  const size_t K = kValidationBlocks;
  BlockedNormalEquations eq{std::vector<Eigen::MatrixXd>(K), std::vector<Eigen::VectorXd>(K),
                            std::vector<double>(K), std::vector<size_t>(K)};
  for (size_t b = 0; b < K; ++b) {
    const auto from =
        static_cast<Eigen::Index>((b * samples_ + K - 1) / K);  // first index with index·K/N = b
    const auto to = static_cast<Eigen::Index>(((b + 1) * samples_ + K - 1) / K);
    const auto rows = A.middleRows(from, to - from);
    const auto tb = t.segment(from, to - from);
    eq.G[b] = rows.transpose() * rows;
    eq.h[b] = rows.transpose() * tb;
    eq.bb[b] = tb.squaredNorm();
    eq.samples[b] = static_cast<size_t>(to - from);
  }
  Eigen::MatrixXd R = Eigen::MatrixXd::Zero(m, m);
  const auto nn = static_cast<Eigen::Index>(n);
  R.topLeftCorner(nn, nn) = spectrum_roughness_.transpose() * spectrum_roughness_;
  double trG = 0;
  for (size_t b = 0; b < K; ++b) trG += eq.G[b].topLeftCorner(nn, nn).trace();
  const double trR = R.trace();
  WeightValidation v = ChooseStrength(eq, R, trR > 0 ? trG / trR : 0, kSpectrumRule);
  const bool changed = v.lambda != spectrum_validation_.lambda;
  spectrum_validation_ = std::move(v);
  return changed;
}

WeightValidation RecordFitness::ValidateAt(std::span<const double> p) const {
  const size_t K = kValidationBlocks;
  BlockedNormalEquations eq{std::vector<Eigen::MatrixXd>(K), std::vector<Eigen::VectorXd>(K),
                            std::vector<double>(K), std::vector<size_t>(K)};
  Accumulate(p, eq);
  return ChoosePenalty(eq, penalties_, penalty_names_);
}

bool RecordFitness::Revalidate(std::span<const double> params) {
  if (!validation_.used) return false;
  WeightValidation v = ValidateAt(params);
  const bool changed = v.relative != validation_.relative || v.penalty != validation_.penalty;
  validation_ = std::move(v);
  regularisation_ = penalties_[validation_.penalty];
  return changed;
}

void RecordFitness::Accumulate(std::span<const double> p, BlockedNormalEquations& eq,
                               std::vector<std::vector<double>>* regs) const {
  const Family& fam = model_.family();
  const size_t m = fam.regressors(), nf = model_.family_param_count();
  const int pol = model_.scale().polarity;
  NormalEquationsBuilder builder(eq, m, samples_);
  std::vector<double> ue;
  const bool linear_output = model_.has_linear_output_effects();
  // The regressors of a record: the caller's (kept for the output) or this thread's scratch; the
  // family writes every entry.
  thread_local std::vector<double> scratch;
  const bool keep = regs != nullptr && !linear_output;
  if (keep) regs->resize(records_.size());  // their buffers reused from call to call
  for (size_t ri = 0; ri < records_.size(); ++ri) {
    const io::Record* r = records_[ri];
    const size_t from = SimulatedFrom(*r, r->end_scored);
    model_.EffectiveDrive(*r, p.subspan(nf), from, r->end_scored, ue);
    if (keep) (*regs)[ri].clear();  // none kept unless formed below
    // Rows with structure (the Preisach grid): their normal equations without the rows.
    if (!linear_output && fam.AddNormalEquations(*r, from, ue, pol, builder)) continue;
    std::vector<double>& reg = keep ? (*regs)[ri] : scratch;
    reg.resize(ue.size() * m);
    fam.Regressors(ue, reg);
    if (linear_output) {  // creep-spectrum: on each regressor, so the weights are solved for its
                          // output
      model_.ApplyLinearOutputEffects(*r, p.subspan(nf), from, reg, m);
    }
    AddRecordRows(*r, from, reg, m, pol, builder);
  }
  builder.Finish();
}

double RecordCentre(const io::Record& r, size_t from, std::span<const double> reg, size_t m,
                    std::vector<double>& c) {
  auto row = [&](size_t k) { return reg.data() + RegressorRow(k, from) * m; };
  double d = 0;
  c.assign(m, 0.0);
  if (r.offset_mode == io::OffsetMode::kFit) {
    for (size_t k = r.first_scored; k < r.end_scored; ++k) {
      for (size_t j = 0; j < m; ++j) c[j] += row(k)[j];
      d += r.y[k];
    }
    for (double& v : c) v /= static_cast<double>(r.scored());
    d /= static_cast<double>(r.scored());
  } else if (r.offset_mode == io::OffsetMode::kRest) {
    std::copy_n(row(0), m, c.begin());
    d = r.offset;
  } else {
    d = r.offset;
  }
  return d;
}

void AddRecordRows(const io::Record& r, size_t from, std::span<const double> reg, size_t m, int pol,
                   NormalEquationsBuilder& builder) {
  auto row = [&](size_t k) { return reg.data() + RegressorRow(k, from) * m; };
  thread_local std::vector<double> c;
  const double d = RecordCentre(r, from, reg, m, c);
  for (size_t k = r.first_scored; k < r.end_scored; ++k) {
    double* out = builder.Row();
    for (size_t j = 0; j < m; ++j) out[j] = pol * (row(k)[j] - c[j]);
    builder.Add(r.y[k] - d);
  }
}

std::vector<double> RecordFitness::SolveWeights(std::span<const double> p,
                                                std::vector<std::vector<double>>* regs) const {
  BlockedNormalEquations eq{{Eigen::MatrixXd()}, {Eigen::VectorXd()}, {0.0}, {0}};
  Accumulate(p, eq, regs);
  if (validation_.used) eq.G[0] += validation_.lambda * regularisation_;
  // Many unknowns: from the weights at the neutral parameters (records/nnls.h; a fixed start, so
  // the result does not depend on the order of the evaluations).
  const Eigen::VectorXd w = eq.G[0].rows() >= kIncrementalNnlsFrom
                                ? NonNegativeLeastSquaresFrom(eq.G[0], eq.h[0], weights_start_)
                                : NonNegativeLeastSquares(eq.G[0], eq.h[0]);
  return std::vector<double>(w.data(), w.data() + w.size());
}

namespace {

// A record's model output y (from the model's Simulate: ŷ without polarity and offset, and its rest
// output) with polarity and the record's offset applied in place; its squared errors over the
// scored window added to sse in sample order — Run's and EvaluateMany's one arithmetic.
double ScoreRecord(const io::Record& r, int polarity, double rest_output, std::span<double> y,
                   double& sse) {
  const double rest = polarity * rest_output;
  for (double& v : y) v *= polarity;
  const double o = RecordOffset(r, y, rest);
  for (double& v : y) v += o;
  for (size_t k = r.first_scored; k < r.end_scored; ++k) {
    const double e = r.y[k] - y[k];
    sse += e * e;
  }
  return o;
}

}  // namespace

double RecordFitness::ResidualWeight() const {
  return model_.family().sums_errors() ? 1.0 : 1 / std::sqrt(static_cast<double>(samples_));
}

double RecordFitness::MeanSquare(double sse) const {
  if (model_.family().sums_errors())
    return std::isfinite(sse) ? sse : std::numeric_limits<double>::infinity();
  return std::isfinite(sse) ? sse / static_cast<double>(samples_)
                            : std::numeric_limits<double>::infinity();
}

opt::FitnessResult RecordFitness::Cost(double mse, std::span<const double> params) const {
  if (!std::isfinite(mse)) return {penalty_, opt::FitnessStatus::kPenalized, "diverged"};
  const double rough = SpectrumPenalty(params);
  return {rough > 0 ? mse + rough / static_cast<double>(samples_) : mse, opt::FitnessStatus::kOk,
          ""};
}

RecordFitness::Output RecordFitness::Run(std::span<const double> params, bool keep_outputs) const {
  Output out;
  // A linear family: the regressors of the weights' solve give the output too (RecordModel::
  // LinearOutput, Simulate's arithmetic), unless a linear output effect was applied to them.
  thread_local std::vector<std::vector<double>> regs;
  const bool kept = model_.family().linear() && !model_.has_linear_output_effects();
  if (model_.family().linear()) out.weights = SolveWeights(params, &regs);
  double sse = 0;
  for (size_t i = 0; i < records_.size(); ++i) {
    const io::Record* r = records_[i];
    // Every sample of [0, end_scored) is written by Simulate / LinearOutput; a search's evaluation
    // (keep_outputs = false) simulates into a buffer kept per thread.
    thread_local std::vector<double> buffer;
    std::vector<double> own;
    std::vector<double>& y = keep_outputs ? own : buffer;
    y.resize(r->end_scored);
    // (A family that sums its rows itself kept none: simulated.)
    const double rest =
        !kept || regs[i].empty()
            ? model_.Simulate(*r, params, out.weights, r->end_scored, y, prepared_[i].get())
            : model_.LinearOutput(*r, params, out.weights, r->end_scored, regs[i], y);
    out.offsets.push_back(ScoreRecord(*r, model_.scale().polarity, rest, y, sse));
    if (keep_outputs) out.yhat.push_back(std::move(own));
  }
  out.mse = MeanSquare(sse);
  return out;
}

void RecordFitness::RunMany(std::span<const std::span<const double>> ps, std::span<Output> out,
                            bool keep_outputs) const {
  const size_t L = ps.size();
  bool direct = lanes() > 1 && L > 1;
  for (const std::span<const double> p : ps) direct = direct && p.size() == model_.params().size();
  if (!direct) {
    for (size_t l = 0; l < L; ++l) out[l] = Run(ps[l], keep_outputs);
    return;
  }
  // Run's arithmetic for every vector, the simulations side by side (RecordModel::SimulateMany:
  // each its own drive and output effects).
  std::vector<double> sse(L, 0.0), rest(L);
  std::vector<std::span<double>> ys(L);
  thread_local std::vector<std::vector<double>>
      buffers;  // keep_outputs = false: as Run's, one per lane
  if (buffers.size() < L) buffers.resize(L);
  for (size_t l = 0; l < L; ++l) out[l] = Output{};
  for (size_t i = 0; i < records_.size(); ++i) {
    const io::Record* r = records_[i];
    for (size_t l = 0; l < L; ++l) {  // every sample of [0, end_scored) is written by SimulateMany
      if (keep_outputs) {
        ys[l] = out[l].yhat.emplace_back(r->end_scored);
      } else {
        buffers[l].resize(r->end_scored);
        ys[l] = buffers[l];
      }
    }
    model_.SimulateMany(*r, ps, r->end_scored, ys, rest, prepared_[i].get());
    for (size_t l = 0; l < L; ++l)
      out[l].offsets.push_back(ScoreRecord(*r, model_.scale().polarity, rest[l], ys[l], sse[l]));
  }
  for (size_t l = 0; l < L; ++l) out[l].mse = MeanSquare(sse[l]);
}

opt::FitnessResult RecordFitness::Evaluate(const opt::Genome& genome) const {
  if (spectrum_solved_ &&
      genome.reals.size() == searched_.size()) {  // the spectrum solved, not searched
    double cost = 0;
    Expand(genome.reals, &cost);
    if (!std::isfinite(cost)) return {penalty_, opt::FitnessStatus::kPenalized, "diverged"};
    return {cost, opt::FitnessStatus::kOk, ""};
  }
  return Cost(Run(genome.reals, /*keep_outputs=*/false).mse, genome.reals);
}

int RecordFitness::lanes() const {
  const Family& fam = model_.family();
  return fam.linear() ? 1 : std::max(1, fam.lanes());
}

namespace {

/// The genomes' parameter vectors.
std::vector<std::span<const double>> Reals(std::span<const opt::Genome* const> genomes) {
  std::vector<std::span<const double>> ps;
  for (const opt::Genome* g : genomes) ps.push_back(g->reals);
  return ps;
}

}  // namespace

void RecordFitness::EvaluateMany(std::span<const opt::Genome* const> genomes,
                                 std::span<opt::FitnessResult> out) const {
  if (lanes() == 1)
    return FitnessFunction::EvaluateMany(genomes, out);  // Evaluate each (a solved spectrum too)
  const std::vector<std::span<const double>> ps = Reals(genomes);
  std::vector<Output> o(ps.size());
  RunMany(ps, o, /*keep_outputs=*/false);
  for (size_t l = 0; l < ps.size(); ++l) out[l] = Cost(o[l].mse, ps[l]);
}

bool RecordFitness::Residuals(std::span<const double> searched_or_all,
                              std::vector<double>& r) const {
  std::vector<double> expanded;
  if (spectrum_solved_ && searched_or_all.size() == searched_.size())
    expanded = Expand(searched_or_all);
  const std::span<const double> params =
      expanded.empty() ? searched_or_all : std::span<const double>(expanded);
  return ResidualsOf(Run(params), params, r);
}

void RecordFitness::ResidualsMany(std::span<const std::span<const double>> ps,
                                  std::span<std::vector<double>> rs, std::span<bool> ok) const {
  if (lanes() == 1) {  // Residuals each (a solved spectrum's vectors expanded there)
    for (size_t l = 0; l < ps.size(); ++l) ok[l] = Residuals(ps[l], rs[l]);
    return;
  }
  std::vector<Output> o(ps.size());
  RunMany(ps, o);
  for (size_t l = 0; l < ps.size(); ++l) ok[l] = ResidualsOf(o[l], ps[l], rs[l]);
}

bool RecordFitness::ResidualsOf(const Output& o, std::span<const double> params,
                                std::vector<double>& r) const {
  if (!std::isfinite(o.mse)) return false;
  r.clear();
  r.reserve(samples_);
  const double s = ResidualWeight();
  for (size_t i = 0; i < records_.size(); ++i) {
    const io::Record& rec = *records_[i];
    for (size_t k = rec.first_scored; k < rec.end_scored; ++k)
      r.push_back((rec.y[k] - o.yhat[i][k]) * s);
  }
  if (spectrum_count_ > 0 && spectrum_validation_.lambda > 0) {  // the roughness penalty's rows
    const Eigen::Map<const Eigen::VectorXd> w(params.data() + spectrum_first_,
                                              static_cast<Eigen::Index>(spectrum_count_));
    const Eigen::VectorXd d = spectrum_roughness_ * w;
    const double f = std::sqrt(spectrum_validation_.lambda) * s;
    for (Eigen::Index i = 0; i < d.size(); ++i) r.push_back(f * d(i));
  }
  return true;
}

RecordMetrics Evaluate(const RecordModel& model, std::span<const double> params,
                       std::span<const double> weights, const io::Record& r,
                       std::vector<double>* yhat_out) {
  std::vector<double> y(r.end_scored);
  const double rest = model.scale().polarity * model.Simulate(r, params, weights, r.end_scored, y);
  for (double& v : y) v *= model.scale().polarity;
  const double o = RecordOffset(r, y, rest);
  for (double& v : y) v += o;
  RecordMetrics m;
  m.name = r.name;
  m.role = r.role;
  m.samples = r.scored();
  m.offset = o;
  double sse = 0, lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (size_t k = r.first_scored; k < r.end_scored; ++k) {
    const double e = r.y[k] - y[k];
    sse += e * e;
    if (std::abs(e) > m.max_abs) {
      m.max_abs = std::abs(e);
      m.max_at_s = r.t[k];
    }
    lo = std::min(lo, r.y[k]);
    hi = std::max(hi, r.y[k]);
  }
  if (!std::isfinite(sse)) m.max_abs = std::numeric_limits<double>::infinity();
  m.sse = sse;
  m.rmse = std::sqrt(sse / static_cast<double>(m.samples));
  m.range = hi - lo;
  m.nrmse_pct = m.range > 0 ? 100 * m.rmse / m.range : std::numeric_limits<double>::infinity();
  if (yhat_out) *yhat_out = std::move(y);
  return m;
}

namespace {

// A residual vector's result: cost Σ r²; the penalty, "diverged", when the output is not finite.
opt::FitnessResult ResidualResult(bool ok, std::vector<double> residuals) {
  if (!ok) return {opt::kDefaultErrorCost, opt::FitnessStatus::kPenalized, "diverged"};
  opt::FitnessResult out;
  out.residuals = std::move(residuals);
  for (double e : out.residuals) out.cost += e * e;
  return out;
}

}  // namespace

opt::FitnessResult RecordResidualFitness::Evaluate(const opt::Genome& genome) const {
  std::vector<double> r;
  const bool ok = fitness_.Residuals(genome.reals, r);
  return ResidualResult(ok, std::move(r));
}

void RecordResidualFitness::EvaluateMany(std::span<const opt::Genome* const> genomes,
                                         std::span<opt::FitnessResult> out) const {
  std::vector<std::vector<double>> rs(genomes.size());
  const std::unique_ptr<bool[]> ok(new bool[genomes.size()]);
  fitness_.ResidualsMany(Reals(genomes), rs, std::span<bool>(ok.get(), genomes.size()));
  for (size_t l = 0; l < genomes.size(); ++l) out[l] = ResidualResult(ok[l], std::move(rs[l]));
}

RecordMap::RecordMap(const RecordModel& model)
    : params_(model.params()), forms_(model.search_forms()) {
  for (size_t i = 0; i < params_.size(); ++i) {
    const ParamInfo& p = params_[i];
    if (!(p.lower < p.upper) || (p.log_scale && !(p.lower > 0)))
      throw InputError(FieldError(
          p.name + " box", "[" + io::FormatNumber(p.lower) + ", " + io::FormatNumber(p.upper) + "]",
          "must be lower < upper (lower > 0 on a log scale)"));
    const int r = forms_[i].ratio_of;
    if (r >= 0 && (static_cast<size_t>(r) >= params_.size() || static_cast<size_t>(r) == i ||
                   forms_[static_cast<size_t>(r)].ratio_of >= 0))
      throw InputError(p.name + ": searched as a ratio of parameter " + std::to_string(r) +
                       ", which is not a plain parameter of the model");
  }
}

double UnitCoordinate(double lower, double upper, bool log_scale, double x) {
  double u;
  if (log_scale) {
    u = std::log(std::max(x, lower) / lower) / std::log(upper / lower);
  } else {
    u = (x - lower) / (upper - lower);
  }
  return std::clamp(u, 0.0, 1.0);
}

double PhysicalCoordinate(double lower, double upper, bool log_scale, double u) {
  u = std::clamp(u, 0.0, 1.0);
  if (log_scale) return lower * std::exp(u * std::log(upper / lower));
  return lower + u * (upper - lower);
}

namespace {

double UnitOf(const ParamInfo& s, double x) {
  return UnitCoordinate(s.lower, s.upper, s.log_scale, x);
}

double PhysicalOf(const ParamInfo& s, double u) {
  return PhysicalCoordinate(s.lower, s.upper, s.log_scale, u);
}

}  // namespace

std::vector<double> RecordMap::ToPhysical(std::span<const double> unit) const {
  if (unit.size() != params_.size())
    throw InputError(
        FieldError("unit point size", unit.size(), "must be " + std::to_string(params_.size())));
  std::vector<double> x(params_.size());
  for (size_t i = 0; i < x.size(); ++i) x[i] = PhysicalOf(params_[i], unit[i]);
  for (size_t i = 0; i < x.size(); ++i)
    if (forms_[i].ratio_of >= 0) x[i] = x[i] * x[static_cast<size_t>(forms_[i].ratio_of)];
  return x;
}

std::vector<double> RecordMap::ToUnit(std::span<const double> physical) const {
  if (physical.size() != params_.size())
    throw InputError(FieldError("physical point size", physical.size(),
                                "must be " + std::to_string(params_.size())));
  std::vector<double> u(params_.size());
  for (size_t i = 0; i < u.size(); ++i) {
    double x = physical[i];
    if (const int r = forms_[i].ratio_of; r >= 0) {
      const double d = physical[static_cast<size_t>(r)];
      x = d > 0 ? physical[i] / d : 0.0;
    }
    u[i] = UnitOf(params_[i], x);
  }
  return u;
}

void RecordMap::Bounds(std::span<const double> x, int i, double* lower, double* upper) const {
  const ParamInfo& p = params_[static_cast<size_t>(i)];
  const int r = forms_[static_cast<size_t>(i)].ratio_of;
  *lower = r >= 0 ? p.lower * x[static_cast<size_t>(r)] : p.lower;
  *upper = r >= 0 ? p.upper * x[static_cast<size_t>(r)] : p.upper;
}

double RecordMap::Scale(std::span<const double> x, int i) const {
  const ParamInfo& p = params_[static_cast<size_t>(i)];
  if (forms_[static_cast<size_t>(i)].scale > 0) return forms_[static_cast<size_t>(i)].scale;
  if (p.log_scale)
    return std::max(x[static_cast<size_t>(i)], p.lower) * std::log(p.upper / p.lower);
  return p.upper - p.lower;
}

SearchBudget SizedSearchBudget(size_t searched) {
  const int d = static_cast<int>(std::clamp<size_t>(searched, 1, 100));
  SearchBudget b;
  b.particles = std::min(30, 10 + 5 * (d - 1));
  b.iterations = std::min(150, 30 + 30 * (d - 1));
  b.stall = std::min(40, 10 * d);
  b.repetitions = d <= 2 ? 2 : 3;
  b.converged_spread = 1e-3;
  return b;
}

SearchBudget BudgetOf(const opt::SearchOptions& s) {
  return {s.pso.particles, s.pso.iterations, s.pso.stall_iterations, s.repetitions,
          s.pso.converged_spread};
}

std::string SearchBudget::Describe() const {
  std::string s = "PSO " + std::to_string(particles) + " particles × ≤ " +
                  std::to_string(iterations) + " iterations, stall " + std::to_string(stall);
  if (converged_spread > 0) s += ", converged at a spread of " + io::FormatNumber(converged_spread);
  return s + ", " + std::to_string(repetitions) +
         (repetitions == 1 ? " repetition" : " repetitions");
}

namespace {

/// The box of every parameter (or only the searched ones) and their units.
opt::ParamBox BoxOf(const std::vector<ParamInfo>& params, const std::vector<size_t>& searched,
                    bool only_searched, std::vector<std::string>& units) {
  opt::ParamBox box;
  units.clear();
  for (size_t i = 0; i < params.size(); ++i) {
    if (only_searched && std::find(searched.begin(), searched.end(), i) == searched.end()) continue;
    const ParamInfo& p = params[i];
    box.names.push_back(p.name);
    box.lower.push_back(p.lower);
    box.upper.push_back(p.upper);
    box.log_scale.push_back(p.log_scale);
    units.push_back(p.unit);
  }
  return box;
}

/// The search's budget sized to the number of searched parameters (one: the line search) unless
/// the user kept it; a line-search budget refused for another search.
void SizeSearch(const FitOptions::Sizing& k, size_t n_searched, opt::SearchOptions& so,
                FitResult& res) {
  if (k.enabled && so.algorithm == opt::SearchAlgorithm::kPso) {
    if (n_searched == 1 && !k.keep_algorithm && !k.keep_particles && !k.keep_iterations &&
        !k.keep_stall && !k.keep_repetitions) {
      so.algorithm = opt::SearchAlgorithm::kLine;  // one bounded scalar: a grid, then Brent
      so.repetitions = 1;
    } else {
      const SearchBudget b = SizedSearchBudget(n_searched);
      if (!k.keep_particles) so.pso.particles = b.particles;
      if (!k.keep_iterations) so.pso.iterations = b.iterations;
      if (!k.keep_stall) so.pso.stall_iterations = b.stall;
      if (!k.keep_repetitions) so.repetitions = b.repetitions;
      so.pso.converged_spread = b.converged_spread;
    }
    res.budget_sized = true;
  } else if (so.algorithm == opt::SearchAlgorithm::kLine && !k.keep_repetitions) {
    so.repetitions = 1;  // asked for by name: its one repetition
  }
  if (k.line_given && so.algorithm != opt::SearchAlgorithm::kLine)
    throw InputError(
        "--line-grid / --line-brackets / --line-tolerance: the line search's budget, for a "
        "search of one parameter with the sized budget; this fit searches " +
        std::to_string(n_searched) + " parameter" + (n_searched == 1 ? "" : "s") + " by " +
        opt::SearchAlgorithmName(so.algorithm) +
        (n_searched == 1 ? " (--algorithm or a PSO budget flag was given)" : ""));
}

/// Progress every 25 iterations of the search (or steps of the line search).
void SetProgress(const FitOptions& options, opt::SearchOptions& so) {
  const bool line = so.algorithm == opt::SearchAlgorithm::kLine;
  const int grid = so.line.grid;
  so.on_progress = [&options, line, grid](const opt::SearchProgress& p) {
    if (p.iteration % 25 != 0) return;
    const std::string where = !line ? "search repetition " + std::to_string(p.repetition) +
                                          " iteration " + std::to_string(p.iteration)
                              : p.iteration == 0
                                  ? "line search, the grid of " + std::to_string(grid)
                                  : "line search, Brent step " + std::to_string(p.iteration);
    options.progress(where + ": best MSE " + io::FormatNumber(p.overall_best_cost));
  };
}

bool HasBeamEffect(const RecordModel& model) {
  for (EffectKind e : model.effects())
    if (!e.none() && e->stage() == model::EffectStage::kBeam) return true;
  return false;
}

/// The fin's starts of a beam model (FitOptions::beam): polish_from with the last effect's
/// magnitude at each fraction of its range's upper end (either sign: the first fraction on each
/// side). Empty when that effect has no magnitude.
std::vector<std::vector<double>> BeamStarts(const FitOptions& o, const RecordModel& model) {
  if (o.beam.lm_iterations < 1)
    throw InputError(FieldError("beam.lm_iterations", o.beam.lm_iterations, "must be >= 1"));
  if (o.beam.start_fractions.empty())
    throw InputError("beam.start_fractions: needs at least one entry");
  for (double f : o.beam.start_fractions)
    if (!(f > 0 && f <= 1))
      throw InputError(FieldError("beam.start_fractions[]", f, "must be in (0, 1]"));
  const EffectKind last = model.effects().back();
  const int mp = model::GetEffectInfo(last).magnitude_param;
  if (mp < 0) return {};
  const size_t mag = model.EffectParams(last).first + static_cast<size_t>(mp);
  const ParamInfo& s = model.params()[mag];
  const bool both_signs = s.lower < 0 && s.upper > 0;
  std::vector<std::vector<double>> starts;
  for (size_t j = 0; j < o.beam.start_fractions.size(); ++j) {
    const double f = both_signs ? o.beam.start_fractions[0] : o.beam.start_fractions[j];
    std::vector<double> x = o.polish_from;
    x[mag] = both_signs && j % 2 == 1 ? f * s.lower : f * s.upper;
    starts.push_back(std::move(x));
  }
  return starts;
}

/// Hands an evaluator the physical values of the unit genomes of a map whose genomes are unit
/// coordinates (RecordMap): what the records fitness takes.
class PhysicalGenomes final : public opt::BatchEvaluator {
 public:
  PhysicalGenomes(std::unique_ptr<opt::BatchEvaluator> inner, const opt::ParameterMap& map)
      : inner_(std::move(inner)), map_(map) {}
  void Evaluate(const opt::EvalBatch& batch, std::span<opt::FitnessResult> out) override {
    std::vector<opt::Genome> g(batch.genomes.size());
    for (size_t i = 0; i < g.size(); ++i) g[i].reals = map_.ToPhysical(batch.genomes[i].reals);
    opt::EvalBatch b = batch;
    b.genomes = g;
    inner_->Evaluate(b, out);
  }
  int concurrency() const override { return inner_->concurrency(); }

 private:
  std::unique_ptr<opt::BatchEvaluator> inner_;
  const opt::ParameterMap& map_;
};

/// The map of the searched parameters: a model with search forms (a ratio: bimorph-fin's bench
/// form) the RecordMap, whose genomes are unit coordinates; else their box (null: none).
std::unique_ptr<opt::ParameterMap> SearchedMap(const RecordModel& model,
                                               const std::vector<size_t>& searched,
                                               const opt::ParamBox& search_box,
                                               const std::vector<std::string>& units) {
  if (model.has_ratio()) {
    if (searched.size() != model.params().size())
      throw InputError(model.Describe() +
                       ": a parameter searched as a ratio needs every parameter searched (no "
                       "solved weights)");
    return std::make_unique<RecordMap>(model);
  }
  if (search_box.size() == 0) return nullptr;
  return std::make_unique<opt::BoxMap>(search_box, units);
}

/// The evaluator as the map's genomes need it: handed physical values where they are unit
/// coordinates.
std::unique_ptr<opt::BatchEvaluator> Physical(std::unique_ptr<opt::BatchEvaluator> e,
                                              const opt::ParameterMap* map) {
  if (map == nullptr || map->physical_genomes()) return e;
  return std::make_unique<PhysicalGenomes>(std::move(e), *map);
}

/// The starts given: a polish from physical values (no search), and extra starts in unit
/// coordinates of every parameter; both reduced to the searched parameters.
void AddStarts(const FitOptions& options, const RecordModel& model,
               const std::vector<size_t>& searched, const opt::ParameterMap* searched_map,
               opt::FitOptions& fo, FitResult& res) {
  const size_t n_params = model.params().size();
  // Physical points of every parameter, reduced to the searched ones, in unit coordinates.
  auto unit = [&](const std::vector<double>& x, const std::string& what) {
    if (x.size() != n_params)
      throw InputError(FieldError(what, x.size(), "must have one value per parameter"));
    std::vector<double> sp;
    for (size_t i : searched) sp.push_back(x[i]);
    return searched_map->ToUnit(sp);
  };
  if (!options.polish_from.empty()) {  // no search: the polish from these physical values
    if (options.polish_from.size() != n_params)
      throw InputError(FieldError("polish_from", options.polish_from.size(),
                                  "must have one value per parameter"));
    fo.search = false;
    if (searched_map) fo.starts = {unit(options.polish_from, "polish_from")};
    if (searched_map && HasBeamEffect(model)) {  // the fin's refinement of a CVODE model
      std::vector<std::vector<double>> starts = BeamStarts(options, model);
      if (!starts.empty()) fo.starts.clear();
      for (size_t j = 0; j < starts.size(); ++j)
        fo.starts.push_back(unit(starts[j], "beam start " + std::to_string(j)));
      fo.lm.max_iterations = options.beam.lm_iterations;
      fo.lm.central = false;  // forward differences: half the CVODE runs per Jacobian
      res.lm_differences = fo.lm.central_to_finish ? "forward-central" : "forward";
    }
  }
  if (searched_map) {
    for (size_t j = 0; j < options.seed_points.size(); ++j)
      fo.search_options.seeds.push_back(
          unit(options.seed_points[j], "seed_points[" + std::to_string(j) + "]"));
    for (size_t j = 0; j < options.start_points.size(); ++j)
      fo.starts.push_back(unit(options.start_points[j], "start_points[" + std::to_string(j) + "]"));
  }
  for (const std::vector<double>& u :
       options.extra_starts) {  // unit coordinates of every parameter
    if (u.size() != n_params)
      throw InputError(FieldError("extra_starts", u.size(), "must have one value per parameter"));
    std::vector<double> su;
    for (size_t i : searched) su.push_back(u[i]);
    fo.starts.push_back(std::move(su));
  }
}

/// Every vector the search tried diverged (each cost the penalty), so the best is one of them: a
/// named error, not metrics and a fit.json of NaN.
[[noreturn]] void ThrowDiverged(const RecordModel& model,
                                const std::vector<const io::Record*>& train, int64_t evaluations) {
  std::string names;
  for (const io::Record* r : train) names += (names.empty() ? "" : ", ") + r->name;
  throw InputError(
      model.Describe() + ": the model's output on the training records (" + names +
      ") is not finite at any of the " + std::to_string(evaluations) +
      " parameter vectors evaluated in the search box (every simulation diverged): try more "
      "integration sub-steps (--substeps), a smoother drive, or another family");
}

/// The polish's options; the LM's differences forward, central to finish after a search, unless
/// the user chose.
void SetPolish(const FitOptions& options, opt::FitOptions& fo, FitResult& res) {
  fo.polish = options.polish;
  fo.lm = options.lm;
  if (options.lm_differences_auto) {
    fo.lm.central = false;
    fo.lm.central_to_finish = fo.search_options.algorithm != opt::SearchAlgorithm::kLine;
  }
  res.lm_differences = fo.lm.central             ? "central"
                       : fo.lm.central_to_finish ? "forward-central"
                                                 : "forward";
}

/// The search and polish's figures into the result; the best searched parameters returned.
std::vector<double> TakeFit(opt::FitResult fit, FitResult& res) {
  res.search = std::move(fit.search);
  res.evaluations = fit.evaluations;
  res.lm_iterations = fit.lm_iterations;
  res.stop_reason = res.search.stop_reason;
  res.polishes = fit.polishes;
  res.best_polish_repetition = fit.best_polish_repetition;
  res.polish_message = fit.message;
  res.uncertainty = std::move(fit.uncertainty);
  return std::move(fit.x);
}

/// A model with `resonance` (records/resonance.h): the mode placed where the training residual of
/// the fit without it (its share at zero), or a rest's ringing, shows a dominant band, polished
/// from there at share ½ and 1 besides the fit's best; the better training cost kept.
void RestartAtMode(const RecordModel& model, const RecordFitness& fitness,
                   const std::vector<const io::Record*>& train, const opt::ParameterMap& map,
                   const opt::FitProblem& problem, const opt::FitOptions& fo,
                   std::vector<double>& best_searched, FitResult& res) {
  const auto [first, count] = model.EffectParams(EffectKind::Named("resonance"));
  if (count != 3) return;
  const bool solved = fitness.spectrum_solved();
  const std::vector<double> full = solved ? fitness.Expand(best_searched) : best_searched;
  std::vector<double> without = full;
  without[first] = 0;
  const auto& box = model.params();
  const std::optional<ModeStart> start =
      FindModeStart(train, fitness.Run(without).yhat, box[first + 1].lower);
  if (!start) return;
  const model::SpectralBand& b = start->band;
  opt::FitOptions again = fo;
  again.search = false;
  again.starts = {map.ToUnit(best_searched)};
  for (double share : {0.5, 1.0}) {
    std::vector<double> x = full;
    x[first] = share;
    x[first + 1] = std::clamp(b.f_peak, box[first + 1].lower, box[first + 1].upper);
    x[first + 2] = std::clamp(b.zeta, box[first + 2].lower, box[first + 2].upper);
    std::vector<double> xs;
    for (size_t i : fitness.searched()) xs.push_back(x[i]);
    again.starts.push_back(map.ToUnit(xs));
  }
  opt::FitResult second = opt::Fit(problem, again);
  res.evaluations += second.evaluations;
  res.lm_iterations += second.lm_iterations;
  res.polishes += second.polishes;
  auto mse = [&](const std::vector<double>& xs) {
    return fitness.Run(solved ? fitness.Expand(xs) : xs, false).mse;
  };
  const bool kept = mse(second.x) < mse(best_searched);
  res.mode_start = "f_n " + FormatG(b.f_peak, 4) + " Hz, zeta " + FormatG(b.zeta, 2) + " from " +
                   start->source + " (band " + FormatG(b.f_lo, 3) + "-" + FormatG(b.f_hi, 3) +
                   " Hz, " + FormatG(100 * b.share, 3) + " % of its power)" +
                   (kept ? "" : "; the search's own fit was better");
  if (!kept) return;
  best_searched = std::move(second.x);
  res.uncertainty = std::move(second.uncertainty);
}

}  // namespace

namespace {

/// Every record of the set evaluated with the fit: its metrics and output.
void EvaluateEvery(const io::RecordSet& set, FitResult& res) {
  for (const io::Record& r : set.records) {
    std::vector<double> y;
    res.metrics.push_back(Evaluate(*res.model, res.params, res.weights, r, &y));
    res.yhat.push_back(std::move(y));
  }
}

}  // namespace

FitResult FitModel(const io::RecordSet& set, std::shared_ptr<RecordModel> model,
                   const FitOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  auto train = set.WithRole(model::CaseRole::kTrain);
  if (train.empty()) throw InputError(set.source.string() + ": no record has the role 'train'");
  if (options.threads < 1) throw InputError(FieldError("threads", options.threads, "must be >= 1"));
  if (const std::string e = RateCoverageError(set, model->effects()); !e.empty())
    throw InputError(e);
  RecordFitness fitness(*model, train);
  FitResult res;
  res.model = model;
  const auto& params = model->params();
  // Searched: the model's parameters (a linear family's weights are solved, not among them; with
  // the creep spectrum, its weights neither: records/spectrum_solve.h).
  const std::vector<size_t>& searched = fitness.searched();
  const bool solved = fitness.spectrum_solved();
  std::vector<double> best;  // every parameter
  if (!params.empty()) {
    std::vector<std::string> units;
    const opt::BoxMap map(BoxOf(params, searched, false, units), units);
    const opt::ParamBox search_box = BoxOf(params, searched, true, units);
    const std::unique_ptr<opt::ParameterMap> searched_map =
        SearchedMap(*model, searched, search_box, units);
    const opt::ParameterMap* m = searched_map.get();
    const RecordResidualFitness residual_fitness(fitness);
    opt::FitProblem problem;
    problem.map = m;
    // The factory's evaluators (the service's workers) rebuild the fitness as constructed: once a
    // revalidation below has changed its strengths, the polishes under them run here.
    bool revalidated = false;
    problem.cost_evaluator = [&]() -> std::unique_ptr<opt::BatchEvaluator> {
      if (options.evaluator_factory && !revalidated)
        return Physical(options.evaluator_factory(fitness, RecordEvaluation::kCost), m);
      return Physical(std::make_unique<opt::ThreadPoolEvaluator>(fitness, options.threads), m);
    };
    problem.residual_evaluator = [&]() -> std::unique_ptr<opt::BatchEvaluator> {
      if (options.evaluator_factory && !revalidated)
        return Physical(options.evaluator_factory(fitness, RecordEvaluation::kResiduals), m);
      return Physical(std::make_unique<opt::ThreadPoolEvaluator>(residual_fitness, options.threads),
                      m);
    };
    problem.physical_residuals = [&](std::span<const double> x, std::vector<double>& r) {
      return fitness.Residuals(x, r);
    };
    problem.residual_weight = fitness.ResidualWeight();
    opt::FitOptions fo;
    fo.search_options = options.search;
    res.searched_parameters = searched.size();
    res.spectrum_solved = solved;
    res.solved_parameters = params.size() - searched.size();  // the spectrum's weights where solved
    const FitOptions::Sizing& k = options.sizing;
    opt::SearchOptions& so = fo.search_options;
    SizeSearch(k, searched.size(), so, res);
    res.algorithm = so.algorithm;
    res.line = so.line;
    res.budget = BudgetOf(fo.search_options);
    fo.polish_repetitions =
        options.polish_repetitions ? std::max(0, fo.search_options.repetitions - 1) : 0;
    fo.concurrent_polishes =
        true;  // each polish its own ThreadPoolEvaluator over the const fitness
    if (options.progress) SetProgress(options, fo.search_options);
    SetPolish(options, fo, res);
    AddStarts(options, *model, searched, m, fo, res);
    fo.search_cost_is_sum_of_squares = true;  // the search's cost is the MSE = Σ r²
    // With the spectrum solved, the table covers every parameter (below), not the searched ones.
    fo.uncertainty = options.uncertainty && !solved;
    fo.uncertainty_fd_step = options.lm.fd_step;
    fo.threads = options.threads;
    std::vector<double> best_searched;
    if (searched_map) {
      best_searched = TakeFit(opt::Fit(problem, fo), res);
      if (options.polish && options.polish_from.empty())
        RestartAtMode(*model, fitness, train, *m, problem, fo, best_searched, res);
    }
    best = solved ? fitness.Expand(best_searched) : best_searched;
    // A regularised linear family with effects: its strength was chosen with the effects at their
    // neutral values; re-chosen at the solution, and where it changes the solution is polished
    // again under the new strength (locally: a polish, no search). A creep spectrum's roughness
    // penalty likewise (searched without it): chosen at the solution, polished under it (where
    // the spectrum is solved: solved again under it), and chosen once more at the result.
    const bool spectrum = fitness.spectrum_validation().used && options.spectrum_roughness;
    for (int round = 0; round < (spectrum ? 2 : 1) && options.polish; ++round) {
      bool changed = false;
      if (fitness.validation().used && model->params().size() > model->family_param_count())
        changed = fitness.Revalidate(best);
      if (spectrum) changed = fitness.RevalidateSpectrum(best, map, options.threads) || changed;
      if (!changed) break;
      revalidated = true;
      if (searched_map) {
        opt::FitOptions again = fo;
        again.search = false;
        again.starts = {m->ToUnit(best_searched)};
        opt::FitResult second = opt::Fit(problem, again);
        res.evaluations += second.evaluations;
        res.lm_iterations += second.lm_iterations;
        res.polishes += second.polishes;
        if (!solved) res.uncertainty = std::move(second.uncertainty);
        best_searched = std::move(second.x);
      }
      best = solved ? fitness.Expand(best_searched) : best_searched;
    }
    if (solved && options.uncertainty)
      res.uncertainty =
          opt::ComputeUncertainty(map, problem.physical_residuals, best, options.threads,
                                  options.lm.fd_step, problem.residual_weight);
  }
  const RecordFitness::Output out = fitness.Run(best);
  if (!std::isfinite(out.mse)) ThrowDiverged(*model, train, res.evaluations);
  res.params = best;
  res.weights = out.weights;
  res.regularisation = fitness.validation();
  res.spectrum_regularisation = fitness.spectrum_validation();
  res.spectrum_sigma = fitness.spectrum_sigma();
  const double n = static_cast<double>(fitness.samples());
  res.train_mse = model->family().sums_errors() ? out.mse / n : out.mse;
  res.train_sse = model->family().sums_errors() ? out.mse : out.mse * n;
  EvaluateEvery(set, res);
  res.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return res;
}

std::string FitResult::SpectrumIdentification() const {
  const auto [first, count] = model->EffectParams(EffectKind::Named("creep-spectrum"));
  if (count == 0 || spectrum_sigma.size() != count) return "";
  double mean = 0;
  for (size_t i = 0; i < count; ++i) mean += params[first + i] / static_cast<double>(count);
  std::vector<size_t> loose;
  for (size_t i = 0; i < count; ++i)
    if (!(spectrum_sigma[i] <= mean)) loose.push_back(i);
  if (loose.empty()) return "";
  const auto& box = model->params();
  std::string names, sigmas;
  for (size_t i : loose) {
    names += (names.empty() ? "" : ", ") + box[first + i].name;
    sigmas += (sigmas.empty() ? "" : ", ") + FormatG(spectrum_sigma[i], 2);
  }
  return "the training excitation does not identify the creep spectrum's " + names + " (σ " +
         sigmas + " from the training records alone, above the mean fitted weight " +
         FormatG(mean, 2) +
         "): the roughness penalty holds them to their neighbours, and what they add to a withheld "
         "prediction "
         "is extrapolated (fast relaxations need steps and holds at several amplitudes in the "
         "training drive, "
         "slow ones a record several times longer than their time)";
}

namespace {

/// FitRecords for preisach at kAutoLevels: the effects searched on the coarsest grid, the levels
/// chosen at them (FitPreisachLevels), the chosen grid's weights solved there.
FitResult FitPreisachAuto(const io::RecordSet& set, const DataScale& scale,
                          const FitOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const std::vector<const io::Record*> train = set.WithRole(model::CaseRole::kTrain);
  const std::vector<int>& levels = PreisachLevelCandidates();
  FitResult base;
  if (!options.effects.empty()) {
    FitOptions o = options;
    o.family_options.pi_operators = levels.front();
    base = FitRecords(set, o);
  }
  const PreisachLevelFits fits =
      FitPreisachLevels(train, scale, options.family_options, options.effects, base.params, levels);
  const size_t c = fits.choice.chosen;
  FitResult r;
  if (!options.effects.empty() && levels[c] == levels.front()) {
    r = std::move(base);
  } else {
    // The chosen grid: its weights at the coarse fit's effects (no search, no polish), every record
    // evaluated with the whole model.
    FamilyOptions fo = options.family_options;
    fo.pi_operators = levels[c];
    r = std::move(base);
    r.model = std::make_shared<RecordModel>(MakeFamily(options.family, scale, fo), options.effects,
                                            scale);
    if (r.params.empty()) r.params.assign(r.model->params().size(), 0.0);
    r.weights = fits.fitness[c]->Run(fits.params, false).weights;
    r.regularisation = fits.fitness[c]->validation();
    EvaluateResolved(set, r);
  }
  r.resolution = fits.choice;
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return r;
}

}  // namespace

void EvaluateResolved(const io::RecordSet& set, FitResult& r) {
  r.metrics.clear();
  r.yhat.clear();
  double sse = 0;
  size_t n = 0;
  for (const io::Record& rec : set.records) {
    std::vector<double> y;
    r.metrics.push_back(Evaluate(*r.model, r.params, r.weights, rec, &y));
    r.yhat.push_back(std::move(y));
    if (rec.role == model::CaseRole::kTrain) {
      sse += r.metrics.back().rmse * r.metrics.back().rmse *
             static_cast<double>(r.metrics.back().samples);
      n += r.metrics.back().samples;
    }
  }
  r.train_sse = sse;
  r.train_mse = n > 0 ? sse / static_cast<double>(n) : 0;
  r.uncertainty = {};  // the coarse grid's: not this model's
}

FitResult FitRecords(const io::RecordSet& set, const FitOptions& options) {
  const DataScale scale = MeasureScale(set.WithRole(model::CaseRole::kTrain));
  if (options.family == "preisach" && options.family_options.pi_operators == kAutoLevels)
    return FitPreisachAuto(set, scale, options);
  std::shared_ptr<const Family> fam = MakeFamily(options.family, scale, options.family_options);
  auto model = std::make_shared<RecordModel>(fam, options.effects, scale);
  return FitModel(set, model, options);
}

}  // namespace pz::records
