#include "hgann/operating_law.h"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <tuple>

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
using Active = std::array<std::array<bool, OperatingLaw::kMaxTerms>, kOut>;

/// ℓ_λ(f) over [f_lo, f_hi] (the header's Box–Cox shape in f): 0 at f_lo, 1 at f_hi.
double FShape(double f, double f_lo, double f_hi, double power) {
  if (power == 0) return std::log(f / f_lo) / std::log(f_hi / f_lo);
  return (std::pow(f, power) - std::pow(f_lo, power)) /
         (std::pow(f_hi, power) - std::pow(f_lo, power));
}

/// The law's hidden layer and its basis φ = (1, x_V, ℓ, q, h_V) at the training cases, every case
/// of the configuration and the spread penalty's grid (q = 0 without the interaction's nodes, h_V
/// = 0 without a middle training amplitude); θ holds kMaxTerms coefficients a parameter, those
/// not in the law (OperatingLaw::active) held at 0 by their prior.
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
  int hv = -1;  ///< hidden node of the amplitude hinge (curvature in V)
  static constexpr int terms = OperatingLaw::kMaxTerms;
  std::array<std::array<bool, OperatingLaw::kMaxTerms>, kOut> active{};
  std::vector<Phi> at_train, at_cases, at_grid;

  LawBasis(const HgannFitnessConfig& config, bool with_interaction, const Active& in_law,
           double f_power)
      : cfg(config), active(in_law) {
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
    double knot_v = -1;  // the middle training amplitude, as the frequency's
    for (int i : training) {
      const double x = norm.NormalizeAmplitude(cfg.cases[i].drive.amplitude_v);
      if (x > 1e-9 && x < 1 - 1e-9 && (knot_v < 0 || std::abs(x - 0.5) < std::abs(knot_v - 0.5)))
        knot_v = x;
    }
    int h = 2;
    if (knot > 0 && f_lo > 0) hf = h++;
    if (with_interaction) ridge0 = h, h += kRidges;
    if (knot_v > 0) hv = h++;
    model::Network n = SatlinSkeleton(h);
    if (hf >= 0) {
      n.w1(1, hf) = 1 / (1 - knot);
      n.c1(hf) = -knot / (1 - knot);
      m1 = FShape(f_knot, f_lo, f_hi, f_power) / knot;
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
    }
    if (hv >= 0) {
      n.w1(0, hv) = 1 / (1 - knot_v);
      n.c1(hv) = -knot_v / (1 - knot_v);
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
    for (const HgannCase& c : cfg.cases)
      points.emplace_back(c.drive.amplitude_v, c.drive.frequency_hz);
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
    Phi phi{1.0, b(0), m1 * b(1) + (hf >= 0 ? m2 * b(hf) : 0.0), 0.0, hv >= 0 ? b(hv) : 0.0,
            hf >= 0 ? b(hf) : 0.0};
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

  /// The prior's σ of θ's coefficient t of output k (a term not in the law: 1e-4, held at 0).
  double Tau(int k, int t) const {
    if (!active[k][t]) return 1e-4;
    return t == 0 ? OperatingLaw::kConstantTau : OperatingLaw::kSlopeTau;
  }

  /// The law θ as the template's output weights.
  model::Network Network(std::span<const double> th) const {
    model::Network n = net0;
    const auto clamp = [](double w) { return std::clamp(w, model::kWeightMin, model::kWeightMax); };
    for (int k = 0; k < kOut; ++k) {
      const double c = th[terms * k], a = th[terms * k + 1], b = th[terms * k + 2],
                   d = ridge0 >= 0 ? th[terms * k + 3] : 0.0;
      n.c2(k) = clamp(c);
      n.w2(0, k) = clamp(a + q_w[0] * d);
      n.w2(1, k) = clamp(b * m1);
      if (hf >= 0) n.w2(hf, k) = clamp(b * m2 + th[terms * k + 5]);
      if (ridge0 >= 0) {
        n.w2(ridge0, k) = clamp(-q_w[0] * d);
        for (int i = 1; i < kRidges; ++i) n.w2(ridge0 + i, k) = clamp(q_w[i] * d);
      }
      if (hv >= 0) n.w2(hv, k) = clamp(th[terms * k + 4]);
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
        r.push_back(sigma_ * (t == 0 ? x - 0.5 : x) / b_.Tau(k, t));
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
    for (int t = 0; t < terms; ++t) ata(t, t) += 1 / (b.Tau(k, t) * b.Tau(k, t));
    atb(0) += 0.5 / (b.Tau(k, 0) * b.Tau(k, 0));
    const Eigen::VectorXd x = ata.ldlt().solve(atb);
    for (int t = 0; t < terms; ++t)
      th[terms * k + t] = std::clamp(x(t), t ? -3.0 : -2.0, t ? 3.0 : 2.0);
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

/// σ² (JᵀJ)⁺ over the data's and the prior's rows of J (the MAP cost's rows in LawResiduals'
/// order: data, the spread grid's, the prior's). The spread penalty's rows are left out: they are
/// the fitness's preference, not information, and with λ = 10 deg² they would outweigh the data.
Eigen::MatrixXd InformationCovariance(const LawBasis& b, const Eigen::MatrixXd& j, double sigma2) {
  const int n_prior = b.terms * kOut;
  const int n_grid = b.cfg.spread_penalty > 0 ? kOut * kGrid * kGrid : 0;
  const int n_data = static_cast<int>(j.rows()) - n_grid - n_prior;
  Eigen::MatrixXd kept(n_data + n_prior, j.cols());
  kept << j.topRows(n_data), j.bottomRows(n_prior);
  return sigma2 * (kept.transpose() * kept).completeOrthogonalDecomposition().pseudoInverse();
}

/// Posterior covariance σ² (JᵀJ)⁺ of θ (J: every row of the MAP cost), the prior's share of each
/// coefficient's variance, and each parameter's σ at every case.
void Posterior(const LawBasis& b, const opt::LmResult& r, OperatingLaw& law) {
  const int terms = b.terms, n = terms * kOut;
  if (r.jacobian.cols() != n) return;
  const Eigen::MatrixXd cov = InformationCovariance(b, r.jacobian, law.sigma2);
  for (int k = 0; k < kOut; ++k) {
    law.data_settled[k] = true;
    for (int t = 0; t < terms; ++t) {
      if (!b.active[k][t]) continue;
      const double tau = b.Tau(k, t);
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

/// Weighted χ² of the per-case estimates of output k on the basis columns `cols` (σ as the trend
/// seeds take it, at least 0.5 % of the range), and the number of estimates; `coef` (when given
/// and the estimates are at least as many as the columns): the least squares' coefficients.
std::pair<double, int> EstimatesChi2(const LawBasis& b, const std::vector<CaseEstimate>& est,
                                     int k, const std::vector<int>& cols,
                                     Eigen::VectorXd* coef = nullptr) {
  const double width = b.cfg.ranges[k].upper - b.cfg.ranges[k].lower;
  std::vector<int> rows;
  for (size_t m = 0; m < est.size() && m < b.at_train.size(); ++m)
    if (est[m].ok) rows.push_back(static_cast<int>(m));
  const int n = static_cast<int>(rows.size()), p = static_cast<int>(cols.size());
  if (n < p || width <= 0) return {0.0, n};
  Eigen::MatrixXd a(n, p);
  Eigen::VectorXd y(n);
  for (int r = 0; r < n; ++r) {
    const CaseEstimate& e = est[rows[r]];
    const double sd = std::isfinite(e.sigma[k]) ? std::max(e.sigma[k] / width, 0.005) : 0.25;
    for (int c = 0; c < p; ++c) a(r, c) = b.at_train[rows[r]][cols[c]] / sd;
    y(r) = e.s[k] / sd;
  }
  const Eigen::VectorXd x = a.completeOrthogonalDecomposition().solve(y);
  if (coef) *coef = x;
  return {n == p ? 0.0 : (a * x - y).squaredNorm(), n};
}

// The terms of μ, δ, a1 and a2 beyond the level (and the interaction, when in the law): of x_V
// and ℓ, x_V and the curvature h_V, all three, x_V, ℓ and the curvature in f (the log-f hinge
// h_f on its own: the f-shape free at the three frequencies), or all four, the set whose
// per-case estimates' weighted χ²
// + 2 p is lowest (Akaike), the fewer terms on a tie within 1e-6. On the paper's four cases an
// f-slope and a V-curvature can fit the same estimates (the 500 V cases are the only ones off
// 0.25 Hz): a1 ∝ V² is x_V + h_V, not an f-slope through case 5. Not for the loop's α, β, γ,
// whose per-case estimates scatter along a valley: they keep x_V and ℓ.
// `alternatives`: each other set that fits the estimates alike (χ² + 2 p within kAlike of the
// lowest), as (output, its estimates' coefficients − the chosen set's): the committee's shapes.
void SelectTerms(const LawBasis& b, const std::vector<CaseEstimate>& est, Active& active,
                 std::vector<std::pair<int, Phi>>* alternatives = nullptr) {
  constexpr double kAlike = 2;  // Akaike: a set within 2 of the best has substantial support
  // a, b, e, g, d: the interaction d in every set when the training determines it (as in the
  // law's basis), and then only beside both main effects (the marginality principle: with the
  // corner trained, a set of V, V·f and a V curvature without ln f fitted a1's estimates of an
  // additive law, flat in f at 375 V).
  static constexpr std::array<std::array<bool, 5>, 9> kSets = {{{true, true, false, false, false},
                                                                 {true, false, true, false, false},
                                                                 {true, true, true, false, false},
                                                                 {true, true, false, true, false},
                                                                 {true, true, true, true, false},
                                                                 {true, true, false, false, true},
                                                                 {true, true, true, false, true},
                                                                 {true, true, false, true, true},
                                                                 {true, true, true, true, true}}};
  const bool determined = active[0][3];
  for (int k : {0, 1, 5, 6}) {
    std::vector<std::pair<double, int>> scored;  // (χ² + 2 p, set), sets that can be fitted
    std::vector<Phi> coefs;                      // their coefficients, in the law's slots
    for (int i = 0; i < static_cast<int>(kSets.size()); ++i) {
      const auto& set = kSets[i];
      if ((set[2] && b.hv < 0) || (set[3] && b.hf < 0) || set[4] != determined) continue;
      std::vector<int> cols = {0};
      if (set[0]) cols.push_back(1);
      if (set[1]) cols.push_back(2);
      if (set[4]) cols.push_back(3);
      if (set[2]) cols.push_back(4);
      if (set[3]) cols.push_back(5);
      Eigen::VectorXd x;
      const auto [chi2, n] = EstimatesChi2(b, est, k, cols, &x);
      if (n < static_cast<int>(cols.size())) continue;
      scored.emplace_back(chi2 + 2.0 * static_cast<double>(cols.size()), i);
      Phi c{};
      for (size_t j = 0; j < cols.size(); ++j) c[cols[j]] = x(static_cast<int>(j));
      coefs.push_back(c);
    }
    // The lowest score; when two sets of as many terms tie there (each fits the estimates
    // exactly: a curvature in V or one in f through four cases), the estimates cannot say which,
    // and the best of the sets with fewer terms is taken instead.
    const auto size = [](int i) { return std::count(kSets[i].begin(), kSets[i].end(), true); };
    std::array<bool, 5> chosen = kSets[0];
    for (int cap = 5; cap >= 1; --cap) {
      double best = std::numeric_limits<double>::infinity();
      int pick = -1, ties = 0;
      for (const auto& [score, i] : scored) {
        if (size(i) > cap) continue;
        if (score < best - 1e-6) best = score, pick = i, ties = 1;
        else if (score <= best + 1e-6 && size(i) == size(pick)) ++ties;
      }
      if (pick < 0) break;
      chosen = kSets[pick];
      if (ties == 1) break;
      cap = static_cast<int>(size(pick));  // the loop's −1 goes below the tied size
    }
    active[k][1] = chosen[0];
    active[k][2] = chosen[1];
    active[k][4] = chosen[2];
    active[k][5] = chosen[3];
    active[k][3] = chosen[4];
    if (!alternatives || scored.empty()) continue;
    double lowest = std::numeric_limits<double>::infinity();
    size_t at = 0;
    for (size_t j = 0; j < scored.size(); ++j) {
      lowest = std::min(lowest, scored[j].first);
      if (kSets[scored[j].second] == chosen) at = j;
    }
    for (size_t j = 0; j < scored.size(); ++j) {
      if (j == at || scored[j].first > lowest + kAlike) continue;
      Phi d{};
      for (int t = 0; t < OperatingLaw::kMaxTerms; ++t) d[t] = coefs[j][t] - coefs[at][t];
      alternatives->emplace_back(k, d);
    }
  }
}

}  // namespace

namespace {

/// The law of the header with the shape in f ℓ_λ, λ = f_power.
OperatingLaw FitShape(const HgannFitness& fitness, const std::vector<CaseEstimate>& estimates,
                      const TrendSeedOptions& options, double f_power) {
  const HgannFitnessConfig& cfg = fitness.config();
  OperatingLaw law;
  law.f_power = f_power;
  Active active{};
  for (auto& a : active) a = {true, true, true, false, false, false};
  const bool interaction = InteractionDetermined(LawBasis(cfg, true, active, f_power));
  for (auto& a : active) a[3] = interaction;
  SelectTerms(LawBasis(cfg, interaction, active, f_power), estimates, active, &law.alternatives);
  const LawBasis basis(cfg, interaction, active, f_power);
  law.interaction = interaction;
  law.active = active;
  int terms = 0;
  for (const auto& a : active)
    terms = std::max(terms, static_cast<int>(std::count(a.begin(), a.end(), true)));
  law.terms = terms;
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
  law.map_cost = best.cost;
  for (int k = 0; k < kOut; ++k)
    for (int t = 0; t < basis.terms; ++t) law.coef[k][t] = best.x[basis.terms * k + t];
  Posterior(basis, best, law);
  law.network = basis.Network(best.x);
  law.theta = best.x;
  law.cost = fitness.EvaluateNetwork(law.network).cost;
  for (const HgannCaseResult& c : fitness.EvaluateCases(law.network))
    if (c.training) law.data_cost += c.pi;
  law.simulations += static_cast<int64_t>(cfg.cases.size() + basis.training.size());
  return law;
}

}  // namespace

OperatingLaw FitOperatingLaw(const HgannFitness& fitness,
                             const std::vector<CaseEstimate>& estimates,
                             const TrendSeedOptions& options) {
  OperatingLaw kept;
  std::vector<OperatingLaw::Shape> shapes;
  int64_t simulations = 0;
  for (const double power : OperatingLaw::kFPowers) {
    OperatingLaw law = FitShape(fitness, estimates, options, power);
    simulations += law.simulations;
    if (!law.ok) continue;
    shapes.push_back({power, law.map_cost, law.interaction, law.active, law.theta});
    if (!kept.ok || law.map_cost < kept.map_cost) kept = std::move(law);
  }
  kept.shapes = std::move(shapes);
  kept.simulations = simulations;
  return kept;
}

namespace {

/// A member of the committee: its parameters at every case of the configuration, then at every
/// point of the user's list (nullopt where its loop is unbounded).
using MemberParams = std::vector<std::optional<Array7>>;

bool Bounded(const Array7& p) {
  model::BimorphParams bp;
  bp.alpha = p[2];
  bp.beta = p[3];
  bp.gamma = p[4];
  return bp.HysteresisBounded();
}

/// θ's parameters at `points` under `basis`.
MemberParams ParamsAt(const LawBasis& basis, const std::vector<double>& th,
                      const std::vector<Phi>& points) {
  MemberParams out;
  for (const Phi& phi : points)
    out.push_back(basis.LoopBounded(th, phi) ? std::optional<Array7>(basis.Params(th, phi))
                                             : std::nullopt);
  return out;
}

/// The posterior members (CommitteeOf): the law moved one posterior σ either way along each
/// direction the prior settles; empty when the law's MAP cost cannot be evaluated.
std::vector<std::vector<double>> PosteriorMembers(const HgannFitness& fitness,
                                                  const OperatingLaw& law, const LawBasis& basis,
                                                  int threads, int64_t* evaluations) {
  constexpr int kT = OperatingLaw::kMaxTerms;
  LawResiduals residuals(fitness, basis, std::sqrt(law.sigma2));
  const opt::ResidualFunction f = [&](std::span<const double> th, std::vector<double>& r) {
    return residuals(th, r);
  };
  const std::vector<double>& x = law.theta;
  std::vector<double> r0;
  const int n = kT * kOut;
  std::vector<double> lower(n, -3.0), upper(n, 3.0);
  Eigen::MatrixXd j;
  if (!f(x, r0) ||
      !opt::NumericJacobian(f, x, r0, lower, upper, 1e-3, true, std::max(1, threads), j,
                            evaluations))
    return {};
  // Posterior covariance and its directions the prior settles (prior variance τ² of each term).
  const Eigen::MatrixXd cov = InformationCovariance(basis, j, law.sigma2);
  Eigen::VectorXd tau(n);
  for (int i = 0; i < n; ++i) tau(i) = basis.Tau(i / kT, i % kT);
  // In the prior's units (θ_i / τ_i) the prior's covariance is I: a direction whose posterior
  // variance stays above kPriorShare is one the data leave to the prior.
  Eigen::MatrixXd scaled = tau.asDiagonal().inverse() * cov * tau.asDiagonal().inverse();
  // The loop's α, β, γ (outputs 2–4) are held at the law's: they trade along a valley (one of
  // them moved alone by its prior's σ leaves the loop unbounded, or is taken back by the
  // others), so their directions are not a trend's (as in hgann/extrapolation.h).
  for (int i = 0; i < n; ++i)
    if ((i / kT >= 2 && i / kT <= 4) || !law.active[i / kT][i % kT])
      scaled.row(i).setZero(), scaled.col(i).setZero();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (scaled + scaled.transpose()));
  std::vector<std::vector<double>> members;
  for (int i = n - 1; i >= 0 && members.size() < 12; --i) {
    if (eig.eigenvalues()(i) < OperatingLaw::kPriorShare) break;
    const Eigen::VectorXd step =
        tau.asDiagonal() * eig.eigenvectors().col(i) * std::sqrt(eig.eigenvalues()(i));
    for (double sign : {1.0, -1.0}) {
      // Shortened (halved, at most 6 times) while its loop is unbounded at a case or a point of
      // the grid: a law the fitness refuses is no member (the prior's σ along a direction of the
      // loop's α, β, γ reaches beyond their bounded region).
      for (double scale = 1; scale > 0.01; scale *= 0.5) {
        std::vector<double> m = x;
        for (int c = 0; c < n; ++c) m[c] += sign * scale * step(c);
        bool bounded = true;
        for (const auto* points : {&basis.at_cases, &basis.at_grid})
          for (const Phi& phi : *points) bounded = bounded && basis.LoopBounded(m, phi);
        if (!bounded) continue;
        members.push_back(std::move(m));
        break;
      }
    }
  }
  return members;
}

/// The committee's shapes (CommitteeOf): for μ, δ, a1 and a2, the law moved by each other term set
/// that fits the per-case estimates alike (OperatingLaw::alternatives: a curvature in V against
/// one in f, where the estimates cannot tell them), and, when the law has no V·f term because the
/// training cases cannot show one, along the training design's null direction in its terms and
/// the interaction, either way, with an interaction d as large as the parameter's own largest
/// slope (at least 1 % of its range): a V·f term of the size of the trend itself.
std::vector<std::vector<double>> ShapeMembers(const OperatingLaw& law, const LawBasis& basis) {
  constexpr int kT = OperatingLaw::kMaxTerms;
  const std::vector<double>& x = law.theta;
  std::vector<std::vector<double>> members;
  for (const auto& [k, d] : law.alternatives) {
    std::vector<double> m = x;
    for (int t = 0; t < kT; ++t) m[kT * k + t] += d[t];
    members.push_back(std::move(m));
  }
  for (int k : {0, 1, 5, 6}) {
    if (law.interaction || basis.at_train.empty()) break;
    std::vector<int> cols;  // the parameter's terms and the interaction
    for (int t = 0; t < kT; ++t)
      if (law.active[k][t] || t == 3) cols.push_back(t);
    const int p = static_cast<int>(cols.size());
    Eigen::MatrixXd design(static_cast<int>(basis.at_train.size()), p);
    for (size_t r = 0; r < basis.at_train.size(); ++r)
      for (int c = 0; c < p; ++c) design(static_cast<int>(r), c) = basis.at_train[r][cols[c]];
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(design, Eigen::ComputeFullV);
    const Eigen::VectorXd null = svd.matrixV().col(p - 1);
    const int id = static_cast<int>(std::find(cols.begin(), cols.end(), 3) - cols.begin());
    if (std::abs(null(id)) < 1e-9) continue;
    const double size = std::max({std::abs(x[kT * k + 1]), std::abs(x[kT * k + 2]), 0.01});
    for (double sign : {1.0, -1.0}) {
      std::vector<double> m = x;
      for (int c = 0; c < p; ++c) m[kT * k + cols[c]] += sign * size * null(c) / null(id);
      members.push_back(std::move(m));
    }
  }
  return members;
}

/// The case a point of the user's list is simulated as: the training case nearest it in
/// (x_V, x_f), at the point's (V, f) with that case's sample rate, cycles and saturations.
HgannCase CandidateCase(const HgannFitnessConfig& cfg, double v, double f) {
  const auto& norm = cfg.normalization;
  const HgannCase* nearest = nullptr;
  double best = std::numeric_limits<double>::infinity();
  for (const HgannCase& c : cfg.cases) {
    if (!c.training) continue;
    const double dv = norm.NormalizeAmplitude(c.drive.amplitude_v) - norm.NormalizeAmplitude(v);
    const double df =
        norm.NormalizeFrequency(c.drive.frequency_hz) - norm.NormalizeFrequency(f);
    if (dv * dv + df * df < best) best = dv * dv + df * df, nearest = &c;
  }
  HgannCase out = nearest ? *nearest : cfg.cases.front();
  out.number = 0;
  out.training = false;
  out.drive.amplitude_v = v;
  out.drive.frequency_hz = f;
  out.measured_deg.assign(static_cast<size_t>(std::max(2, out.drive.NumSamples())), 0.0);
  return out;
}

/// Query by committee (CommitteeOf): the candidates ranked by what stays open were each measured.
void RankCandidates(const HgannFitnessConfig& cfg, const std::vector<std::vector<double>>& dis,
                    const std::vector<double>& cand_floor, const std::vector<int>& cand_point,
                    LawCommittee& out) {
  const size_t n_cases = cfg.cases.size();
  std::vector<std::tuple<double, double, int>> ranked;  // (remaining, −own disagreement, cand)
  for (size_t c = 0; c < out.candidates.size(); ++c) {
    const size_t at = static_cast<size_t>(cand_point[c]);
    double remaining = 0, own = 0;
    for (size_t t = 0; t < n_cases; ++t) {
      if (static_cast<int>(t) == out.candidates[c].case_index || cfg.cases[t].training) continue;
      double worst = 0;
      for (size_t m = 0; m < dis.size(); ++m)
        if (dis[m][at] < 2 * cand_floor[c]) worst = std::max(worst, dis[m][t]);
      remaining += std::min(worst / out.floor[t], 1e6);
    }
    for (size_t m = 0; m < dis.size(); ++m) own = std::max(own, dis[m][at]);
    ranked.emplace_back(remaining, -std::min(own / cand_floor[c], 1e6), static_cast<int>(c));
  }
  std::sort(ranked.begin(), ranked.end());
  for (const auto& [remaining, own, cand] : ranked) out.next.emplace_back(cand, remaining);
}

}  // namespace

LawCommittee CommitteeOf(const HgannFitness& fitness, const OperatingLaw& law,
                         const CommitteeOptions& options) {
  const HgannFitnessConfig& cfg = fitness.config();
  LawCommittee out;
  const size_t n_cases = cfg.cases.size();
  out.floor.assign(n_cases, 0.0);
  out.disagreement.assign(n_cases, 0.0);
  out.kept_disagreement.assign(n_cases, 0.0);
  out.open.assign(n_cases, false);
  constexpr int kT = OperatingLaw::kMaxTerms;
  if (!law.ok || law.theta.size() != static_cast<size_t>(kT * kOut)) return out;
  // The points: every case, then the user's list.
  std::vector<HgannCase> points(cfg.cases.begin(), cfg.cases.end());
  for (const auto& [v, f] : options.candidates) points.push_back(CandidateCase(cfg, v, f));
  const LawBasis basis(cfg, true, law.active, law.f_power);
  std::vector<Phi> at_points = basis.at_cases;
  for (size_t i = n_cases; i < points.size(); ++i)
    at_points.push_back(basis.At(points[i].drive.amplitude_v, points[i].drive.frequency_hz));
  int64_t evaluations = 0;
  std::vector<MemberParams> members;
  const auto posterior = PosteriorMembers(fitness, law, basis, options.threads, &evaluations);
  const auto shapes = ShapeMembers(law, basis);
  for (const auto* set : {&posterior, &shapes})
    for (const std::vector<double>& th : *set) members.push_back(ParamsAt(basis, th, at_points));
  for (const OperatingLaw::Shape& s : law.shapes) {
    if (s.f_power == law.f_power ||
        s.map_cost > law.map_cost + OperatingLaw::kShapeAlike * law.sigma2)
      continue;
    const LawBasis other(cfg, true, s.active, s.f_power);
    std::vector<Phi> at;
    for (const HgannCase& c : points)
      at.push_back(other.At(c.drive.amplitude_v, c.drive.frequency_hz));
    members.push_back(ParamsAt(other, s.theta, at));
  }
  int kept = -1;
  if (options.kept) {
    MemberParams m;
    for (const HgannCase& c : points) {
      const Array7 p = options.kept->Predict(c.drive.amplitude_v, c.drive.frequency_hz).ToArray();
      m.push_back(Bounded(p) ? std::optional<Array7>(p) : std::nullopt);
    }
    kept = static_cast<int>(members.size());
    members.push_back(std::move(m));
  }
  out.members = static_cast<int>(members.size());
  out.lo.resize(n_cases);
  out.hi.resize(n_cases);
  // Each point's prediction under the law and under every member.
  std::vector<std::vector<double>> dis(members.size(), std::vector<double>(points.size(), 0.0));
  std::vector<double> point_floor(points.size(), 0.0);
  for (size_t i = 0; i < points.size(); ++i) {
    const HgannCase& c = points[i];
    point_floor[i] = law.sigma2 * static_cast<double>(c.measured_deg.size());
    const Array7 p0 = basis.Params(law.theta, at_points[i]);
    if (i < n_cases) out.floor[i] = point_floor[i], out.lo[i] = out.hi[i] = p0;
    std::vector<double> y0(c.measured_deg.size()), y(c.measured_deg.size());
    ++out.simulations;
    if (!fitness.SimulateCase(model::NetworkParameters::FromArray(p0), c, y0)) continue;
    for (size_t m = 0; m < members.size(); ++m) {
      const std::optional<Array7>& p = members[m][i];
      double d = 0;
      ++out.simulations;
      if (!p || !fitness.SimulateCase(model::NetworkParameters::FromArray(*p), c, y)) {
        d = std::numeric_limits<double>::infinity();
      } else {
        for (size_t k = 0; k < y.size(); ++k) d += (y[k] - y0[k]) * (y[k] - y0[k]);
        if (i < n_cases)
          for (int k = 0; k < kOut; ++k)
            out.lo[i][k] = std::min(out.lo[i][k], (*p)[k]),
            out.hi[i][k] = std::max(out.hi[i][k], (*p)[k]);
      }
      dis[m][i] = d;
      if (i < n_cases) out.disagreement[i] = std::max(out.disagreement[i], d);
      if (i < n_cases && static_cast<int>(m) == kept) out.kept_disagreement[i] = d;
    }
    if (i < n_cases) out.open[i] = !c.training && out.disagreement[i] >= 2 * out.floor[i];
  }
  // The candidates: the user's points, or every withheld case.
  std::vector<int> cand_point;
  std::vector<double> cand_floor;
  for (size_t i = 0; i < points.size(); ++i) {
    const bool user = i >= n_cases;
    if (options.candidates.empty() ? (user || cfg.cases[i].training) : !user) continue;
    out.candidates.push_back({points[i].drive.amplitude_v, points[i].drive.frequency_hz,
                              user ? -1 : static_cast<int>(i)});
    cand_point.push_back(static_cast<int>(i));
    cand_floor.push_back(point_floor[i]);
  }
  RankCandidates(cfg, dis, cand_floor, cand_point, out);
  out.simulations += evaluations;
  return out;
}

std::string PriorSettledNames(const OperatingLaw& law) {
  static constexpr const char* kNames[kOut] = {"μ", "δ", "α", "β", "γ", "a1", "a2"};
  std::string out;
  for (int k = 0; k < kOut; ++k)
    if (!law.data_settled[k]) out += (out.empty() ? "" : ", ") + std::string(kNames[k]);
  return out;
}

}  // namespace pz::hgann
