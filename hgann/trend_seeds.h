// Trend seeds (issue 36): networks for the GA's generation 0 that already follow the operating
// point, made from per-case fits of the training cases — the paper's eq. 7 (a regression of the
// per-case parameters on V and f), done by the network.
//
//  1. Per-case fits: each training case alone, the seven parameters in the network's scaled units
//     s ∈ [0, 1]⁷ (p = lower + s (upper − lower)), bounded Levenberg–Marquardt on the case's
//     residuals y_model − y_meas from a fixed list of starts (the previous case's solution first),
//     the lowest PI kept; σ of each s from the Jacobian at the solution (s² (JᵀJ)⁺, s² = PI/(N −
//     7); infinite along directions the case does not see), times √((1 + ρ)/(1 − ρ)) for the lag-1
//     autocorrelation ρ of the residuals (they are not white: encoder rounding of a slow signal).
//     A parameter that half the training cases or more do not pin down (μ: one frequency sees the
//     Rayleigh damping as one number) is held at the median of its per-case values and the cases
//     are fitted again, so that their other estimates belong to one value of it; one parameter at
//     a time, the loosest first, until none is loose (μ and δ are loose together; holding μ pins
//     δ down).
//  2. Trend networks (TrendNetwork): hidden satlin nodes x_V, x_f and a hinge of each input at the
//     middle level of the training cases (500 V and 0.5 Hz on the paper's split), outputs
//     s_k = clamp(c_k + Σ_j B_j W2_jk, 0, 1): piecewise linear over the box. Per parameter, the
//     structure its per-case estimates support: of constant, V only, f only, plane, V piecewise,
//     f piecewise, plane + a hinge, the weighted least squares (weights 1/σ², σ at least 0.5 % of
//     the range, a quarter of it where the case does not pin it down) with the lowest χ² + 2 p;
//     of shapes that score alike (a hinge in V or one in f through four cases), the one that
//     varies least over the spread penalty's 5 × 5 grid (the range of the shapes within 2 of the
//     chosen one's score, at every case, is kept: TrendSeeds::supported_lo/hi; where they part the
//     training cases do not settle the parameter: δ is a hinge in f on trends-dev and one in V on
//     trends-dev3, and their four training cases fit both alike). When the loop's shapes (α, β, γ)
//     leave it unbounded at a training case or a grid point, they are made constant (the estimates'
//     mean). On the paper's split two training cases share a V (5, 6) and two an f (1, 7), which is
//     what tells a parameter of f alone (δ on trends-dev) from one of V alone (a1). Then polished
//     by LM within that structure on all training cases at once, on the fitness's own cost: every
//     training case's y_model − y_meas and, with a spread penalty λ, √(λ/25) (s_k(g) − mean s_k)
//     over the penalty's 5 × 5 grid, an unbounded loop on the grid refused. Seeds: the structured
//     trend polished, the same unpolished, the constant network polished, and the structure
//     polished again from that constant (slopes from 0: a start the fitness accepts). (Every
//     weight free fits the training cases better and the withheld ones far worse:
//     the history of docs/performance.md, "Trend seeds".)
//  3. At the chromosome's resolution: each seed's output codes (c2 and W2 of the used hidden nodes)
//     are polished by a coordinate search over the codes (steps ±1, ±4, ±16, three passes, only
//     strictly lower costs of the problem's own fitness kept): the Lamarckian write-back of the
//     polish into the bits.
// Deterministic: a function of the fitness's configuration alone (the thread count changes only
// how fast the Jacobians' columns are computed).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "hgann/hgann_fitness.h"
#include "hgann/operating_law.h"
#include "model/network.h"
#include "opt/evaluator.h"

namespace pz::hgann {

/// One training case fitted alone.
struct CaseEstimate {
  int number = 0;
  double amplitude_v = 0, frequency_hz = 0;
  std::array<double, model::kNetworkOutputs> s{};      ///< scaled parameters in [0, 1]
  std::array<double, model::kNetworkOutputs> value{};  ///< in the parameters' units
  std::array<double, model::kNetworkOutputs> sigma{};  ///< 1-σ of value (+inf: not identifiable)
  double pi = 0;                                       ///< PI of the case with these [deg²]
  /// The variance of one residual that σ is scaled by: PI / (N − free) · (1 + ρ) / (1 − ρ).
  double residual_var = 0;
  bool ok = false;  ///< a start could be simulated
};

struct TrendSeedOptions {
  int threads = 1;          ///< Jacobian columns in parallel, ≥ 1 (does not change the result)
  int case_starts = 6;      ///< starts of each per-case fit, ≥ 1
  int lm_iterations = 60;   ///< per fit, ≥ 1
  bool code_polish = true;  ///< step 3
};

struct TrendSeeds {
  std::vector<CaseEstimate> cases;   ///< the training cases, in case order
  std::vector<opt::Genome> genomes;  ///< the seeds, best (lowest cost) first
  std::vector<double> costs;         ///< each seed's fitness cost
  std::vector<std::string> names;    ///< "trend (polished)", …, "constant (polished)"
  int64_t simulations = 0;           ///< case simulations spent
  double wall_time_s = 0;
  /// Per case of the configuration (every role, in its order): the lowest and highest value of
  /// each parameter, in its units, over the shapes its per-case estimates support alike (step 2's
  /// candidates whose χ² + 2 p is within 2 of the chosen one's: Akaike's "substantial support").
  /// Where they part, the training cases do not settle the parameter there: the network's value
  /// is one guess of several that fit them alike.
  std::vector<std::array<double, model::kNetworkOutputs>> supported_lo, supported_hi;
  /// The operating-point law fitted on every training case at once (hgann/operating_law.h): one
  /// of the seeds ("operating-point law (joint fit)") when it could be fitted.
  OperatingLaw law;
  /// The law's seed replaces the structured trends (they are left out of `genomes`) when its cost
  /// is at most kLawMargin × theirs (1: when it fits the training cases at least as well; a
  /// larger margin, preferring the law, lost on the check benches: trend_seeds.cc).
  bool law_kept = false;
  double law_cost = 0, structured_cost = 0;  ///< the seeds' costs (+inf: none)
};
inline constexpr double kLawMargin = 1.0;

/// Steps 1–3 of the file comment on the fitness's training cases.
TrendSeeds MakeTrendSeeds(const HgannFitness& fitness, const TrendSeedOptions& options = {});

/// Per-case fits (step 1) of the given cases (any role) of the fitness's configuration; `hold`
/// (scaled values, NaN = fitted) keeps parameters at given values (their σ is then +inf);
/// `start` (scaled values) is then the only start of every case's fit.
std::vector<CaseEstimate> FitCases(
    const HgannFitness& fitness, const std::vector<int>& case_indices,
    const TrendSeedOptions& options, int64_t* simulations = nullptr,
    const std::array<double, model::kNetworkOutputs>* hold = nullptr,
    const std::array<double, model::kNetworkOutputs>* start = nullptr);

/// A satlin network of `hidden` (≥ 2) hidden nodes whose nodes 0 and 1 pass x_V and x_f through;
/// the other nodes' weights, the second layer and the maps are left to the caller (zero).
model::Network SatlinSkeleton(int hidden);

/// The seeds' network: input and hidden satlin; hidden node 0 = x_V, 1 = x_f, then a hinge
/// satlin((x − knot)/(1 − knot)) of x_V at knot_v and of x_f at knot_f (each only when in (0,
/// 0.9)); outputs satlin(Σ_j B_j w2[j][k] + c2[k]) (missing entries 0). H = 2 … 4.
model::Network TrendNetwork(double knot_v, double knot_f, const std::vector<double>& c2,
                            const std::vector<std::vector<double>>& w2,
                            const model::InputNormalization& normalization,
                            const model::ParameterRanges& ranges);

}  // namespace pz::hgann
