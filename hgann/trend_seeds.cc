#include "hgann/trend_seeds.h"

#include <Eigen/Dense>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>

#include "model/chromosome.h"
#include "opt/lm.h"

namespace pz::hgann {
namespace {

constexpr int kOut = model::kNetworkOutputs;
/// Smallest σ of a per-case estimate in the structure selection, as a share of the range.
constexpr double kMinSigmaShare = 0.005;
using Array7 = std::array<double, kOut>;

model::NetworkParameters ToParams(std::span<const double> s, const model::ParameterRanges& ranges) {
  Array7 p{};
  for (int k = 0; k < kOut; ++k) {
    const double u = std::clamp(s[k], 0.0, 1.0);
    p[k] = ranges[k].lower + u * (ranges[k].upper - ranges[k].lower);
  }
  return model::NetworkParameters::FromArray(p);
}

/// The i-th point of the Halton sequence in [0, 1)^7 (bases 2 … 17).
Array7 Halton(int i) {
  static constexpr int kBases[kOut] = {2, 3, 5, 7, 11, 13, 17};
  Array7 x{};
  for (int k = 0; k < kOut; ++k) {
    double f = 1, r = 0;
    for (int n = i; n > 0; n /= kBases[k]) {
      f /= kBases[k];
      r += f * (n % kBases[k]);
    }
    x[k] = r;
  }
  return x;
}

/// The fixed starts of a per-case fit: a physical guess (light damping, a loop in the middle of its
/// ranges, small backlash), then Halton points inside [0.05, 0.95]⁷ (backlash in [0.01, 0.2]).
std::vector<std::vector<double>> CaseStarts(int count) {
  std::vector<std::vector<double>> out;
  out.push_back({0.3, 0.2, 0.5, 0.5, 0.5, 0.05, 0.05});
  for (int i = 1; static_cast<int>(out.size()) < count; ++i) {
    const Array7 h = Halton(i);
    std::vector<double> s(kOut);
    for (int k = 0; k < kOut; ++k) s[k] = k >= 5 ? 0.01 + 0.19 * h[k] : 0.05 + 0.9 * h[k];
    out.push_back(std::move(s));
  }
  return out;
}

/// 1-σ of each coordinate from the Jacobian: √(s² diag (JᵀJ)⁺), +inf where a column is (nearly) in
/// the null space.
std::vector<double> Sigmas(const Eigen::MatrixXd& j, double cost) {
  const int n = static_cast<int>(j.cols());
  std::vector<double> out(n, std::numeric_limits<double>::infinity());
  if (n == 0 || j.rows() <= n) return out;
  const double s2 = cost / static_cast<double>(j.rows() - n);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(j, Eigen::ComputeThinV);
  const Eigen::VectorXd& sv = svd.singularValues();
  const double cut = sv.size() ? sv(0) * 1e-6 : 0;
  for (int k = 0; k < n; ++k) {
    double var = 0;
    bool weak = false;
    for (int m = 0; m < sv.size(); ++m) {
      const double v = svd.matrixV()(k, m);
      if (sv(m) <= cut) {
        weak = weak || std::abs(v) > 1e-3;
        continue;
      }
      var += v * v / (sv(m) * sv(m));
    }
    if (!weak) out[k] = std::sqrt(s2 * var);
  }
  return out;
}

double Clamp01(double x) { return std::clamp(x, 0.0, 1.0); }

}  // namespace

model::Network SatlinSkeleton(int hidden) {
  using model::TransferFunction;
  model::Network n;
  n.input_tf = {TransferFunction::kSatlin, TransferFunction::kSatlin};
  n.hidden_tf.assign(hidden, TransferFunction::kSatlin);
  n.output_tf.fill(TransferFunction::kSatlin);
  n.w1 = Eigen::MatrixXd::Zero(2, hidden);
  n.c1 = Eigen::VectorXd::Zero(hidden);
  n.w1(0, 0) = 1;
  n.w1(1, 1) = 1;
  return n;
}

model::Network TrendNetwork(double knot_v, double knot_f, const std::vector<double>& c2,
                            const std::vector<std::vector<double>>& w2,
                            const model::InputNormalization& normalization,
                            const model::ParameterRanges& ranges) {
  std::vector<std::pair<int, double>> hinges;  // (input, knot)
  if (knot_v > 0 && knot_v < 0.9) hinges.emplace_back(0, knot_v);
  if (knot_f > 0 && knot_f < 0.9) hinges.emplace_back(1, knot_f);
  const int h = 2 + static_cast<int>(hinges.size());
  model::Network n = SatlinSkeleton(h);
  for (size_t m = 0; m < hinges.size(); ++m) {
    const auto [input, knot] = hinges[m];
    n.w1(input, 2 + m) = 1 / (1 - knot);
    n.c1(2 + m) = -knot / (1 - knot);
  }
  n.w2 = Eigen::MatrixXd::Zero(h, kOut);
  n.c2 = Eigen::VectorXd::Zero(kOut);
  for (int k = 0; k < kOut; ++k) {
    if (k < static_cast<int>(c2.size()))
      n.c2(k) = std::clamp(c2[k], model::kWeightMin, model::kWeightMax);
    for (int j = 0; j < h; ++j)
      if (j < static_cast<int>(w2.size()) && k < static_cast<int>(w2[j].size()))
        n.w2(j, k) = std::clamp(w2[j][k], model::kWeightMin, model::kWeightMax);
  }
  n.normalization = normalization;
  n.ranges = ranges;
  return n;
}

std::vector<CaseEstimate> FitCases(const HgannFitness& fitness,
                                   const std::vector<int>& case_indices,
                                   const TrendSeedOptions& options, int64_t* simulations,
                                   const Array7* hold, const Array7* start) {
  const HgannFitnessConfig& cfg = fitness.config();
  std::vector<int> free;  // the fitted coordinates (the others held)
  for (int k = 0; k < kOut; ++k)
    if (!hold || std::isnan((*hold)[k])) free.push_back(k);
  const int nf = static_cast<int>(free.size());
  const auto full = [&](std::span<const double> x) {
    Array7 s{};
    for (int k = 0; k < kOut; ++k) s[k] = hold && !std::isnan((*hold)[k]) ? (*hold)[k] : 0.0;
    for (int m = 0; m < nf; ++m) s[free[m]] = x[m];
    return s;
  };
  std::atomic<int64_t> sims{0};
  opt::LmOptions lm;
  lm.max_iterations = options.lm_iterations;
  lm.threads = std::max(1, options.threads);
  const std::vector<double> lower(nf, 0.0), upper(nf, 1.0);
  std::vector<std::vector<double>> fixed;
  for (const auto& s : CaseStarts(std::max(1, options.case_starts))) {
    std::vector<double> x;
    for (int k : free) x.push_back(s[k]);
    fixed.push_back(std::move(x));
  }
  std::vector<CaseEstimate> out;
  std::vector<double> previous;
  for (int index : case_indices) {
    const HgannCase& c = cfg.cases.at(index);
    const opt::ResidualFunction residual = [&](std::span<const double> s, std::vector<double>& r) {
      r.resize(c.measured_deg.size());
      ++sims;
      if (!fitness.SimulateCase(ToParams(full(s), cfg.ranges), c, r)) return false;
      for (size_t k = 0; k < r.size(); ++k) r[k] -= c.measured_deg[k];
      return true;
    };
    std::vector<std::vector<double>> starts;
    if (start) {
      starts.emplace_back();
      for (int k : free) starts.back().push_back(std::clamp((*start)[k], 0.0, 1.0));
    } else {
      if (!previous.empty()) starts.push_back(previous);
      for (const auto& s : fixed) starts.push_back(s);
    }
    opt::LmResult best;
    best.cost = std::numeric_limits<double>::infinity();
    for (const auto& s0 : starts) {
      opt::LmResult r = opt::LevenbergMarquardt(residual, s0, lower, upper, lm);
      if (std::isfinite(r.cost) && r.cost < best.cost) best = std::move(r);
    }
    CaseEstimate e;
    e.number = c.number;
    e.amplitude_v = c.drive.amplitude_v;
    e.frequency_hz = c.drive.frequency_hz;
    e.ok = std::isfinite(best.cost);
    e.pi = best.cost;
    if (e.ok) {
      // σ of white residuals, inflated by √((1 + ρ)/(1 − ρ)) for their lag-1 autocorrelation ρ
      // (encoder rounding of a slow signal and the model's own error are not white).
      double num = 0, den = 0;
      for (size_t k = 0; k < best.r.size(); ++k) {
        den += best.r[k] * best.r[k];
        if (k > 0) num += best.r[k] * best.r[k - 1];
      }
      const double rho = den > 0 ? std::clamp(num / den, 0.0, 0.95) : 0.0;
      const double inflation = std::sqrt((1 + rho) / (1 - rho));
      if (static_cast<int>(best.r.size()) > nf)
        e.residual_var =
            best.cost / static_cast<double>(best.r.size() - nf) * inflation * inflation;
      std::vector<double> sigma = Sigmas(best.jacobian, best.cost);
      const Array7 x = full(best.x);
      e.sigma.fill(std::numeric_limits<double>::infinity());
      for (int k = 0; k < kOut; ++k) {
        const double width = cfg.ranges[k].upper - cfg.ranges[k].lower;
        e.s[k] = x[k];
        e.value[k] = cfg.ranges[k].lower + x[k] * width;
      }
      for (int m = 0; m < nf; ++m)
        e.sigma[free[m]] =
            sigma[m] * inflation * (cfg.ranges[free[m]].upper - cfg.ranges[free[m]].lower);
      previous = best.x;
    } else {
      e.sigma.fill(std::numeric_limits<double>::infinity());
    }
    out.push_back(e);
  }
  if (simulations) *simulations += sims.load();
  return out;
}

namespace {

/// The middle level of the training cases' normalised input values strictly inside (0, 1) (the
/// one nearest 0.5), or −1 when there is none.
double Knot(std::vector<double> x) {
  std::sort(x.begin(), x.end());
  double best = -1;
  for (double v : x)
    if (v > 1e-9 && v < 1 - 1e-9 && (best < 0 || std::abs(v - 0.5) < std::abs(best - 0.5)))
      best = v;
  return best;
}

// A parameter that half the training cases or more do not pin down (σ infinite or above a quarter
// of its range: μ against δ on the fin, whose damping one frequency sees as one number) is held
// at the median of its per-case values and the cases refitted: their estimates of the other
// parameters then belong to one value of it, which a network can take. One at a time, the
// loosest first (ties: the first): μ and δ are loose together, and holding μ pins δ down
// (holding both left δ constant on trends-dev2, whose δ varies).
void HoldLooseParameters(const HgannFitness& fitness, const std::vector<int>& training,
                         const TrendSeedOptions& options, TrendSeeds& out) {
  const HgannFitnessConfig& cfg = fitness.config();
  Array7 hold;
  hold.fill(std::nan(""));
  for (int round = 0; round < kOut; ++round) {
    int pick = -1, most = 0;
    for (int k = 0; k < kOut; ++k) {
      if (!std::isnan(hold[k])) continue;
      const double width = cfg.ranges[k].upper - cfg.ranges[k].lower;
      int n = 0, loose = 0;
      for (const CaseEstimate& e : out.cases) {
        if (!e.ok) continue;
        ++n;
        loose += !(std::isfinite(e.sigma[k]) && e.sigma[k] <= 0.25 * width);
      }
      if (n > 0 && 2 * loose >= n && loose > most) pick = k, most = loose;
    }
    if (pick < 0) break;
    std::vector<double> values;
    for (const CaseEstimate& e : out.cases)
      if (e.ok) values.push_back(e.s[pick]);
    std::sort(values.begin(), values.end());
    const size_t n = values.size();
    hold[pick] = n % 2 ? values[n / 2] : 0.5 * (values[n / 2 - 1] + values[n / 2]);
    out.cases = FitCases(fitness, training, options, &out.simulations, &hold);
  }
}

constexpr int kGrid = 5;  // the spread penalty's grid (HgannFitness::GridOf)

/// What steps 2 and 3 share: the template network (the hidden layer of every seed, file comment,
/// step 2, as the chromosome holds it), its hidden outputs at the training cases and over the
/// spread penalty's grid, and the layout of θ = (c2_k, W2(0, k) … W2(h − 1, k)) for k = 0 … 6:
/// (h + 1) · 7 coordinates.
struct TrendBasis {
  const HgannFitnessConfig& cfg;
  const std::vector<int>& training;
  const std::vector<CaseEstimate>& cases;
  model::Network net0;
  int h = 0, per = 0, n_theta = 0;
  std::vector<std::vector<double>> b_train, b_grid, b_cases;  ///< b_cases: every case, any role
  std::vector<int> rows;  ///< the cases whose per-case fit succeeded

  TrendBasis(const HgannFitnessConfig& config, const std::vector<int>& train,
             const std::vector<CaseEstimate>& estimates)
      : cfg(config), training(train), cases(estimates) {
    const auto& norm = cfg.normalization;
    std::vector<double> xv, xf;
    for (int i : training) {
      xv.push_back(norm.NormalizeAmplitude(cfg.cases[i].drive.amplitude_v));
      xf.push_back(norm.NormalizeFrequency(cfg.cases[i].drive.frequency_hz));
    }
    net0 = model::DecodeChromosome(
        model::EncodeChromosome(TrendNetwork(Knot(xv), Knot(xf), {}, {}, norm, cfg.ranges)), norm,
        cfg.ranges);
    h = net0.hidden();
    for (int i : training)
      b_train.push_back(Hidden(cfg.cases[i].drive.amplitude_v, cfg.cases[i].drive.frequency_hz));
    for (const HgannCase& c : cfg.cases)
      b_cases.push_back(Hidden(c.drive.amplitude_v, c.drive.frequency_hz));
    for (int i = 0; i < kGrid; ++i)
      for (int j = 0; j < kGrid; ++j)
        b_grid.push_back(Hidden(
            norm.amplitude_lo_v + (norm.amplitude_hi_v - norm.amplitude_lo_v) * i / (kGrid - 1),
            norm.frequency_lo_hz +
                (norm.frequency_hi_hz - norm.frequency_lo_hz) * j / (kGrid - 1)));
    per = h + 1;
    n_theta = per * kOut;
    for (size_t m = 0; m < cases.size(); ++m)
      if (cases[m].ok) rows.push_back(static_cast<int>(m));
  }

  std::vector<double> Hidden(double v, double f) const {
    const Eigen::VectorXd b = net0.Forward(v, f).b;
    return std::vector<double>(b.data(), b.data() + b.size());
  }

  /// Output k's scaled parameter under θ at hidden outputs b.
  double S(std::span<const double> th, const std::vector<double>& b, int k) const {
    double n = th[per * k];
    for (int j = 0; j < h; ++j) n += th[per * k + 1 + j] * b[j];
    return Clamp01(n);
  }

  /// Whether the loop's parameters under θ are bounded at every training case and grid point.
  bool LoopBounded(const std::vector<double>& th) const {
    for (const auto* points : {&b_train, &b_grid})
      for (const std::vector<double>& b : *points) {
        std::array<double, kOut> s{};
        for (int k = 0; k < kOut; ++k) s[k] = S(th, b, k);
        if (!hgann::LoopBounded(ToParams(s, cfg.ranges))) return false;
      }
    return true;
  }
};

// Step 2a: least squares of the per-case s on (1, B) (minimum norm: the training cases are fewer
// than the coordinates), and on (1, x_V, x_f) alone (the hinges' weights 0).
std::vector<double> Regress(const TrendBasis& t, int columns) {
  std::vector<double> th(t.n_theta, 0.0);
  const int per = t.per;
  if (t.rows.empty()) {
    const Array7 guess = {0.3, 0.2, 0.5, 0.5, 0.5, 0.05, 0.05};
    for (int k = 0; k < kOut; ++k) th[per * k] = guess[k];
    return th;
  }
  Eigen::MatrixXd a(static_cast<int>(t.rows.size()), 1 + columns),
      y(static_cast<int>(t.rows.size()), kOut);
  for (size_t r = 0; r < t.rows.size(); ++r) {
    a(r, 0) = 1.0;
    for (int j = 0; j < columns; ++j) a(r, 1 + j) = t.b_train[t.rows[r]][j];
    for (int k = 0; k < kOut; ++k) y(r, k) = t.cases[t.rows[r]].s[k];
  }
  const Eigen::MatrixXd coef = a.completeOrthogonalDecomposition().solve(y);
  for (int k = 0; k < kOut; ++k)
    for (int j = 0; j <= columns; ++j) th[per * k + j] = std::clamp(coef(j, k), -3.0, 3.0);
  return th;
}

/// The structured start (step 2a') and which of its coordinates are free; per case of the
/// configuration, the scaled range of the shapes the estimates support alike (TrendSeeds).
struct Structured {
  std::vector<double> theta;
  std::vector<char> free;
  std::vector<Array7> lo, hi;
};

// Step 2a': per parameter, the structure its per-case estimates support (file comment): the
// hidden nodes of each candidate, simplest first; the lowest χ² + 2 p wins (ties: the flatter
// over the grid, then the simpler). (A leave-one-case-out choice was measured worse on both
// development benches: with four training cases every case left out is an extrapolation, and
// it chose constants where the trend is real: the history of docs/performance.md.)
Structured ChooseStructures(const TrendBasis& t, const std::vector<double>& regression) {
  const int h = t.h, per = t.per;
  const std::vector<int>& rows = t.rows;
  const bool hinge_v = h > 2 && t.net0.w1(0, 2) != 0, hinge_f = h > 2 && t.net0.w1(1, h - 1) != 0;
  const int iv = 0, jf = 1, hv = hinge_v ? 2 : -1, hf = hinge_f ? h - 1 : -1;
  std::vector<std::vector<int>> structures = {{}, {iv}, {jf}, {iv, jf}};
  if (hv >= 0) structures.push_back({iv, hv});
  if (hf >= 0) structures.push_back({jf, hf});
  if (hv >= 0) structures.push_back({iv, jf, hv});
  if (hf >= 0) structures.push_back({iv, jf, hf});
  std::vector<double> structured(t.n_theta, 0.0);
  std::vector<char> free_theta(t.n_theta, 0);
  std::vector<Array7> lo(t.b_cases.size()), hi(t.b_cases.size());
  for (int k = 0; k < kOut; ++k) {
    const double width = t.cfg.ranges[k].upper - t.cfg.ranges[k].lower;
    double best_score = std::numeric_limits<double>::infinity(), best_var = 0;
    std::vector<std::pair<double, std::vector<double>>> at_cases;  // (score, value per case)
    size_t chosen = 0;
    for (const std::vector<int>& cols : structures) {
      const int p = 1 + static_cast<int>(cols.size());
      if (p > static_cast<int>(rows.size()) && !cols.empty()) continue;
      Eigen::MatrixXd a(static_cast<int>(rows.size()), p);
      Eigen::VectorXd y(static_cast<int>(rows.size()));
      for (size_t r = 0; r < rows.size(); ++r) {
        const CaseEstimate& e = t.cases[rows[r]];
        const double sd = width > 0 && std::isfinite(e.sigma[k])
                              ? std::max(e.sigma[k] / width, kMinSigmaShare)
                              : 0.25;
        a(r, 0) = 1.0 / sd;
        for (int m = 0; m < static_cast<int>(cols.size()); ++m)
          a(r, 1 + m) = t.b_train[rows[r]][cols[m]] / sd;
        y(r) = e.s[k] / sd;
      }
      if (rows.empty()) break;
      const Eigen::VectorXd coef = a.completeOrthogonalDecomposition().solve(y);
      const double score = (a * coef - y).squaredNorm() + 2.0 * p;
      // Its variance over the penalty's grid (what the spread penalty charges) breaks a tie: two
      // shapes that fit the estimates alike (a hinge in V or in f through four cases) differ in
      // what they say between and beyond them, and the flatter one is what λ asks for.
      double mean = 0, var = 0;
      std::vector<double> g;
      for (const std::vector<double>& b : t.b_grid) {
        double v = coef(0);
        for (int m = 0; m < static_cast<int>(cols.size()); ++m) v += coef(1 + m) * b[cols[m]];
        g.push_back(Clamp01(v));
        mean += g.back() / static_cast<double>(t.b_grid.size());
      }
      for (double v : g) var += (v - mean) * (v - mean);
      std::vector<double> c_values;
      for (const std::vector<double>& b : t.b_cases) {
        double v = coef(0);
        for (int m = 0; m < static_cast<int>(cols.size()); ++m) v += coef(1 + m) * b[cols[m]];
        c_values.push_back(Clamp01(v));
      }
      at_cases.emplace_back(score, std::move(c_values));
      constexpr double kTie = 1e-6;
      const bool lower = score < best_score - kTie,
                 tie = std::abs(score - best_score) <= kTie && var < best_var;
      if (!cols.empty() && !lower && !tie) continue;  // the constant is always a candidate
      best_score = score;
      best_var = var;
      chosen = at_cases.size() - 1;
      for (int i = 0; i < per; ++i) structured[per * k + i] = 0.0, free_theta[per * k + i] = 0;
      structured[per * k] = std::clamp(coef(0), -2.0, 2.0);
      free_theta[per * k] = 1;
      for (int m = 0; m < static_cast<int>(cols.size()); ++m) {
        structured[per * k + 1 + cols[m]] = std::clamp(coef(1 + m), -3.0, 3.0);
        free_theta[per * k + 1 + cols[m]] = 1;
      }
    }
    if (rows.empty()) structured[per * k] = regression[per * k], free_theta[per * k] = 1;
    // The shapes within 2 of the chosen one's χ² + 2 p (Akaike's "substantial support"): their
    // range at each case is what the training cases leave open there.
    for (size_t i = 0; i < t.b_cases.size(); ++i) {
      lo[i][k] = hi[i][k] =
          rows.empty() ? Clamp01(regression[per * k]) : at_cases[chosen].second[i];
      for (const auto& [score, values] : at_cases)
        if (score <= best_score + 2 + 1e-6)
          lo[i][k] = std::min(lo[i][k], values[i]), hi[i][k] = std::max(hi[i][k], values[i]);
    }
  }
  return {std::move(structured), std::move(free_theta), std::move(lo), std::move(hi)};
}

/// The per-case estimates' mean per parameter, as a θ of constants.
std::vector<double> ConstantTheta(const TrendBasis& t, const std::vector<double>& regression) {
  std::vector<double> constant(t.n_theta, 0.0);
  for (int k = 0; k < kOut; ++k) {
    double sum = 0;
    for (int r : t.rows) sum += t.cases[r].s[k];
    constant[t.per * k] =
        t.rows.empty() ? regression[t.per * k] : sum / static_cast<double>(t.rows.size());
  }
  return constant;
}

/// Step 2b: the joint polish on the fitness's own cost: every training case's residuals and, with
/// λ > 0, √(λ / 25) (s_k(g) − mean_g s_k) over the grid (Σ of their squares = λ Σ_k Var_grid s_k),
/// a loop unbounded at a grid point refused as the fitness refuses it. LM over the free
/// coordinates only (the others stay 0).
class JointPolish {
 public:
  JointPolish(const HgannFitness& fitness, const TrendBasis& t, const TrendSeedOptions& options)
      : fitness_(fitness), t_(t), lo_(t.n_theta), hi_(t.n_theta) {
    grid_weight_ = std::sqrt(t.cfg.spread_penalty / (kGrid * kGrid));
    lm_.max_iterations = options.lm_iterations;
    lm_.threads = std::max(1, options.threads);
    for (int i = 0; i < t.n_theta; ++i) {
      lo_[i] = i % t.per == 0 ? -2.0 : -3.0;
      hi_[i] = i % t.per == 0 ? 2.0 : 3.0;
    }
  }

  std::vector<double> operator()(const std::vector<double>& th0, const std::vector<char>& free) {
    const int n_theta = t_.n_theta;
    std::vector<int> index;
    for (int i = 0; i < n_theta; ++i)
      if (free[i]) index.push_back(i);
    std::vector<double> x0, flo, fhi;
    for (int i : index) x0.push_back(th0[i]), flo.push_back(lo_[i]), fhi.push_back(hi_[i]);
    const opt::ResidualFunction reduced = [&](std::span<const double> x, std::vector<double>& r) {
      std::vector<double> th(n_theta, 0.0);
      for (size_t m = 0; m < index.size(); ++m) th[index[m]] = x[m];
      return Residuals(th, r);
    };
    const opt::LmResult r = opt::LevenbergMarquardt(reduced, x0, flo, fhi, lm_);
    std::vector<double> th = th0;
    if (std::isfinite(r.cost))
      for (size_t m = 0; m < index.size(); ++m) th[index[m]] = r.x[m];
    return th;
  }

  int64_t simulations() const { return sims_.load(); }

 private:
  bool Residuals(std::span<const double> th, std::vector<double>& r) {
    const HgannFitnessConfig& cfg = t_.cfg;
    r.clear();
    std::vector<double> angle;
    for (size_t m = 0; m < t_.training.size(); ++m) {
      const HgannCase& c = cfg.cases[t_.training[m]];
      std::array<double, kOut> s{};
      for (int k = 0; k < kOut; ++k) s[k] = t_.S(th, t_.b_train[m], k);
      angle.resize(c.measured_deg.size());
      ++sims_;
      if (!fitness_.SimulateCase(ToParams(s, cfg.ranges), c, angle)) return false;
      for (size_t k = 0; k < angle.size(); ++k) r.push_back(angle[k] - c.measured_deg[k]);
    }
    if (grid_weight_ > 0) {
      std::vector<std::array<double, kOut>> g(t_.b_grid.size());
      for (size_t i = 0; i < t_.b_grid.size(); ++i) {
        for (int k = 0; k < kOut; ++k) g[i][k] = t_.S(th, t_.b_grid[i], k);
        model::BimorphParams bp;
        const auto p = ToParams(g[i], cfg.ranges);
        bp.alpha = p.alpha;
        bp.beta = p.beta;
        bp.gamma = p.gamma;
        if (!bp.HysteresisBounded()) return false;
      }
      for (int k = 0; k < kOut; ++k) {
        double mean = 0;
        for (const auto& x : g) mean += x[k];
        mean /= static_cast<double>(g.size());
        for (const auto& x : g) r.push_back(grid_weight_ * (x[k] - mean));
      }
    }
    return true;
  }

  const HgannFitness& fitness_;
  const TrendBasis& t_;
  std::atomic<int64_t> sims_{0};
  double grid_weight_ = 0;
  opt::LmOptions lm_;
  std::vector<double> lo_, hi_;
};

struct Candidate {
  opt::Genome genome;
  double cost;
  std::string name;
};

/// The candidate's weight codes moved by ±1, ±4, ±16 while one lowers the fitness's cost (at most
/// three passes over the genes).
void PolishCodes(const HgannFitness& fitness, const std::vector<int>& genes, size_t cases,
                 Candidate& cand, int64_t& simulations) {
  static constexpr int kSteps[] = {1, -1, 4, -4, 16, -16};
  for (int pass = 0; pass < 3; ++pass) {
    bool improved = false;
    for (int gene : genes) {
      for (int step : kSteps) {
        const int code =
            static_cast<int>(model::ReadGene(cand.genome.bits, gene, model::kWeightCodeBits));
        const int next = code + step;
        if (next < 0 || next > static_cast<int>(model::kMaxWeightCode)) continue;
        opt::Genome trial = cand.genome;
        model::WriteGene(trial.bits, gene, model::kWeightCodeBits, static_cast<uint32_t>(next));
        const double cost = fitness.Evaluate(trial).cost;
        simulations += static_cast<int64_t>(cases);
        if (cost < cand.cost) {
          cand.genome = std::move(trial);
          cand.cost = cost;
          improved = true;
        }
      }
    }
    if (!improved) break;
  }
}

/// Step 3: the networks as chromosomes, their codes polished on the problem's own fitness; the
/// distinct ones into `out`, lowest cost first.
void AddSeeds(const HgannFitness& fitness, const TrendBasis& t, const TrendSeedOptions& options,
              const std::vector<std::pair<const std::vector<double>*, const char*>>& made,
              const std::vector<std::pair<model::Network, std::string>>& networks,
              TrendSeeds& out) {
  const int h = t.h, per = t.per;
  const auto encode = [&](const std::vector<double>& th) {
    model::Network n = t.net0;
    for (int k = 0; k < kOut; ++k) {
      n.c2(k) = std::clamp(th[per * k], model::kWeightMin, model::kWeightMax);
      for (int j = 0; j < h; ++j)
        n.w2(j, k) = std::clamp(th[per * k + 1 + j], model::kWeightMin, model::kWeightMax);
    }
    return model::EncodeChromosome(n);
  };
  std::vector<Candidate> candidates;
  std::vector<int> genes;
  for (int k = 0; k < kOut; ++k) {
    genes.push_back(model::C2Bit(k));
    for (int j = 0; j < h; ++j) genes.push_back(model::W2Bit(j, k));
  }
  const auto add = [&](std::vector<uint8_t> bits, const std::vector<int>& gene_list,
                       const std::string& name) {
    Candidate cand{opt::Genome{std::move(bits), {}}, 0, name};
    cand.cost = fitness.Evaluate(cand.genome).cost;
    out.simulations += static_cast<int64_t>(t.training.size());
    if (options.code_polish && !gene_list.empty())
      PolishCodes(fitness, gene_list, t.training.size(), cand, out.simulations);
    candidates.push_back(std::move(cand));
  };
  for (const auto& [theta, name] : made) add(encode(*theta), genes, name);
  // A network made elsewhere (the operating-point law) is code-polished but for μ's genes: the
  // polish knows only the fitness, and walked μ, which the data hardly see and whose level the
  // law's prior sets, to its bound for a cost lower by 1e-5 deg²; the others need it (δ's weight
  // quantum, 20 / 2¹⁴ of its range, moves a case's PI by more than its floor).
  for (const auto& [network, name] : networks) {
    std::vector<int> own;
    for (int k = 1; k < kOut; ++k) {
      own.push_back(model::C2Bit(k));
      for (int j = 0; j < network.hidden(); ++j) own.push_back(model::W2Bit(j, k));
    }
    add(model::EncodeChromosome(network), own, name);
  }
  std::stable_sort(candidates.begin(), candidates.end(),
                   [](const Candidate& a, const Candidate& b) { return a.cost < b.cost; });
  for (Candidate& c : candidates) {
    const bool duplicate =
        std::any_of(out.genomes.begin(), out.genomes.end(),
                    [&](const opt::Genome& g) { return g.bits == c.genome.bits; });
    if (duplicate) continue;
    out.genomes.push_back(std::move(c.genome));
    out.costs.push_back(c.cost);
    out.names.push_back(c.name);
  }
}

constexpr const char* kStructured[] = {"structured trend (polished)",
                                       "structured trend (polished from the constant)",
                                       "structured trend (regression)"};
constexpr const char* kLawSeed = "operating-point law (joint fit)";

/// The structured trends left out of the seeds when the law's seed costs at most kLawMargin ×
/// the best of them (TrendSeeds::law_kept).
void LeaveOutStructuredTrends(TrendSeeds& out) {
  const auto is_structured = [](const std::string& name) {
    return std::any_of(std::begin(kStructured), std::end(kStructured),
                       [&](const char* s) { return name == s; });
  };
  double law = std::numeric_limits<double>::infinity();
  double structured = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < out.names.size(); ++i) {
    if (out.names[i] == kLawSeed) law = out.costs[i];
    if (is_structured(out.names[i])) structured = std::min(structured, out.costs[i]);
  }
  out.law_cost = law;
  out.structured_cost = structured;
  out.law_kept = std::isfinite(law) && law <= kLawMargin * structured;
  if (!out.law_kept) return;
  for (size_t i = out.names.size(); i-- > 0;)
    if (is_structured(out.names[i])) {
      out.names.erase(out.names.begin() + static_cast<std::ptrdiff_t>(i));
      out.costs.erase(out.costs.begin() + static_cast<std::ptrdiff_t>(i));
      out.genomes.erase(out.genomes.begin() + static_cast<std::ptrdiff_t>(i));
    }
}

}  // namespace

TrendSeeds MakeTrendSeeds(const HgannFitness& fitness, const TrendSeedOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  const HgannFitnessConfig& cfg = fitness.config();
  TrendSeeds out;
  std::vector<int> training;
  for (size_t i = 0; i < cfg.cases.size(); ++i)
    if (cfg.cases[i].training) training.push_back(static_cast<int>(i));
  out.cases = FitCases(fitness, training, options, &out.simulations);
  HoldLooseParameters(fitness, training, options, out);
  out.law = FitOperatingLaw(fitness, out.cases, options);
  out.simulations += out.law.simulations;

  const TrendBasis basis(cfg, training, out.cases);
  const std::vector<double> regression = Regress(basis, basis.h);
  Structured st = ChooseStructures(basis, regression);
  std::vector<double>& structured = st.theta;
  std::vector<char>& free_theta = st.free;
  const std::vector<double> constant = ConstantTheta(basis, regression);
  // The loop's parameters (α, β, γ: outputs 2–4) held constant, at the per-case estimates' mean,
  // when their shapes leave the loop unbounded at a training case or a point of the penalty's
  // grid: the fitness refuses such a network and LM cannot start from it (trends-dev2, where the
  // estimates' scatter along the α–β–γ valley gave β + γ < 0 at a corner of the box).
  const int per = basis.per;
  if (!basis.LoopBounded(structured))
    for (int k = 2; k <= 4; ++k)
      for (int i = 0; i < per; ++i) {
        structured[per * k + i] = i == 0 ? constant[per * k] : 0.0;
        free_theta[per * k + i] = i == 0;
      }

  JointPolish polish_free(fitness, basis, options);
  // The structured trend polished within its structure. Not the full one (every weight free): on
  // trends-dev it reached a training cost 4 % lower and withheld PIs 10–100 times the truth's —
  // four cases cannot tell a hinge in V from one in f, the per-case estimates' structure can.
  const std::vector<double> from_structured = polish_free(structured, free_theta);
  std::vector<char> free_constant(basis.n_theta, 0);
  for (int k = 0; k < kOut; ++k) free_constant[per * k] = 1;
  const std::vector<double> from_constant = polish_free(constant, free_constant);
  // The structure polished again from the polished constant (its slopes from 0): a start the
  // fitness accepts, where the regression's own start may not be (a loop unbounded somewhere on
  // the grid, which LM cannot start from).
  const std::vector<double> from_both = polish_free(from_constant, free_theta);
  out.simulations += polish_free.simulations();

  // The structured trends are left out when the law's seed costs no more than they do
  // (kLawMargin = 1); otherwise they stay beside it and the GA keeps the lowest. A margin of 1.5
  // (the law preferred while it costs up to 1.5 × the structured trends) won on the development
  // family of bench/oplaw_benches.py and lost on its check family (v^p, √f or linear f laws: with
  // the corner case trained, 1–2 of 8 withheld cases within 3 × against 9 of 12 with the lowest
  // cost kept): the law's class (ln f, the terms its estimates support) is not yet general enough
  // to be preferred against the training cost (docs/performance.md, "Trend seeds").
  const std::vector<std::pair<const std::vector<double>*, const char*>> made = {
      {&from_structured, kStructured[0]},
      {&from_both, kStructured[1]},
      {&structured, kStructured[2]},
      {&from_constant, "constant (polished)"}};
  std::vector<std::pair<model::Network, std::string>> networks;
  if (out.law.ok) networks.emplace_back(out.law.network, kLawSeed);
  AddSeeds(fitness, basis, options, made, networks, out);
  LeaveOutStructuredTrends(out);
  for (size_t i = 0; i < cfg.cases.size(); ++i) {
    Array7 lo{}, hi{};
    for (int k = 0; k < kOut; ++k) {
      const double width = cfg.ranges[k].upper - cfg.ranges[k].lower;
      lo[k] = cfg.ranges[k].lower + st.lo[i][k] * width;
      hi[k] = cfg.ranges[k].lower + st.hi[i][k] * width;
    }
    out.supported_lo.push_back(lo);
    out.supported_hi.push_back(hi);
  }
  out.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace pz::hgann
