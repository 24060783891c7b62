// Where the network extrapolates (issue 36): the withheld cases outside the training cases' convex
// hull in the normalised (V, f) plane, and at each of them the outputs whose value leaves the range
// the training cases support. That range, per output, is the union of the network's own values at
// the training cases and of the training cases' per-case estimates ± 2 σ (where the case pins the
// parameter down: σ finite and at most a quarter of its range), widened by 1 % of the parameter's
// range: a value outside it is one no training case measured, set by the network's shape alone.
#pragma once

#include <array>
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

}  // namespace pz::hgann
