// The operating-point law learnt jointly (issue 47): each of the seven parameters a law of the
// drive's amplitude V and frequency f with the fewest terms the training cases support,
//
//   s_k(V, f) = c_k + a_k x_V + b_k ℓ_λ(f) [+ d_k q(x_V, x_f)]      (scaled units, s ∈ [0, 1])
//
// x_V, x_f the network's normalised inputs (over the training cases), ℓ_λ the law's shape in f,
// a Box–Cox power of f normalised over the training frequencies (ℓ_λ = (f^λ − f_lo^λ) / (f_hi^λ −
// f_lo^λ); λ = 0: ln(f / f_lo) / ln(f_hi / f_lo)), as a network: x_f and a hinge at the middle
// training frequency, exact at the training frequencies and piecewise linear between. The shape
// is a choice the data make: the law is fitted with λ = 0 (ln f), ½ (√f) and 1 (f), and the one of
// the lowest MAP cost is kept (the same number of coefficients each); the others stay beside it
// (OperatingLaw::shapes), and those that fit alike (MAP cost within kShapeAlike σ²) join the
// committee, so that where the shapes part the case is named open. q ≈ x_V x_f the
// interaction (½ (x_V − satlin(x_V − x_f) + satlin(x_V + x_f − 1)): bilinear at the box's
// corners), included only when the training cases determine it (q not a combination of 1, x_V
// and ℓ over the training cases: the paper's four cannot show it, a fifth at a corner can).
//
// Fitted on every training case's data at once, not from per-case estimates: Levenberg–Marquardt
// over the law's coefficients on the fitness's own cost (each training case's y_model − y_meas,
// the spread penalty's grid rows, a loop unbounded at a case or a grid point refused) plus a
// Gaussian prior, the ridge of a maximum a posteriori fit:
//   - every non-constant coefficient ~ N(0, τ²), τ = 0.5 of the parameter's range: the
//     smoothest law (a constant) unless the data pay for a slope; a parameter may move by half
//     its range over the training box at 1 σ, which no bench or paper table exceeds;
//   - every constant ~ N(½, τ_c²), τ_c = 0.5: the middle of the range, so that a level the data
//     do not fix (μ, which one frequency cannot tell from δ) is not left at a bound;
// the prior's rows weighted by the residuals' σ (the per-case fits' residual variance, with the
// autocorrelation inflation of TrendSeeds), so that it is the prior of a Gaussian noise model
// and weighs nothing where the data fix a coefficient. From the posterior covariance
// (JᵀJ / σ²)⁻¹ at the solution: a coefficient whose posterior variance is above a quarter of its
// prior variance is settled by the prior (the data halve its σ at most); a parameter is settled
// by the data when all its coefficients are.
#pragma once

#include <array>
#include <string>
#include <utility>
#include <vector>

#include "hgann/hgann_fitness.h"
#include "job/law_committee.h"
#include "model/network.h"

namespace pz::hgann {

struct CaseEstimate;
struct TrendSeedOptions;

struct OperatingLaw {
  static constexpr int kMaxTerms = 6;  ///< c, a (x_V), b (ℓ), d (q), e (h_V), g (h_f)
  /// The shapes in f tried (Box–Cox λ: ln f, √f, f), the first preferred on a tie.
  static constexpr std::array<double, 3> kFPowers = {0.0, 0.5, 1.0};
  /// Shapes whose MAP cost is within kShapeAlike σ² of the kept one's fit alike (Δχ² ≤ 4: two σ
  /// of the one parameter λ).
  static constexpr double kShapeAlike = 4.0;
  bool ok = false;                     ///< the fit ran from an evaluable start
  double f_power = 0;                  ///< λ of the kept shape ℓ_λ
  double map_cost = 0;                 ///< the LM's MAP cost (data + spread grid + prior) [deg²]
  bool interaction = false;            ///< the q term is in the law
  int terms = 3;                       ///< the most terms of a parameter
  /// Which terms each parameter's law has: c always; d with the interaction; a, b, e (curvature
  /// in V: a hinge at the middle training amplitude) and g (curvature in f: the log-f hinge on
  /// its own) for μ, δ, a1, a2 as their per-case estimates support them (Akaike's χ² + 2 p over
  /// five sets; the loop's α, β, γ keep a and b).
  std::array<std::array<bool, kMaxTerms>, model::kNetworkOutputs> active{};
  /// coef[k][t]: c, a, b, d, e, g of output k, in scaled units (0 for a term not in the law).
  std::array<std::array<double, kMaxTerms>, model::kNetworkOutputs> coef{};
  /// Posterior variance over prior variance of each coefficient (0: the data fix it, 1: only the
  /// prior does).
  std::array<std::array<double, kMaxTerms>, model::kNetworkOutputs> prior_share{};
  std::array<bool, model::kNetworkOutputs> data_settled{};  ///< every coefficient < kPriorShare
  static constexpr double kPriorShare = 0.25;
  static constexpr double kSlopeTau = 0.5, kConstantTau = 0.5;
  double sigma2 = 0;     ///< the residuals' variance the prior is weighted by [deg²]
  double data_cost = 0;  ///< Σ PI over the training cases [deg²]
  double cost = 0;       ///< the fitness's cost of the law's network
  model::Network network;  ///< the law as a network (the chromosome's resolution not applied)
  /// Per case of the configuration (every role): each parameter's 1-σ from the posterior
  /// covariance, in its units (how far laws that fit alike part there).
  std::vector<std::array<double, model::kNetworkOutputs>> sigma_at_case;
  int64_t simulations = 0;
  std::string start;  ///< which start the law was polished from
  /// θ: kMaxTerms coefficients an output, in output order.
  std::vector<double> theta;
  /// Every shape in f fitted (the kept one included), in kFPowers' order.
  struct Shape {
    double f_power = 0, map_cost = 0;
    bool interaction = false;
    std::array<std::array<bool, kMaxTerms>, model::kNetworkOutputs> active{};
    std::vector<double> theta;
  };
  std::vector<Shape> shapes;
  /// The other term sets of μ, δ, a1, a2 that fit the per-case estimates alike (Akaike's χ² + 2 p
  /// within 2 of the lowest): (output, their regression's coefficients − the chosen set's).
  std::vector<std::pair<int, std::array<double, kMaxTerms>>> alternatives;
};

/// What laws that fit the training cases alike say at every case, and which case to measure next
/// (query by committee). The committee: the law with the interaction term (whether or not the
/// training cases determine it), linearised at the fitted law, and the members one posterior σ
/// either way along each direction of its posterior covariance that the prior settles (posterior
/// variance above kPriorShare of the prior's along it): laws the training cases cannot tell from
/// the fitted one; for μ, δ, a1 and a2, the law moved by each other term set that fits the
/// per-case estimates alike (OperatingLaw::alternatives: a curvature in V against one in f), and,
/// without a V·f term, along the training design's null direction of the interaction by the size
/// of the parameter's own largest slope; the other shapes in f that fit alike (OperatingLaw::
/// shapes); and
/// the network kept (CommitteeOptions::kept: it fits the training cases as well, else it would
/// not be kept), so that a case where the kept network parts from the law is never called
/// settled. At every case, each member's predicted angle is compared with the fitted law's:
/// Σ_k (y_member − y_law)², over the case's floor σ² N (the residual variance a sample, as the
/// law's prior uses it). A withheld case is open when a member moves its prediction by 2 floors or
/// more (were that member the truth, the law's PI there would be about 3 × the floor).
/// The next case, by query by committee: each candidate (a withheld case, or a point of the user's
/// list: CommitteeOptions::candidates) is scored by what would remain open were it measured — the
/// members it tells apart from the law (2 floors or more there) ruled out, the largest remaining
/// disagreement at every withheld case other than the candidate, in floors, summed — lowest
/// first; ties by the larger disagreement at the candidate itself. A user's point is simulated as
/// the training case nearest it in (x_V, x_f) would be at its (V, f): that case's sample rate,
/// cycles and saturations.
struct CommitteeOptions {
  int threads = 1;
  const model::Network* kept = nullptr;  ///< the network the run keeps (a member), or none
  /// The user's feasible (V [V], f [Hz]) points; empty: the withheld cases are the candidates.
  std::vector<std::pair<double, double>> candidates;
};
using LawCommittee = job::LawCommittee;
LawCommittee CommitteeOf(const HgannFitness& fitness, const OperatingLaw& law,
                         const CommitteeOptions& options = {});

/// The law of the file comment on the fitness's training cases; `estimates` (the per-case fits,
/// TrendSeeds::cases) give the starts and σ.
OperatingLaw FitOperatingLaw(const HgannFitness& fitness,
                             const std::vector<CaseEstimate>& estimates,
                             const TrendSeedOptions& options);

/// "μ, δ" style list of the parameters the prior settles ("" when the data settle all).
std::string PriorSettledNames(const OperatingLaw& law);

}  // namespace pz::hgann
