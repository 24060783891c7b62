#include "hgann/extrapolation.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pz::hgann {
namespace {

constexpr double kEps = 1e-9;
using Point = std::pair<double, double>;

double Cross(const Point& o, const Point& a, const Point& b) {
  return (a.first - o.first) * (b.second - o.second) - (a.second - o.second) * (b.first - o.first);
}

/// Whether p lies on the segment ab (within kEps).
bool OnSegment(const Point& a, const Point& b, const Point& p) {
  const double len = std::hypot(b.first - a.first, b.second - a.second);
  if (len <= kEps) return std::hypot(p.first - a.first, p.second - a.second) <= kEps;
  if (std::abs(Cross(a, b, p)) / len > kEps) return false;
  const double t =
      ((p.first - a.first) * (b.first - a.first) + (p.second - a.second) * (b.second - a.second)) /
      (len * len);
  return t >= -kEps && t <= 1 + kEps;
}

std::array<double, model::kNetworkOutputs> Outputs(const model::BimorphParams& p) {
  return model::NetworkParameters{p.mu, p.delta, p.alpha, p.beta, p.gamma, p.a1, p.a2}.ToArray();
}

}  // namespace

bool InsideConvexHull(const std::vector<Point>& points, double x, double y) {
  // Andrew's monotone chain: the hull counter-clockwise, collinear points dropped.
  std::vector<Point> pts = points;
  std::sort(pts.begin(), pts.end());
  pts.erase(std::unique(pts.begin(), pts.end()), pts.end());
  const Point p{x, y};
  if (pts.empty()) return false;
  if (pts.size() == 1) return OnSegment(pts[0], pts[0], p);
  std::vector<Point> hull(2 * pts.size());
  size_t k = 0;
  for (size_t i = 0; i < pts.size(); ++i) {
    while (k >= 2 && Cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  for (size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {
    while (k >= t && Cross(hull[k - 2], hull[k - 1], pts[i]) <= 0) --k;
    hull[k++] = pts[i];
  }
  hull.resize(k - 1);
  if (hull.size() < 3) return OnSegment(pts.front(), pts.back(), p);
  for (size_t i = 0; i < hull.size(); ++i) {
    const Point& a = hull[i];
    const Point& b = hull[(i + 1) % hull.size()];
    const double len = std::hypot(b.first - a.first, b.second - a.second);
    if (Cross(a, b, p) < -kEps * len) return false;
  }
  return true;
}

std::vector<ExtrapolatedCase> FindExtrapolations(const HgannFitnessConfig& config,
                                                 const std::vector<HgannCaseResult>& cases,
                                                 const std::vector<CaseEstimate>& estimates) {
  constexpr int kOut = model::kNetworkOutputs;
  const auto& norm = config.normalization;
  const auto at = [&](const HgannCase& c) {
    return Point{norm.NormalizeAmplitude(c.drive.amplitude_v),
                 norm.NormalizeFrequency(c.drive.frequency_hz)};
  };
  const auto result_of = [&](int number) -> const HgannCaseResult* {
    for (const HgannCaseResult& r : cases)
      if (r.number == number) return &r;
    return nullptr;
  };
  std::vector<Point> hull;
  std::array<double, kOut> lo, hi;
  lo.fill(std::numeric_limits<double>::infinity());
  hi.fill(-std::numeric_limits<double>::infinity());
  for (size_t i = 0; i < config.cases.size(); ++i) {
    const HgannCase& c = config.cases[i];
    if (!c.training) continue;
    hull.push_back(at(c));
    if (const HgannCaseResult* r = result_of(c.number)) {
      const auto v = Outputs(r->params);
      for (int k = 0; k < kOut; ++k) lo[k] = std::min(lo[k], v[k]), hi[k] = std::max(hi[k], v[k]);
    }
    if (i < estimates.size() && estimates[i].ok)
      for (int k = 0; k < kOut; ++k) {
        const CaseEstimate& e = estimates[i];
        const double width = config.ranges[k].upper - config.ranges[k].lower;
        if (!std::isfinite(e.sigma[k]) || e.sigma[k] > 0.25 * width) continue;  // not pinned down
        lo[k] = std::min(lo[k], e.value[k] - 2 * e.sigma[k]);
        hi[k] = std::max(hi[k], e.value[k] + 2 * e.sigma[k]);
      }
  }
  for (int k = 0; k < kOut; ++k) {
    const double tol = 0.01 * (config.ranges[k].upper - config.ranges[k].lower);
    lo[k] -= tol;
    hi[k] += tol;
  }
  std::vector<ExtrapolatedCase> out;
  for (const HgannCase& c : config.cases) {
    if (c.training) continue;
    const Point p = at(c);
    if (InsideConvexHull(hull, p.first, p.second)) continue;
    ExtrapolatedCase e;
    e.number = c.number;
    e.amplitude_v = c.drive.amplitude_v;
    e.frequency_hz = c.drive.frequency_hz;
    e.lo = lo;
    e.hi = hi;
    if (const HgannCaseResult* r = result_of(c.number)) {
      e.value = Outputs(r->params);
      for (int k = 0; k < kOut; ++k)
        if (e.value[k] < lo[k] || e.value[k] > hi[k]) e.outputs.push_back(k);
    } else {
      e.value.fill(std::nan(""));
    }
    out.push_back(std::move(e));
  }
  return out;
}

std::vector<int> UnsettledOutputs(const HgannFitnessConfig& config, const TrendSeeds& seeds,
                                  size_t index,
                                  const std::array<double, model::kNetworkOutputs>& network,
                                  const CaseEstimate* estimate,
                                  const std::function<double(int k, double value)>& moved) {
  std::vector<int> out;
  if (index >= seeds.supported_lo.size() || index >= seeds.supported_hi.size()) return out;
  for (int k = 0; k < model::kNetworkOutputs; ++k) {
    if (k >= 2 && k <= 4) continue;  // α, β, γ: their estimates scatter along a valley
    const double width = config.ranges[k].upper - config.ranges[k].lower;
    const double lo = std::min(seeds.supported_lo[index][k], network[k]),
                 hi = std::max(seeds.supported_hi[index][k], network[k]);
    double tol = 0.01 * width;
    if (estimate && estimate->ok) {
      // A parameter the case's own data do not pin down (μ against δ) is one it does not see.
      if (!std::isfinite(estimate->sigma[k]) || estimate->sigma[k] > 0.25 * width) continue;
      tol = std::max(tol, 2 * estimate->sigma[k]);
    }
    if (hi - lo <= tol) continue;
    if (estimate && estimate->ok && moved) {
      const double far = hi - network[k] > network[k] - lo ? hi : lo;
      const double d = moved(k, far);
      if (std::isfinite(d) && d < 2 * estimate->pi) continue;
    }
    out.push_back(k);
  }
  return out;
}

}  // namespace pz::hgann
