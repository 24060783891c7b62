#include "records/spectrum_solve.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "model/effect_library.h"
#include "model/status.h"
#include "records/nnls.h"
#include "records/record_rows.h"

namespace pz::records {
namespace {

using Eigen::Index;

/// One training record: its regressors (rows of samples from.., row-major), what its offset mode
/// removes from the output, and its scored targets t = y − d.
struct RecordRows {
  const io::Record* r = nullptr;
  size_t from = 0, rows = 0;
  std::vector<double> reg;
  Eigen::VectorXd t;
  Eigen::MatrixXd
      C;  ///< scored rows of pol · (L_w A − centre), at the w of the last normal equations
  std::vector<double> a, c;  ///< each relaxation's discretisation at the record's dt
};

/// L_w on every column of a record's regressors at once (rows in the inner loop, so the columns
/// vectorise): the creep spectrum's ApplyOutput arithmetic on each column, out = L_w reg.
void FilterRows(const RecordRows& d, const Eigen::VectorXd& w, size_t m, std::vector<double>& out,
                std::vector<double>& state) {
  const size_t n = d.a.size();
  out.resize(d.reg.size());
  state.assign((n + 2) * m, 0.0);  // x_i (n × m), prev, corr
  double* prev = state.data() + n * m;
  double* corr = prev + m;
  const double* row0 = d.reg.data();
  std::copy_n(row0, m, out.data());
  for (size_t k = 1; k < d.rows; ++k) {
    const double* row = d.reg.data() + k * m;
    double* o = out.data() + k * m;
    std::fill_n(corr, m, 0.0);
    for (size_t i = 0; i < n; ++i) {
      double* x = state.data() + i * m;
      const double a = d.a[i], b = 1 - d.a[i], c = d.c[i], wi = w(static_cast<Index>(i));
      for (size_t j = 0; j < m; ++j) {
        const double dj = row[j] - row0[j];
        x[j] = a * x[j] + b * prev[j] + (dj - prev[j]) * c;
        corr[j] += wi * (dj - x[j]);
      }
    }
    for (size_t j = 0; j < m; ++j) {
      prev[j] = row[j] - row0[j];
      o[j] = row[j] - corr[j];
    }
  }
}

size_t Row(const RecordRows& d, size_t k) { return RegressorRow(k, d.from); }

class Solver {
 public:
  Solver(const SpectrumProblem& p, std::span<const double> params)
      : p_(p),
        model_(*p.model),
        m_(model_.family().regressors()),
        n_(p.count),
        nf_(model_.family_param_count()),
        pol_(model_.scale().polarity),
        effect_params_(params.begin() + static_cast<std::ptrdiff_t>(nf_), params.end()) {
    const auto& box = model_.params();
    for (size_t i = 0; i < n_; ++i) upper_.push_back(box[p.first + i].upper);
    std::vector<double> ue, c;
    const std::vector<double> taus =
        EffectKind::Named("creep-spectrum")->KernelData(model_.scale());
    if (taus.size() != n_)
      throw InputError("SolveSpectrum: " + std::to_string(n_) + " weights for " +
                       std::to_string(taus.size()) + " relaxations");
    data_.resize(p.records.size());
    for (size_t i = 0; i < p.records.size(); ++i) {
      RecordRows& d = data_[i];
      d.r = p.records[i];
      const io::Record& r = *d.r;
      d.from = SimulatedFrom(r, r.end_scored);
      model_.EffectiveDrive(r, effect_params_, d.from, r.end_scored, ue);
      d.rows = ue.size();
      d.reg.resize(d.rows * m_);
      model_.family().Regressors(ue, d.reg);
      const double off = RecordCentre(r, d.from, d.reg, 0, c);
      d.a.resize(n_);
      d.c.resize(n_);
      for (size_t i = 0; i < n_; ++i) {  // as the effect's ApplyOutput
        const model::LowpassStep st = model::LowpassConsts(taus[i], r.dt);
        d.a[i] = st.a;
        d.c[i] = st.c;
      }
      d.t.resize(static_cast<Index>(r.scored()));
      for (size_t k = r.first_scored; k < r.end_scored; ++k)
        d.t(static_cast<Index>(k - r.first_scored)) = r.y[k] - off;
    }
    if (p.regularisation != nullptr && p.regularisation->size() > 0) R_ = *p.regularisation;
    if (p.roughness != nullptr && p.roughness->size() > 0)
      DtD_ = p.roughness->transpose() * *p.roughness;
  }

  int grams() const { return grams_; }
  void Metric(const Eigen::VectorXd& w, SpectrumMetric& out) {
    Normal(w);
    out.G = G_;
    out.C.clear();
    for (const RecordRows& d : data_) out.C.push_back(d.C);
  }
  static std::vector<RecordRows>& Cache() {
    thread_local std::vector<RecordRows> cache;
    return cache;
  }

  /// s_ = A θ on a record's rows, and Z's columns pol · centred (I − L_i) s_ (each relaxation's
  /// share of the output, on the scored samples).
  void Relaxations(const RecordRows& d, const Eigen::VectorXd& theta, Eigen::MatrixXd& Z) {
    Output(d, theta, s_);
    Eigen::VectorXd unit = Eigen::VectorXd::Zero(static_cast<Index>(n_));
    for (size_t i = 0; i < n_; ++i) {
      unit.setZero();
      unit(static_cast<Index>(i)) = 1;
      z_ = s_;
      model_.ApplyLinearOutputEffects(*d.r, EffectParams(unit), d.from, z_, 1);
      for (size_t k = 0; k < d.rows; ++k) z_[k] = s_[k] - z_[k];
      Centred(d, z_, Z.col(static_cast<Index>(i)));
    }
  }

  /// The weights that best fit with the family's weights fixed at θ (the iteration's start from a
  /// reference (θ, w) solved elsewhere: one small solve in n unknowns brings w near this
  /// problem's).
  Eigen::VectorXd WeightsFor(const Eigen::VectorXd& theta) {
    const auto N = static_cast<Index>(n_);
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(N, N);
    Eigen::VectorXd h = Eigen::VectorXd::Zero(N);
    for (RecordRows& d : data_) {
      const io::Record& r = *d.r;
      const auto S = static_cast<Index>(r.scored());
      Eigen::MatrixXd Z(S, N);
      Relaxations(d, theta, Z);
      Eigen::VectorXd e(S);
      Centred(d, s_, e);
      G.noalias() += Z.transpose() * Z;
      h.noalias() += Z.transpose() * (e - d.t);  // t ≈ s − Z w
    }
    if (DtD_.size() > 0) G += p_.mu * DtD_;
    Eigen::VectorXd w = NonNegativeLeastSquares(G, h);
    for (size_t i = 0; i < n_; ++i)
      w(static_cast<Index>(i)) = std::min(w(static_cast<Index>(i)), upper_[i]);
    return w;
  }

  /// From (θ0, w0) when θ0 is given (the steps then start in the problem's shared metric, if any),
  /// else from w0 with θ solved there.
  SpectrumSolution Run(const Eigen::VectorXd& w0, const Eigen::VectorXd* theta0 = nullptr) {
    SpectrumSolution s;
    Eigen::VectorXd w = w0, theta;
    if (theta0 != nullptr) {
      theta = *theta0;
    } else {  // θ at the start: the family's own solve at w (the normal equations of C(w) alone)
      Normal(w);
      Eigen::MatrixXd H = G_;
      if (R_.size() > 0) H += p_.lambda * R_;
      theta = NonNegativeLeastSquares(H, h_);
    }
    double sse = 0;
    double f = Objective(theta, w, &sse);
    s.objectives.push_back(f);
    std::vector<char> at_upper(n_, 0);
    for (size_t i = 0; i < n_; ++i) at_upper[i] = w(static_cast<Index>(i)) >= upper_[i];
    const auto M = static_cast<Index>(m_), N = static_cast<Index>(n_);
    for (int it = 0; it < kMaxIterations && std::isfinite(f); ++it) {
      // The normal equations of [C(w) | −Z] (C(w)'s part only where w moved since the last ones).
      Eigen::MatrixXd H;
      Eigen::VectorXd rhs;
      Linearised(theta, w, H, rhs);
      // Weights at their upper bound stay there (their columns moved to the right-hand side).
      std::vector<Index> free;
      for (Index j = 0; j < M; ++j) free.push_back(j);
      for (size_t i = 0; i < n_; ++i)
        if (!at_upper[i]) free.push_back(M + static_cast<Index>(i));
      const auto F = static_cast<Index>(free.size());
      Eigen::MatrixXd Hf(F, F);
      Eigen::VectorXd rf(F);
      for (Index a = 0; a < F; ++a) {
        rf(a) = rhs(free[static_cast<size_t>(a)]);
        for (size_t i = 0; i < n_; ++i)
          if (at_upper[i])
            rf(a) -= H(free[static_cast<size_t>(a)], M + static_cast<Index>(i)) * upper_[i];
        for (Index b = 0; b < F; ++b)
          Hf(a, b) = H(free[static_cast<size_t>(a)], free[static_cast<size_t>(b)]);
      }
      const Eigen::VectorXd uf = NonNegativeLeastSquares(Hf, rf);
      Eigen::VectorXd u(M + N);
      for (size_t i = 0; i < n_; ++i) u(M + static_cast<Index>(i)) = upper_[i];
      for (Index a = 0; a < F; ++a) u(free[static_cast<size_t>(a)]) = uf(a);
      // A weight held at its bound whose linearised gradient points inside is freed for the next
      // step.
      const Eigen::VectorXd grad = H * u - rhs;
      bool released = false;
      for (size_t i = 0; i < n_; ++i)
        if (at_upper[i] && grad(M + static_cast<Index>(i)) > 0) {
          at_upper[i] = 0;
          released = true;
        }
      // The step, shortened where a weight would leave its upper bound, halved until f decreases.
      Eigen::VectorXd x(M + N);
      x << theta, w;
      const Eigen::VectorXd dx = u - x;
      double amax = 1;
      Index hits = -1;
      for (size_t i = 0; i < n_; ++i) {
        const Index j = M + static_cast<Index>(i);
        if (u(j) > upper_[i] && dx(j) > 0) {
          const double a = (upper_[i] - x(j)) / dx(j);
          if (a < amax) {
            amax = a;
            hits = j;
          }
        }
      }
      double alpha = amax, f_new = f, sse_new = sse;
      Eigen::VectorXd tn, wn;
      bool accepted = false;
      for (int half = 0; half <= kMaxHalvings; ++half, alpha *= 0.5) {
        const Eigen::VectorXd xn = x + alpha * dx;
        tn = xn.head(M).cwiseMax(0.0);
        wn = xn.tail(N).cwiseMax(0.0);
        for (size_t i = 0; i < n_; ++i)
          wn(static_cast<Index>(i)) = std::min(wn(static_cast<Index>(i)), upper_[i]);
        if (half == 0 && hits >= 0) wn(hits - M) = upper_[static_cast<size_t>(hits - M)];
        double e = 0;
        const double fn = Objective(tn, wn, &e);
        if (fn < f) {
          f_new = fn;
          sse_new = e;
          accepted = true;
          if (half == 0 && hits >= 0) at_upper[static_cast<size_t>(hits - M)] = 1;
          break;
        }
      }
      ++s.iterations;
      if (!accepted) {
        if (released) continue;
        break;
      }
      const double gain = (f - f_new) / std::max(f, std::numeric_limits<double>::min());
      theta = tn;
      w = wn;
      f = f_new;
      sse = sse_new;
      s.objectives.push_back(f);
      if (gain < kTolerance && !released) break;
    }
    s.ok = std::isfinite(f);
    s.w.assign(w.data(), w.data() + w.size());
    s.theta.assign(theta.data(), theta.data() + theta.size());
    s.sse = sse;
    s.roughness = DtD_.size() > 0 ? p_.mu * w.dot(DtD_ * w) : 0;
    s.objective = f;
    s.grams = grams_;
    return s;
  }

 private:
  static constexpr int kMaxIterations = 40, kMaxHalvings = 30;
  static constexpr double kTolerance = 1e-9;
  /// The normal equations are rebuilt when a weight has moved more than kRefresh from where they
  /// were built, or after kStaleSteps steps in their metric.
  static constexpr double kRefresh = 0.02;
  static constexpr int kStaleSteps = 3;
  /// Steps in the problem's shared metric before the normal equations of this problem are built.
  static constexpr int kSharedSteps = 8;

  /// The effect parameters with the spectrum's weights w.
  const std::vector<double>& EffectParams(const Eigen::VectorXd& w) {
    for (size_t i = 0; i < n_; ++i) effect_params_[p_.first - nf_ + i] = w(static_cast<Index>(i));
    return effect_params_;
  }

  /// s = reg θ on a record's rows, then `weights` of the relaxations applied (L_weights s).
  void Output(const RecordRows& d, const Eigen::VectorXd& theta, std::vector<double>& s) const {
    s.resize(d.rows);
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    const Eigen::Map<const RowMajor> A(d.reg.data(), static_cast<Index>(d.rows),
                                       static_cast<Index>(m_));
    Eigen::Map<Eigen::VectorXd>(s.data(), static_cast<Index>(d.rows)).noalias() = A * theta;
  }

  /// pol · (v − centre) on the scored samples (v: one value per row).
  void Centred(const RecordRows& d, const std::vector<double>& v, Eigen::Ref<Eigen::VectorXd> out) {
    const double c0 = CentreOf(d, v);
    const io::Record& r = *d.r;
    for (size_t k = r.first_scored; k < r.end_scored; ++k)
      out(static_cast<Index>(k - r.first_scored)) = pol_ * (v[Row(d, k)] - c0);
  }
  double CentreOf(const RecordRows& d, const std::vector<double>& v) {
    RecordCentre(*d.r, d.from, v, 1, centre_);
    return centre_[0];
  }

  double Objective(const Eigen::VectorXd& theta, const Eigen::VectorXd& w, double* sse) {
    const std::vector<double>& ep = EffectParams(w);
    double e2 = 0;
    for (const RecordRows& d : data_) {
      Output(d, theta, s_);
      model_.ApplyLinearOutputEffects(*d.r, ep, d.from, s_, 1);
      const double c0 = CentreOf(d, s_);
      const io::Record& r = *d.r;
      for (size_t k = r.first_scored; k < r.end_scored; ++k) {
        const double e = d.t(static_cast<Index>(k - r.first_scored)) - pol_ * (s_[Row(d, k)] - c0);
        e2 += e * e;
      }
    }
    *sse = e2;
    double f = e2;
    if (R_.size() > 0) f += p_.lambda * theta.dot(R_ * theta);
    if (DtD_.size() > 0) f += p_.mu * w.dot(DtD_ * w);
    return std::isfinite(f) ? f : std::numeric_limits<double>::infinity();
  }

  /// The normal equations of C(w) = L_w A (scored rows centred, polarity applied): G_, h_; each
  /// record's C kept.
  void Normal(const Eigen::VectorXd& w) {
    const auto M = static_cast<Index>(m_);
    G_ = Eigen::MatrixXd::Zero(M, M);
    h_ = Eigen::VectorXd::Zero(M);
    for (RecordRows& d : data_) {
      FilterRows(d, w, m_, creg_, state_);
      RecordCentre(*d.r, d.from, creg_, m_, centre_);
      const io::Record& r = *d.r;
      d.C.resize(static_cast<Index>(r.scored()), M);
      for (size_t k = r.first_scored; k < r.end_scored; ++k) {
        const double* row = creg_.data() + Row(d, k) * m_;
        const auto i = static_cast<Index>(k - r.first_scored);
        for (size_t j = 0; j < m_; ++j)
          d.C(i, static_cast<Index>(j)) = pol_ * (row[j] - centre_[j]);
      }
      G_.selfadjointView<Eigen::Lower>().rankUpdate(d.C.transpose());
      h_.noalias() += d.C.transpose() * d.t;
    }
    G_.triangularView<Eigen::StrictlyUpper>() = G_.transpose();
    gram_w_ = w;
    stale_ = 0;
    ++grams_;
  }

  /// The Gauss–Newton normal equations at (θ, w) in u = (θ', w'): H = MᵀM + diag(λR, μDᵀD),
  /// rhs = H x − g with g = ½∇f at x = (θ, w) exact and M = [C | −Z], Z = pol · centred
  /// (I − L_i)(A θ) — C = C(w) where the last normal equations were built at this w (rhs = Mᵀ(t − Z
  /// w), the plain Gauss–Newton step), else C at their w (kept for kStaleSteps steps while w stays
  /// within kRefresh of it: a step in the metric of a nearby Hessian, the gradient exact through
  /// the relaxations' adjoint, so the iteration still converges to the optimum of f).
  void Linearised(const Eigen::VectorXd& theta, const Eigen::VectorXd& w, Eigen::MatrixXd& H,
                  Eigen::VectorXd& rhs) {
    const bool shared = p_.metric != nullptr && grams_ == 0 && ++shared_steps_ <= kSharedSteps;
    if (!shared && (gram_w_.size() != w.size() || (gram_w_ - w).cwiseAbs().maxCoeff() > kRefresh ||
                    ++stale_ > kStaleSteps))
      Normal(w);
    const auto M = static_cast<Index>(m_), N = static_cast<Index>(n_);
    H = Eigen::MatrixXd::Zero(M + N, M + N);
    H.topLeftCorner(M, M) = shared ? p_.metric->G : G_;
    size_t record = 0;
    Eigen::VectorXd g = Eigen::VectorXd::Zero(M + N);  // ½∇ of the squared errors
    using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    for (RecordRows& d : data_) {
      const io::Record& r = *d.r;
      const auto S = static_cast<Index>(r.scored());
      Eigen::MatrixXd Z(S, N);
      Relaxations(d, theta, Z);
      // The residual at (θ, w), and ρ: its samples gathered on the rows, less what the offset
      // removes.
      z_ = s_;
      model_.ApplyLinearOutputEffects(r, EffectParams(w), d.from, z_, 1);
      Eigen::VectorXd e(S);
      Centred(d, z_, e);
      e = d.t - e;
      rho_.assign(d.rows, 0.0);
      for (size_t k = r.first_scored; k < r.end_scored; ++k)
        rho_[Row(d, k)] += e(static_cast<Index>(k - r.first_scored));
      const double sum = e.sum();
      if (r.offset_mode == io::OffsetMode::kFit) {
        const double mean = sum / static_cast<double>(S);
        for (size_t k = r.first_scored; k < r.end_scored; ++k) rho_[Row(d, k)] -= mean;
      } else if (r.offset_mode == io::OffsetMode::kRest) {
        rho_[0] -= sum;
      }
      // C(w)ᵀ e = pol Aᵀ L_wᵀ ρ, with L_w v = v − Σ w_i (I − F_i) P v (P v = v − v₀, F_i the
      // relaxation x_k = a x_{k−1} + c d_k + (1 − a − c) d_{k−1} from 0): L_wᵀ ρ = ρ − Pᵀ Σ w_i (ρ
      // − F_iᵀ ρ).
      acc_.assign(d.rows, 0.0);
      for (size_t i = 0; i < n_; ++i) {
        const double a = d.a[i], c = d.c[i], b = 1 - a - c, wi = w(static_cast<Index>(i));
        double u = 0, next = 0;  // u_{l+1}, ρ_{l+1}
        for (size_t l = d.rows; l-- > 0;) {
          u = a * u + c * rho_[l] + b * next;
          next = rho_[l];
          acc_[l] += wi * (rho_[l] - u);
        }
      }
      double total = 0;
      for (double v : acc_) total += v;
      acc_[0] -= total;
      for (size_t l = 0; l < d.rows; ++l) acc_[l] = rho_[l] - acc_[l];
      const Eigen::Map<const RowMajor> A(d.reg.data(), static_cast<Index>(d.rows), M);
      g.head(M).noalias() -= pol_ * (A.transpose() * Eigen::Map<const Eigen::VectorXd>(
                                                         acc_.data(), static_cast<Index>(d.rows)));
      g.tail(N).noalias() += Z.transpose() * e;
      // M's columns: C, then −Z.
      H.topRightCorner(M, N).noalias() -= (shared ? p_.metric->C[record] : d.C).transpose() * Z;
      ++record;
      H.bottomRightCorner(N, N).noalias() += Z.transpose() * Z;
    }
    EffectParams(w);
    H.bottomLeftCorner(N, M) = H.topRightCorner(M, N).transpose();
    if (R_.size() > 0) H.topLeftCorner(M, M) += p_.lambda * R_;
    if (DtD_.size() > 0) H.bottomRightCorner(N, N) += p_.mu * DtD_;
    Eigen::VectorXd x(M + N);
    x << theta, w;
    rhs = H * x - g;  // the penalties' gradients cancel: H x − (g + P x) + P x
    if (R_.size() > 0) rhs.head(M) -= p_.lambda * (R_ * theta);
    if (DtD_.size() > 0) rhs.tail(N) -= p_.mu * (DtD_ * w);
  }

  const SpectrumProblem& p_;
  const RecordModel& model_;
  const size_t m_, n_, nf_;
  const int pol_;
  std::vector<double> effect_params_;
  std::vector<double> upper_;
  std::vector<RecordRows>& data_ = Cache();  ///< this thread's buffers, reused from call to call
  Eigen::MatrixXd R_, DtD_;
  Eigen::MatrixXd G_;
  Eigen::VectorXd h_, gram_w_;
  int grams_ = 0, stale_ = 0, shared_steps_ = 0;
  std::vector<double> creg_, s_, z_, centre_, state_, rho_, acc_;
};

}  // namespace

bool SpectrumSolved(const RecordModel& model) {
  if (!model.family().linear()) return false;
  bool spectrum = false, other = false;
  for (EffectKind e : model.effects()) {
    if (e->stage() != model::EffectStage::kOutput) continue;
    (e == EffectKind::Named("creep-spectrum") ? spectrum : other) = true;
  }
  return spectrum && !other && model.has_linear_output_effects();
}

std::vector<size_t> SearchedParams(const RecordModel& model) {
  std::vector<size_t> out;
  const auto [first, count] = SpectrumSolved(model)
                                  ? model.EffectParams(EffectKind::Named("creep-spectrum"))
                                  : std::pair<size_t, size_t>{0, 0};
  for (size_t i = 0; i < model.params().size(); ++i)
    if (i < first || i >= first + count) out.push_back(i);
  return out;
}

SpectrumMetric BuildSpectrumMetric(const SpectrumProblem& problem, std::span<const double> params,
                                   std::span<const double> w) {
  SpectrumProblem p = problem;
  p.metric = nullptr;
  Solver solver(p, params);
  SpectrumMetric out;
  solver.Metric(Eigen::Map<const Eigen::VectorXd>(w.data(), static_cast<Eigen::Index>(w.size())),
                out);
  return out;
}

SpectrumSolution SolveSpectrum(const SpectrumProblem& problem, std::span<const double> params) {
  if (problem.model == nullptr) throw InputError("SolveSpectrum: no model");
  const RecordModel& model = *problem.model;
  if (!model.family().linear() || !model.has_linear_output_effects() || problem.count == 0)
    throw InputError("SolveSpectrum: " + model.Describe() +
                     " is not a linear family with a creep spectrum");
  if (params.size() != model.params().size())
    throw InputError("SolveSpectrum: " + std::to_string(params.size()) + " parameters given, " +
                     std::to_string(model.params().size()) + " expected");
  if (problem.first < model.family_param_count() || problem.first + problem.count > params.size())
    throw InputError("SolveSpectrum: the spectrum's weights are not among the effects' parameters");
  Solver solver(problem, params);
  const auto n = static_cast<Eigen::Index>(problem.count);
  SpectrumSolution best;
  int iterations = 0;
  if (!problem.start.empty()) {
    if (problem.start.size() != problem.count)
      throw InputError("SolveSpectrum: the start has the wrong size");
    Eigen::VectorXd w = Eigen::Map<const Eigen::VectorXd>(problem.start.data(), n);
    if (problem.start_theta.size() == problem.model->family().regressors()) {
      const Eigen::VectorXd theta = Eigen::Map<const Eigen::VectorXd>(
          problem.start_theta.data(), static_cast<Eigen::Index>(problem.start_theta.size()));
      w = solver.WeightsFor(theta);
      best = problem.metric != nullptr ? solver.Run(w, &theta) : solver.Run(w);
    } else {
      best = solver.Run(w);
    }
    best.start = 2;
    best.grams = solver.grams();
    return best;
  }
  if (!problem.zero_start && !(problem.log_creep_start > 0))
    throw InputError("SolveSpectrum: no start");
  if (problem.zero_start) {
    best = solver.Run(Eigen::VectorXd::Zero(n));
    iterations = best.iterations;
  }
  if (problem.log_creep_start > 0) {
    Eigen::VectorXd w(n);
    for (Eigen::Index i = 0; i < n; ++i)
      w(i) = std::min(problem.log_creep_start,
                      model.params()[problem.first + static_cast<size_t>(i)].upper);
    SpectrumSolution other = solver.Run(w);
    other.start = 1;
    iterations += other.iterations;
    if (!problem.zero_start || (other.ok && (!best.ok || other.objective < best.objective)))
      best = std::move(other);
  }
  best.iterations = iterations;
  best.grams = solver.grams();
  return best;
}

}  // namespace pz::records
