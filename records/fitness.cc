#include "records/fitness.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "io/csv.h"
#include "model/format.h"
#include "records/nnls.h"
#include "records/spectrum_solve.h"

namespace pz::records {

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

}  // namespace pz::records
