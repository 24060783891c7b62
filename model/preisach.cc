#include "model/preisach.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "model/format.h"
#include "model/kernels/pzk.h"

namespace pz::model {
namespace {

std::string Num(double x) { return FormatG(x, 6); }

/// The grid's constants: per width its half-width, its cells' lower centres and the constant k_i.
struct GridTables {
  std::vector<double> r, k;
  std::vector<size_t> first;  ///< index of the first cell of width i (first[n] = cells)
  std::vector<double> c;      ///< lower centre of every cell
  double delta = 0;
  explicit GridTables(const PreisachGrid& g) {
    ThrowIfError(g.Validate());
    const int n = g.levels;
    delta = g.step();
    for (int i = 0; i < n; ++i) {
      r.push_back(g.half_width(i));
      k.push_back((g.u_min + r.back()) / (n - i));
      first.push_back(c.size());
      for (int j = 0; j < n - i; ++j) c.push_back(g.u_min + r.back() + j * delta);
    }
    first.push_back(c.size());
  }
  size_t widths() const { return r.size(); }
};

static_assert(static_cast<int>(InitialState::kDescended) == pzk::PZK_DESCENDED &&
              static_cast<int>(InitialState::kAscended) == pzk::PZK_ASCENDED &&
              static_cast<int>(InitialState::kCentred) == pzk::PZK_CENTRED);

/// The Preisach grid as its kernel's block (model/kernels/play_operators.h pzk_preisach_step): the
/// constants c = {Δ, r_i, k_i, centres}; Step(d, o, x) moves the plays d to x into o and returns
/// Σ_ij w_ij φ_ij(o_i).
class PreisachKernel {
 public:
  PreisachKernel(const PreisachGrid& g, std::span<const double> w, InitialState start)
      : n_(static_cast<size_t>(g.levels)), c_(1 + 2 * n_ + g.cells()) {
    b_.kind = pzk::PZK_PREISACH;
    b_.n = g.levels;
    b_.u_min = g.u_min;
    b_.u_max = g.u_max;
    b_.w = w.data();
    b_.nw = static_cast<int>(w.size());
    b_.init = static_cast<int>(start);
  }
  PreisachKernel(const PreisachKernel&) = delete;
  PreisachKernel& operator=(const PreisachKernel&) = delete;
  size_t widths() const { return n_; }
  double half_width(size_t i) const { return c_[1 + i]; }
  /// The plays d at rest at x (the constants made); returns the output there.
  double Init(double* d, double x) { return pzk::pzk_preisach_init(&b_, c_.data(), d, x); }
  double Step(const double* d, double* o, double x) const {
    return pzk::pzk_preisach_step(&b_, c_.data(), d, o, x);
  }

 private:
  size_t n_;
  std::vector<double> c_;
  pzk::pzk_block b_{};
};

/// The asymmetric PI as its kernel's block (model/kernels/play_operators.h pzk_asym_pi_step): c =
/// {thresholds, knots}, w = {w0, weights, up, down}; Step(d, o, x) moves the plays d to x into o
/// and returns the output.
class AsymmetricPiKernel {
 public:
  explicit AsymmetricPiKernel(const AsymmetricPi& op) {
    c_ = op.thresholds;
    c_.insert(c_.end(), op.knots.begin(), op.knots.end());
    w_.push_back(op.w0);
    for (const auto* v : {&op.weights, &op.up, &op.down}) w_.insert(w_.end(), v->begin(), v->end());
    b_.kind = pzk::PZK_ASYMMETRIC_PI;
    b_.n = static_cast<int>(op.thresholds.size());
    b_.m = static_cast<int>(op.knots.size());
    b_.w = w_.data();
    b_.nw = static_cast<int>(w_.size());
  }
  AsymmetricPiKernel(const AsymmetricPiKernel&) = delete;
  AsymmetricPiKernel& operator=(const AsymmetricPiKernel&) = delete;
  double Step(const double* d, double* o, double x) const {
    return pzk::pzk_asym_pi_step(&b_, c_.data(), d, o, x);
  }

 private:
  std::vector<double> c_, w_;
  pzk::pzk_block b_{};
};

/// Solves f(v) = ref for a non-decreasing f on [lo, hi] with f(lo) ≤ ref ≤ f(hi), by bisection down
/// to adjacent doubles; returns the end whose value is nearer.
template <class F>
double Bisect(const F& f, double lo, double hi, double flo, double fhi, double ref) {
  if (flo == ref) return lo;
  if (fhi == ref) return hi;
  for (int it = 0; it < 2100; ++it) {
    const double mid = lo + 0.5 * (hi - lo);
    if (!(mid > lo && mid < hi)) break;
    const double fm = f(mid);
    if (fm == ref) return mid;
    if (fm < ref) {
      lo = mid;
      flo = fm;
    } else {
      hi = mid;
      fhi = fm;
    }
  }
  return std::abs(fhi - ref) <= std::abs(ref - flo) ? hi : lo;
}

/// One inverse step of a monotone operator: the drive v with f(v) = ref, starting from the previous
/// drive v0 (f(v0) = y0) within [lo, hi]; out-of-reach references give the limit and are counted.
template <class F>
double SolveStep(const F& f, double v0, double y0, double ref, double lo, double hi,
                 InverseReport* rep) {
  if (ref == y0) return v0;
  if (ref > y0) {
    const double fh = f(hi);
    if (fh < ref) {
      ++rep->saturated;
      rep->max_shortfall = std::max(rep->max_shortfall, ref - fh);
      return hi;
    }
    return Bisect(f, v0, hi, y0, fh, ref);
  }
  const double fl = f(lo);
  if (fl > ref) {
    ++rep->saturated;
    rep->max_shortfall = std::max(rep->max_shortfall, fl - ref);
    return lo;
  }
  return Bisect(f, lo, v0, fl, y0, ref);
}

/// A bracket [v − d, v + d] that holds ref for an unbounded non-decreasing f (doubling d).
template <class F>
void Bracket(const F& f, double v, double ref, double* lo, double* hi) {
  double d = std::max(1.0, std::abs(v)) * 1e-3;
  *lo = v;
  *hi = v;
  for (int it = 0; it < 2100; ++it) {
    if (f(*hi) >= ref && f(*lo) <= ref) return;
    *lo = v - d;
    *hi = v + d;
    d *= 2;
  }
  throw InputError("inverse: no drive reaches the reference " + Num(ref));
}

}  // namespace

Status PreisachGrid::Validate() const {
  if (!std::isfinite(u_min) || !std::isfinite(u_max) || !(u_min < u_max)) {
    return InvalidArgument("preisach.range = [" + Num(u_min) + ", " + Num(u_max) +
                           "]: must be finite with u_min < u_max (a constant drive?)");
  }
  if (levels < 1 || levels > 200)
    return InvalidArgument(FieldError("preisach.levels", levels, "must be 1 … 200"));
  return Status::Ok();
}

size_t PreisachGrid::cell(int i, int j) const {
  // Widths 0 … i−1 hold n + (n−1) + … + (n−i+1) cells.
  return static_cast<size_t>(i) * static_cast<size_t>(levels) -
         static_cast<size_t>(i) * static_cast<size_t>(i - 1) / 2 + static_cast<size_t>(j);
}

std::string PreisachGrid::CellName(int i, int j) const {
  const double c = u_min + half_width(i) + (j + 0.5) * step();
  return "w(a=" + Num(c + half_width(i)) + ",b=" + Num(c - half_width(i)) + ")";
}

void PreisachRegressors(const PreisachGrid& grid, std::span<const double> u, std::span<double> out,
                        InitialState start) {
  const GridTables t(grid);
  const size_t m = grid.cells(), n = t.widths();
  if (out.size() != u.size() * m) throw InputError("PreisachRegressors: output size mismatch");
  if (u.empty()) return;
  RequireResolved(start, "PreisachRegressors");
  std::vector<double> p(n);
  for (size_t i = 0; i < n; ++i) p[i] = PlayRest(u[0], t.r[i], start);
  for (size_t s = 0; s < u.size(); ++s) {
    double* row = out.data() + s * m;
    for (size_t i = 0; i < n; ++i) {
      p[i] = std::max(u[s] - t.r[i], std::min(u[s] + t.r[i], p[i]));
      for (size_t q = t.first[i]; q < t.first[i + 1]; ++q)
        row[q] = std::clamp(p[i], t.c[q], t.c[q] + t.delta) - t.c[q] + t.k[i];
    }
  }
}

void ApplyPreisach(const PreisachGrid& grid, std::span<const double> w, std::span<const double> u,
                   std::span<double> y, InitialState start) {
  ThrowIfError(grid.Validate());
  if (w.size() != grid.cells()) {
    throw InputError("preisach: " + std::to_string(w.size()) + " weights for " +
                     std::to_string(grid.cells()) + " cells");
  }
  if (y.size() != u.size()) throw InputError("ApplyPreisach: output size mismatch");
  if (u.empty()) return;
  RequireResolved(start, "ApplyPreisach");
  PreisachKernel kernel(grid, w, start);  // the step is the kernel's
  std::vector<double> p(kernel.widths());
  y[0] = kernel.Init(p.data(), u[0]);
  for (size_t s = 1; s < u.size(); ++s) y[s] = kernel.Step(p.data(), p.data(), u[s]);
}

namespace {

/// The Gram matrix of Σ (w_a − w_b)² over the grid's neighbours along the centre and, with
/// `triangle`, along α and β between the hysteron widths (PreisachRoughness,
/// PreisachTriangleRoughness).
std::vector<double> Roughness(const PreisachGrid& grid, bool triangle) {
  ThrowIfError(grid.Validate());
  const size_t m = grid.cells();
  std::vector<double> R(m * m, 0.0);
  auto edge = [&](size_t a, size_t b) {
    R[a * m + a] += 1;
    R[b * m + b] += 1;
    R[a * m + b] -= 1;
    R[b * m + a] -= 1;
  };
  for (int i = 0; i < grid.levels; ++i) {
    for (int j = 0; j < grid.levels - i; ++j) {
      if (j + 1 < grid.levels - i)
        edge(grid.cell(i, j), grid.cell(i, j + 1));  // along the centre: α and β + Δ
      if (!triangle || i == 0 || i + 1 >= grid.levels)
        continue;  // the reversible cells: no neighbours across widths
      if (j + 1 < grid.levels - i)
        edge(grid.cell(i, j), grid.cell(i + 1, j));                // along α: α + Δ, the same β
      if (j >= 1) edge(grid.cell(i, j), grid.cell(i + 1, j - 1));  // along β: β − Δ, the same α
    }
  }
  return R;
}

}  // namespace

std::vector<double> PreisachRoughness(const PreisachGrid& grid) { return Roughness(grid, false); }

std::vector<double> PreisachTriangleRoughness(const PreisachGrid& grid) {
  return Roughness(grid, true);
}

InverseReport InvertPreisach(const PreisachGrid& grid, std::span<const double> w,
                             std::span<const double> y_ref, double u_lo, double u_hi,
                             std::span<double> u, InitialState start) {
  ThrowIfError(grid.Validate());
  if (w.size() != grid.cells()) {
    throw InputError("preisach inverse: " + std::to_string(w.size()) + " weights for " +
                     std::to_string(grid.cells()) + " cells");
  }
  for (size_t q = 0; q < w.size(); ++q) {
    if (!(w[q] >= 0) || !std::isfinite(w[q])) {
      throw InputError("preisach inverse: weight " + std::to_string(q) + " = " + Num(w[q]) +
                       ": must be finite and >= 0 (a monotone operator)");
    }
  }
  if (!std::isfinite(u_lo) || !std::isfinite(u_hi) || !(u_lo < u_hi)) {
    throw InputError("preisach inverse: drive limits [" + Num(u_lo) + ", " + Num(u_hi) +
                     "] must be finite, lo < hi");
  }
  if (u.size() != y_ref.size()) throw InputError("InvertPreisach: output size mismatch");
  InverseReport rep;
  if (u.empty()) return rep;
  RequireResolved(start, "InvertPreisach");
  // The forward step is the kernel's (PreisachKernel): a trial moves the plays into `trial`.
  PreisachKernel kernel(grid, w, start);
  const size_t n = kernel.widths();
  std::vector<double> p(n), trial(n);
  kernel.Init(p.data(), u_lo);  // the constants
  // The first sample: a rest state (every play at PlayRest(v)), whose output is non-decreasing in
  // v.
  auto rest = [&](double v) {
    for (size_t i = 0; i < n; ++i) trial[i] = PlayRest(v, kernel.half_width(i), start);
    return kernel.Step(trial.data(), trial.data(), v);
  };
  const double mid = 0.5 * (u_lo + u_hi);
  double v = SolveStep(rest, mid, rest(mid), y_ref[0], u_lo, u_hi, &rep);
  for (size_t i = 0; i < n; ++i) p[i] = PlayRest(v, kernel.half_width(i), start);
  double y = kernel.Step(p.data(), p.data(), v);
  u[0] = v;
  for (size_t s = 1; s < y_ref.size(); ++s) {
    auto step = [&](double x) { return kernel.Step(p.data(), trial.data(), x); };
    v = SolveStep(step, v, y, y_ref[s], u_lo, u_hi, &rep);
    y = kernel.Step(p.data(), p.data(), v);
    u[s] = v;
  }
  return rep;
}

Status AsymmetricPi::Validate() const {
  if (!std::isfinite(w0))
    return InvalidArgument("asymmetric-pi.w0 = " + Num(w0) + ": must be finite");
  if (thresholds.size() != weights.size()) {
    return InvalidArgument("asymmetric-pi.weights has " + std::to_string(weights.size()) +
                           " values for " + std::to_string(thresholds.size()) + " thresholds");
  }
  if (up.size() != knots.size() || down.size() != knots.size()) {
    return InvalidArgument("asymmetric-pi.up / down have " + std::to_string(up.size()) + " / " +
                           std::to_string(down.size()) + " values for " +
                           std::to_string(knots.size()) + " knots");
  }
  for (size_t i = 0; i < thresholds.size(); ++i) {
    if (!std::isfinite(thresholds[i]) || thresholds[i] <= 0 ||
        (i > 0 && thresholds[i] <= thresholds[i - 1])) {
      return InvalidArgument("asymmetric-pi.thresholds[" + std::to_string(i) +
                             "] = " + Num(thresholds[i]) +
                             ": must be finite, > 0 and above the previous one");
    }
    if (!std::isfinite(weights[i])) {
      return InvalidArgument("asymmetric-pi.weights[" + std::to_string(i) +
                             "] = " + Num(weights[i]) + ": must be finite");
    }
  }
  for (size_t j = 0; j < knots.size(); ++j) {
    if (!std::isfinite(knots[j]) || (j > 0 && knots[j] <= knots[j - 1])) {
      return InvalidArgument("asymmetric-pi.knots[" + std::to_string(j) + "] = " + Num(knots[j]) +
                             ": must be finite and above the previous one");
    }
    if (!std::isfinite(up[j]) || !std::isfinite(down[j])) {
      return InvalidArgument("asymmetric-pi.up/down[" + std::to_string(j) + "]: must be finite");
    }
  }
  return Status::Ok();
}

bool AsymmetricPi::Monotone() const {
  if (!Validate().ok() || !(w0 >= 0)) return false;
  auto nonneg = [](const std::vector<double>& v) {
    return std::all_of(v.begin(), v.end(), [](double x) { return x >= 0; });
  };
  return nonneg(weights) && nonneg(up) && nonneg(down);
}

std::vector<double> AsymmetricPiKnots(int count, double u_min, double u_max) {
  if (count < 1 || count > 1000)
    throw InputError(FieldError("asymmetric-pi knots", count, "must be 1 … 1000"));
  if (!std::isfinite(u_min) || !std::isfinite(u_max) || !(u_min < u_max)) {
    throw InputError("asymmetric-pi: the drive range [" + Num(u_min) + ", " + Num(u_max) +
                     "] is empty (a constant drive?)");
  }
  std::vector<double> z(static_cast<size_t>(count));
  for (int j = 0; j < count; ++j)
    z[static_cast<size_t>(j)] = u_min + (u_max - u_min) * (j + 1) / (count + 1);
  return z;
}

void AsymmetricPiRegressors(std::span<const double> r, std::span<const double> z,
                            std::span<const double> u, std::span<double> out, InitialState start) {
  const size_t n = r.size(), K = z.size(), m = 1 + n + 2 * K;
  if (out.size() != u.size() * m) throw InputError("AsymmetricPiRegressors: output size mismatch");
  if (u.empty()) return;
  RequireResolved(start, "AsymmetricPiRegressors");
  std::vector<double> p(n);
  for (size_t i = 0; i < n; ++i) p[i] = PlayRest(u[0], r[i], start);
  for (size_t s = 0; s < u.size(); ++s) {
    double* row = out.data() + s * m;
    const double x = u[s];
    row[0] = x;
    for (size_t i = 0; i < n; ++i) {
      p[i] = std::max(x - r[i], std::min(x + r[i], p[i]));
      row[1 + i] = p[i];
    }
    for (size_t j = 0; j < K; ++j) {
      row[1 + n + j] = std::max(x - z[j], 0.0);
      row[1 + n + K + j] = std::min(x - z[j], 0.0);
    }
  }
}

void ApplyAsymmetricPi(const AsymmetricPi& op, std::span<const double> u, std::span<double> y) {
  ThrowIfError(op.Validate());
  if (y.size() != u.size()) throw InputError("ApplyAsymmetricPi: output size mismatch");
  if (u.empty()) return;
  RequireResolved(op.start, "ApplyAsymmetricPi");
  const AsymmetricPiKernel kernel(op);  // the step is the kernel's
  std::vector<double> p(op.thresholds.size());
  for (size_t i = 0; i < p.size(); ++i) p[i] = PlayRest(u[0], op.thresholds[i], op.start);
  for (size_t s = 0; s < u.size(); ++s) y[s] = kernel.Step(p.data(), p.data(), u[s]);
}

void InvertAsymmetricPi(const AsymmetricPi& op, std::span<const double> y_ref,
                        std::span<double> u) {
  if (!op.Monotone())
    throw InputError("asymmetric-pi inverse: the operator needs finite weights >= 0 (monotone)");
  double total = op.w0;
  for (double w : op.weights) total += w;
  for (size_t j = 0; j < op.knots.size(); ++j) total += op.up[j] + op.down[j];
  if (!(total > 0))
    throw InputError("asymmetric-pi inverse: every weight is zero (no drive reaches a reference)");
  if (u.size() != y_ref.size()) throw InputError("InvertAsymmetricPi: output size mismatch");
  if (u.empty()) return;
  for (double v : y_ref)
    if (!std::isfinite(v))
      throw InputError("asymmetric-pi inverse: a reference sample is not finite");
  RequireResolved(op.start, "InvertAsymmetricPi");
  const size_t n = op.thresholds.size();
  const AsymmetricPiKernel kernel(op);  // the forward step: a trial moves the plays into `trial`
  std::vector<double> p(n), trial(n);
  InverseReport rep;  // never saturates: the operator is unbounded
  auto rest = [&](double v) {
    for (size_t i = 0; i < n; ++i) trial[i] = PlayRest(v, op.thresholds[i], op.start);
    return kernel.Step(trial.data(), trial.data(), v);
  };
  double lo = 0, hi = 0;
  Bracket(rest, 0.0, y_ref[0], &lo, &hi);
  double v = Bisect(rest, lo, hi, rest(lo), rest(hi), y_ref[0]);
  for (size_t i = 0; i < n; ++i) p[i] = PlayRest(v, op.thresholds[i], op.start);
  double y = kernel.Step(p.data(), p.data(), v);
  u[0] = v;
  for (size_t s = 1; s < y_ref.size(); ++s) {
    auto step = [&](double x) { return kernel.Step(p.data(), trial.data(), x); };
    Bracket(step, v, y_ref[s], &lo, &hi);
    v = SolveStep(step, v, y, y_ref[s], lo, hi, &rep);
    y = kernel.Step(p.data(), p.data(), v);
    u[s] = v;
  }
}

}  // namespace pz::model
