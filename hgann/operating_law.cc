#include "hgann/operating_law.h"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>

#include "hgann/trend_seeds.h"
#include "model/chromosome.h"
#include "opt/lm.h"

namespace pz::hgann {
namespace {

constexpr int kOut = model::kNetworkOutputs;
constexpr int kGrid = 5;  // the spread penalty's grid (HgannFitness::GridOf)
constexpr int kRidges = 4;  // the interaction's ridge units
using Array7 = std::array<double, kOut>;
using Phi = std::array<double, OperatingLaw::kMaxTerms>;

/// The law's hidden layer and its basis φ = (1, x_V, ℓ, q) at the training cases, every case of
/// the configuration and the spread penalty's grid.
struct LawBasis {
  const HgannFitnessConfig& cfg;
  std::vector<int> training;
  model::Network net0;
  int hf = -1;            ///< hidden node of the log-f hinge
  int ridge0 = -1;        ///< the interaction's first ridge node (kRidges of them)
  double m1 = 1, m2 = 0;  ///< ℓ = m1 x_f + m2 hinge
  /// q = Σ_i q_w[i] R_i over the interaction's dictionary (kRidges ridge units and x_V):
  /// R_0 = x_V − satlin(x_V − x_f) = min(x_V, x_f), R_1 = satlin(x_V + x_f − 1),
  /// R_2 = satlin(x_V + 2 x_f − 2), R_3 = satlin(2 x_V + x_f − 2); each 0 where x_V = 0 or x_f = 0
  /// on [0, 1]², their combination chosen closest to x_V ℓ at the configuration's cases.
  std::array<double, 4> q_w{};
  int terms = 3;
  std::vector<Phi> at_train, at_cases, at_grid;

  LawBasis(const HgannFitnessConfig& config, bool with_interaction) : cfg(config) {
    const auto& norm = cfg.normalization;
    for (size_t i = 0; i < cfg.cases.size(); ++i)
      if (cfg.cases[i].training) training.push_back(static_cast<int>(i));
    // The middle training frequency (the one whose x_f is nearest ½ strictly inside (0, 1)).
    double knot = -1, f_knot = 0;
    for (int i : training) {
      const double f = cfg.cases[i].drive.frequency_hz, x = norm.NormalizeFrequency(f);
      if (x > 1e-9 && x < 1 - 1e-9 && (knot < 0 || std::abs(x - 0.5) < std::abs(knot - 0.5)))
        knot = x, f_knot = f;
    }
    const double f_lo = norm.frequency_lo_hz, f_hi = norm.frequency_hi_hz;
    using model::TransferFunction;
    model::Network n;
    n.input_tf = {TransferFunction::kSatlin, TransferFunction::kSatlin};
    int h = 2;
    if (knot > 0 && f_lo > 0) hf = h++;
    if (with_interaction) ridge0 = h, h += kRidges;
    n.hidden_tf.assign(h, TransferFunction::kSatlin);
    n.output_tf.fill(TransferFunction::kSatlin);
    n.w1 = Eigen::MatrixXd::Zero(2, h);
    n.c1 = Eigen::VectorXd::Zero(h);
    n.w1(0, 0) = 1;
    n.w1(1, 1) = 1;
    if (hf >= 0) {
      n.w1(1, hf) = 1 / (1 - knot);
      n.c1(hf) = -knot / (1 - knot);
      m1 = std::log(f_knot / f_lo) / std::log(f_hi / f_lo) / knot;
      m2 = 1 - m1;
    }
    if (with_interaction) {
      static constexpr double kRidge[kRidges][3] = {
          {1, -1, 0}, {1, 1, -1}, {1, 2, -2}, {2, 1, -2}};  // w_V, w_f, bias
      for (int i = 0; i < kRidges; ++i) {
        n.w1(0, ridge0 + i) = kRidge[i][0];
        n.w1(1, ridge0 + i) = kRidge[i][1];
        n.c1(ridge0 + i) = kRidge[i][2];
      }
      terms = 4;
    }
    n.w2 = Eigen::MatrixXd::Zero(h, kOut);
    n.c2 = Eigen::VectorXd::Zero(kOut);
    n.normalization = norm;
    n.ranges = cfg.ranges;
    // At the chromosome's resolution: the basis the GA and the fitness see.
    net0 = model::DecodeChromosome(model::EncodeChromosome(n), norm, cfg.ranges);
    if (with_interaction) FitInteraction();
    for (int i : training)
      at_train.push_back(At(cfg.cases[i].drive.amplitude_v, cfg.cases[i].drive.frequency_hz));
    for (const HgannCase& c : cfg.cases)
      at_cases.push_back(At(c.drive.amplitude_v, c.drive.frequency_hz));
    for (int i = 0; i < kGrid; ++i)
      for (int j = 0; j < kGrid; ++j)
        at_grid.push_back(
            At(norm.amplitude_lo_v + (norm.amplitude_hi_v - norm.amplitude_lo_v) * i / (kGrid - 1),
               norm.frequency_lo_hz +
                   (norm.frequency_hi_hz - norm.frequency_lo_hz) * j / (kGrid - 1)));
  }

  /// The dictionary R_0 … R_3 of the interaction at hidden outputs b.
  std::array<double, 4> Ridges(const Eigen::VectorXd& b) const {
    return {b(0) - b(ridge0), b(ridge0 + 1), b(ridge0 + 2), b(ridge0 + 3)};
  }

  /// q_w: least squares of x_V ℓ on the dictionary at every case's operating point (weight 1)
  /// and the spread grid's (weight 0.3, for the shape between them), with a ridge of 1e-6.
  void FitInteraction() {
    std::vector<std::pair<double, double>> points;
    for (const HgannCase& c : cfg.cases) points.emplace_back(c.drive.amplitude_v, c.drive.frequency_hz);
    const auto& norm = cfg.normalization;
    const size_t n_cases = points.size();
    for (int i = 0; i < kGrid; ++i)
      for (int j = 0; j < kGrid; ++j)
        points.emplace_back(
            norm.amplitude_lo_v + (norm.amplitude_hi_v - norm.amplitude_lo_v) * i / (kGrid - 1),
            norm.frequency_lo_hz + (norm.frequency_hi_hz - norm.frequency_lo_hz) * j / (kGrid - 1));
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(static_cast<int>(points.size()) + 4, 4);
    Eigen::VectorXd y = Eigen::VectorXd::Zero(a.rows());
    for (size_t r = 0; r < points.size(); ++r) {
      const Eigen::VectorXd b = net0.Forward(points[r].first, points[r].second).b;
      const double w = r < n_cases ? 1.0 : 0.3;
      const auto d = Ridges(b);
      for (int i = 0; i < 4; ++i) a(static_cast<int>(r), i) = w * d[i];
      y(static_cast<int>(r)) = w * b(0) * (m1 * b(1) + (hf >= 0 ? m2 * b(hf) : 0.0));
    }
    for (int i = 0; i < 4; ++i) a(static_cast<int>(points.size()) + i, i) = 1e-3;
    const Eigen::VectorXd x = a.colPivHouseholderQr().solve(y);
    for (int i = 0; i < 4; ++i) q_w[i] = x(i);
  }

  Phi At(double v, double f) const {
    const Eigen::VectorXd b = net0.Forward(v, f).b;
    Phi phi{1.0, b(0), m1 * b(1) + (hf >= 0 ? m2 * b(hf) : 0.0), 0.0};
    if (ridge0 >= 0) {
      const auto d = Ridges(b);
      for (int i = 0; i < 4; ++i) phi[3] += q_w[i] * d[i];
    }
    return phi;
  }

  double S(std::span<const double> th, const Phi& phi, int k) const {
    double s = 0;
    for (int t = 0; t < terms; ++t) s += th[terms * k + t] * phi[t];
    return std::clamp(s, 0.0, 1.0);
  }

  Array7 Params(std::span<const double> th, const Phi& phi) const {
    Array7 p{};
    for (int k = 0; k < kOut; ++k)
      p[k] = cfg.ranges[k].lower + S(th, phi, k) * (cfg.ranges[k].upper - cfg.ranges[k].lower);
    return p;
  }

  bool LoopBounded(std::span<const double> th, const Phi& phi) const {
    const Array7 p = Params(th, phi);
    model::BimorphParams bp;
    bp.alpha = p[2];
    bp.beta = p[3];
    bp.gamma = p[4];
    return bp.HysteresisBounded();
  }

  /// The law θ as the template's output weights.
  model::Network Network(std::span<const double> th) const {
    model::Network n = net0;
    const auto clamp = [](double w) { return std::clamp(w, model::kWeightMin, model::kWeightMax); };
    for (int k = 0; k < kOut; ++k) {
      const double c = th[terms * k], a = th[terms * k + 1], b = th[terms * k + 2],
                   d = terms > 3 ? th[terms * k + 3] : 0.0;
      n.c2(k) = clamp(c);
      n.w2(0, k) = clamp(a + q_w[0] * d);
      n.w2(1, k) = clamp(b * m1);
      if (hf >= 0) n.w2(hf, k) = clamp(b * m2);
      if (ridge0 >= 0) {
        n.w2(ridge0, k) = clamp(-q_w[0] * d);
        for (int i = 1; i < kRidges; ++i) n.w2(ridge0 + i, k) = clamp(q_w[i] * d);
      }
    }
    return n;
  }
};

/// Whether the training cases determine the interaction: q is not (within 5 % of its norm) a
/// combination of 1, x_V and ℓ over them.
bool InteractionDetermined(const LawBasis& with) {
  const int n = static_cast<int>(with.at_train.size());
  if (n < 4) return false;
  Eigen::MatrixXd a(n, 3);
  Eigen::VectorXd q(n);
  for (int r = 0; r < n; ++r) {
    for (int t = 0; t < 3; ++t) a(r, t) = with.at_train[r][t];
    q(r) = with.at_train[r][3];
  }
  const Eigen::VectorXd fit = a * a.completeOrthogonalDecomposition().solve(q);
  return q.norm() > 0 && (q - fit).norm() > 0.05 * q.norm();
}

/// The MAP cost's residuals: data, spread grid, prior (file comment of the header).
class LawResiduals {
 public:
  LawResiduals(const HgannFitness& fitness, const LawBasis& basis, double sigma)
      : fitness_(fitness), b_(basis), sigma_(sigma) {
    grid_weight_ = std::sqrt(basis.cfg.spread_penalty / (kGrid * kGrid));
  }

  bool operator()(std::span<const double> th, std::vector<double>& r) {
    const HgannFitnessConfig& cfg = b_.cfg;
    r.clear();
    for (const auto* points : {&b_.at_train, &b_.at_grid})
      for (const Phi& phi : *points)
        if (!b_.LoopBounded(th, phi)) return false;
    std::vector<double> angle;
    for (size_t m = 0; m < b_.training.size(); ++m) {
      const HgannCase& c = cfg.cases[b_.training[m]];
      angle.resize(c.measured_deg.size());
      ++sims_;
      if (!fitness_.SimulateCase(model::NetworkParameters::FromArray(b_.Params(th, b_.at_train[m])),
                                 c, angle))
        return false;
      for (size_t k = 0; k < angle.size(); ++k) r.push_back(angle[k] - c.measured_deg[k]);
    }
    if (grid_weight_ > 0)
      for (int k = 0; k < kOut; ++k) {
        double mean = 0;
        for (const Phi& phi : b_.at_grid) mean += b_.S(th, phi, k);
        mean /= static_cast<double>(b_.at_grid.size());
        for (const Phi& phi : b_.at_grid) r.push_back(grid_weight_ * (b_.S(th, phi, k) - mean));
      }
    for (int k = 0; k < kOut; ++k)
      for (int t = 0; t < b_.terms; ++t) {
        const double x = th[b_.terms * k + t];
        r.push_back(t == 0 ? sigma_ * (x - 0.5) / OperatingLaw::kConstantTau
                           : sigma_ * x / OperatingLaw::kSlopeTau);
      }
    return true;
  }

  int64_t simulations() const { return sims_.load(); }

 private:
  const HgannFitness& fitness_;
  const LawBasis& b_;
  double sigma_ = 0, grid_weight_ = 0;
  std::atomic<int64_t> sims_{0};
};

/// Start A: per parameter, the weighted ridge regression of the per-case estimates on φ with the
/// same prior (σ of an estimate as the trend seeds take it); start B: their mean, slopes 0.
std::vector<double> RegressionStart(const LawBasis& b, const std::vector<CaseEstimate>& est,
                                    bool slopes) {
  const int terms = b.terms;
  std::vector<double> th(terms * kOut, 0.0);
  for (int k = 0; k < kOut; ++k) {
    const double width = b.cfg.ranges[k].upper - b.cfg.ranges[k].lower;
    Eigen::MatrixXd ata = Eigen::MatrixXd::Zero(terms, terms);
    Eigen::VectorXd atb = Eigen::VectorXd::Zero(terms);
    int used = 0;
    double mean = 0;
    for (size_t m = 0; m < est.size() && m < b.at_train.size(); ++m) {
      if (!est[m].ok) continue;
      const double sd = width > 0 && std::isfinite(est[m].sigma[k])
                            ? std::max(est[m].sigma[k] / width, 0.005)
                            : 0.25;
      Eigen::VectorXd row(terms);
      for (int t = 0; t < terms; ++t) row(t) = b.at_train[m][t] / sd;
      ata += row * row.transpose();
      atb += row * (est[m].s[k] / sd);
      mean += est[m].s[k];
      ++used;
    }
    if (used == 0) {
      th[terms * k] = 0.5;
      continue;
    }
    if (!slopes) {
      th[terms * k] = mean / used;
      continue;
    }
    ata(0, 0) += 1 / (OperatingLaw::kConstantTau * OperatingLaw::kConstantTau);
    atb(0) += 0.5 / (OperatingLaw::kConstantTau * OperatingLaw::kConstantTau);
    for (int t = 1; t < terms; ++t)
      ata(t, t) += 1 / (OperatingLaw::kSlopeTau * OperatingLaw::kSlopeTau);
    const Eigen::VectorXd x = ata.ldlt().solve(atb);
    for (int t = 0; t < terms; ++t) th[terms * k + t] = std::clamp(x(t), t ? -3.0 : -2.0, t ? 3.0 : 2.0);
  }
  return th;
}

/// The loop's slopes (α, β, γ: outputs 2–4) set to 0 where the start leaves the loop unbounded.
void FlattenLoopIfUnbounded(const LawBasis& b, std::vector<double>& th) {
  bool bounded = true;
  for (const auto* points : {&b.at_train, &b.at_grid})
    for (const Phi& phi : *points) bounded = bounded && b.LoopBounded(th, phi);
  if (bounded) return;
  for (int k = 2; k <= 4; ++k)
    for (int t = 1; t < b.terms; ++t) th[b.terms * k + t] = 0.0;
}

double MedianResidualVariance(const std::vector<CaseEstimate>& est) {
  std::vector<double> v;
  for (const CaseEstimate& e : est)
    if (e.ok && e.residual_var > 0 && std::isfinite(e.residual_var)) v.push_back(e.residual_var);
  if (v.empty()) return 1e-4;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

/// Posterior covariance σ² (JᵀJ)⁺ of θ (J: every row of the MAP cost), the prior's share of each
/// coefficient's variance, and each parameter's σ at every case.
void Posterior(const LawBasis& b, const opt::LmResult& r, OperatingLaw& law) {
  const int terms = b.terms, n = terms * kOut;
  if (r.jacobian.cols() != n) return;
  const Eigen::MatrixXd info = r.jacobian.transpose() * r.jacobian;
  const Eigen::MatrixXd cov = law.sigma2 * info.completeOrthogonalDecomposition().pseudoInverse();
  for (int k = 0; k < kOut; ++k) {
    law.data_settled[k] = true;
    for (int t = 0; t < terms; ++t) {
      const double tau = t == 0 ? OperatingLaw::kConstantTau : OperatingLaw::kSlopeTau;
      const double share = std::clamp(cov(terms * k + t, terms * k + t) / (tau * tau), 0.0, 1.0);
      law.prior_share[k][t] = share;
      law.data_settled[k] = law.data_settled[k] && share < OperatingLaw::kPriorShare;
    }
  }
  for (const Phi& phi : b.at_cases) {
    Array7 sd{};
    for (int k = 0; k < kOut; ++k) {
      double var = 0;
      for (int t = 0; t < terms; ++t)
        for (int u = 0; u < terms; ++u) var += phi[t] * phi[u] * cov(terms * k + t, terms * k + u);
      sd[k] = std::sqrt(std::max(0.0, var)) * (b.cfg.ranges[k].upper - b.cfg.ranges[k].lower);
    }
    law.sigma_at_case.push_back(sd);
  }
}

}  // namespace

OperatingLaw FitOperatingLaw(const HgannFitness& fitness,
                             const std::vector<CaseEstimate>& estimates,
                             const TrendSeedOptions& options) {
  const HgannFitnessConfig& cfg = fitness.config();
  OperatingLaw law;
  const bool interaction = InteractionDetermined(LawBasis(cfg, true));
  const LawBasis basis(cfg, interaction);
  law.interaction = interaction;
  law.terms = basis.terms;
  law.sigma2 = MedianResidualVariance(estimates);
  LawResiduals residuals(fitness, basis, std::sqrt(law.sigma2));
  const opt::ResidualFunction f = [&](std::span<const double> th, std::vector<double>& r) {
    return residuals(th, r);
  };
  opt::LmOptions lm;
  lm.max_iterations = options.lm_iterations;
  lm.threads = std::max(1, options.threads);
  lm.central = false;
  lm.central_to_finish = true;
  const int n = basis.terms * kOut;
  std::vector<double> lower(n), upper(n);
  for (int i = 0; i < n; ++i) {
    lower[i] = i % basis.terms == 0 ? -2.0 : -3.0;
    upper[i] = -lower[i];
  }
  opt::LmResult best;
  best.cost = std::numeric_limits<double>::infinity();
  for (const bool slopes : {true, false}) {
    std::vector<double> th0 = RegressionStart(basis, estimates, slopes);
    FlattenLoopIfUnbounded(basis, th0);
    opt::LmResult r = opt::LevenbergMarquardt(f, th0, lower, upper, lm);
    if (std::isfinite(r.cost) && r.cost < best.cost) {
      best = std::move(r);
      law.start = slopes ? "the per-case estimates' regression" : "their mean";
    }
  }
  law.simulations = residuals.simulations();
  if (!std::isfinite(best.cost)) return law;
  law.ok = true;
  for (int k = 0; k < kOut; ++k)
    for (int t = 0; t < basis.terms; ++t) law.coef[k][t] = best.x[basis.terms * k + t];
  Posterior(basis, best, law);
  law.network = basis.Network(best.x);
  law.cost = fitness.EvaluateNetwork(law.network).cost;
  for (const HgannCaseResult& c : fitness.EvaluateCases(law.network))
    if (c.training) law.data_cost += c.pi;
  law.simulations += static_cast<int64_t>(cfg.cases.size() + basis.training.size());
  return law;
}

std::string PriorSettledNames(const OperatingLaw& law) {
  static constexpr const char* kNames[kOut] = {"μ", "δ", "α", "β", "γ", "a1", "a2"};
  std::string out;
  for (int k = 0; k < kOut; ++k)
    if (!law.data_settled[k]) out += (out.empty() ? "" : ", ") + std::string(kNames[k]);
  return out;
}

}  // namespace pz::hgann
