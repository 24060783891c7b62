// Where the network extrapolates (issue 36): the withheld cases outside the training cases' convex
// hull in the normalised (V, f) plane, and at each of them the outputs whose value leaves the range
// the training cases support. That range, per output, is the union of the network's own values at
// the training cases and of the training cases' per-case estimates ± 2 σ (where the case pins the
// parameter down: σ finite and at most a quarter of its range), widened by 1 % of the parameter's
// range: a value outside it is one no training case measured, set by the network's shape alone.
#pragma once

#include <array>
#include <functional>
#include <utility>
#include <vector>

#include "hgann/hgann_fitness.h"
#include "hgann/trend_seeds.h"

namespace pz::hgann {

/// Whether (x, y) lies in the convex hull of `points` (on its boundary counts as inside, within
/// 1e-9). Fewer than three points, or collinear ones, make a segment or a point.
bool InsideConvexHull(const std::vector<std::pair<double, double>>& points, double x, double y);

/// One withheld case outside the training cases' hull.
struct ExtrapolatedCase {
  int number = 0;
  double amplitude_v = 0, frequency_hz = 0;
  std::array<double, model::kNetworkOutputs> value{};     ///< the network's, in the units
  std::array<double, model::kNetworkOutputs> lo{}, hi{};  ///< the supported range
  std::vector<int> outputs;  ///< the outputs beyond [lo, hi], in output order
};

/// The withheld cases of `cases` (every case of the fitness's configuration, as EvaluateCases gives
/// them) outside the training cases' hull, in case order. `estimates` (may be empty) are per-case
/// fits of the configuration's cases in its order (identify's report has them for every case).
std::vector<ExtrapolatedCase> FindExtrapolations(const HgannFitnessConfig& config,
                                                 const std::vector<HgannCaseResult>& cases,
                                                 const std::vector<CaseEstimate>& estimates);

/// The outputs at the configuration's case `index` that the training cases do not settle: the
/// shapes that fit their per-case estimates alike (TrendSeeds::supported_lo/hi, with the network's
/// own value `network`, in the parameters' units) part there by more than 1 % of the parameter's
/// range and, when `estimate` (that case's own fit, may be null) is given:
///  - by more than 2 of its σ: more than the case's own data would allow, were they measured (a
///    parameter the case does not pin down, σ infinite or above a quarter of the range, is not
///    named: the case does not see it);
///  - and, with `moved` (Σ over the case's samples of the squared change of its predicted angle
///    when output k alone goes from the network's value to `value`; NaN: could not simulate), when
///    the end of that range farthest from the network's value moves the prediction by 2 × the
///    case's own PI or more: were that end the truth, the network's PI would be 3 × the floor.
/// Inside the training cases' hull or outside it. Empty when the seeds have no such range. α, β
/// and γ are never named: they trade along a valley, where their per-case estimates scatter beyond
/// σ even when the truth is constant (the nominal bench: one of them moved alone then "moves" the
/// prediction by several floors, which the others would take back), so their shapes' spread is not
/// a trend's.
std::vector<int> UnsettledOutputs(const HgannFitnessConfig& config, const TrendSeeds& seeds,
                                  size_t index,
                                  const std::array<double, model::kNetworkOutputs>& network,
                                  const CaseEstimate* estimate,
                                  const std::function<double(int k, double value)>& moved = {});

}  // namespace pz::hgann
