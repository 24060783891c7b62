#include "opt/lm.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <thread>

#include "opt/random.h"

namespace pz::opt {

void ParallelFor(int n, int threads, const std::function<void(int)>& fn) {
  threads = std::max(1, std::min(threads, n));
  if (threads <= 1) {
    for (int i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<int> next{0};
  auto work = [&] {
    for (int i = next.fetch_add(1); i < n; i = next.fetch_add(1)) fn(i);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
}

// ---- Levenberg–Marquardt
// -------------------------------------------------------------------------

Status LmOptions::Validate() const {
  if (max_iterations < 1)
    return InvalidArgument(FieldError("max_iterations", max_iterations, "must be >= 1"));
  if (!(fd_step > 0)) return InvalidArgument(FieldError("fd_step", fd_step, "must be > 0"));
  if (threads < 1) return InvalidArgument(FieldError("threads", threads, "must be >= 1"));
  if (!(ftol >= 0)) return InvalidArgument(FieldError("ftol", ftol, "must be >= 0"));
  if (!(lambda0 > 0)) return InvalidArgument(FieldError("lambda0", lambda0, "must be > 0"));
  return Status::Ok();
}

BatchResidualFunction ParallelResiduals(ResidualFunction f, int threads) {
  return [f = std::move(f), threads](const std::vector<std::vector<double>>& xs,
                                     std::vector<std::vector<double>>& rs, std::vector<char>& ok) {
    rs.assign(xs.size(), {});
    ok.assign(xs.size(), 0);
    ParallelFor(static_cast<int>(xs.size()), threads,
                [&](int i) { ok[i] = f(xs[i], rs[i]) ? 1 : 0; });
  };
}

BatchResidualFunction EvaluatorResiduals(opt::BatchEvaluator& evaluator) {
  return [&evaluator](const std::vector<std::vector<double>>& xs,
                      std::vector<std::vector<double>>& rs, std::vector<char>& ok) {
    std::vector<opt::Genome> genomes(xs.size());
    std::vector<int> idx(xs.size());
    for (size_t i = 0; i < xs.size(); ++i) {
      genomes[i].reals = xs[i];
      idx[i] = static_cast<int>(i);
    }
    std::vector<opt::FitnessResult> out(xs.size());
    evaluator.Evaluate({0, genomes, idx}, out);
    rs.assign(xs.size(), {});
    ok.assign(xs.size(), 0);
    for (size_t i = 0; i < xs.size(); ++i) {
      ok[i] = out[i].status == opt::FitnessStatus::kOk ? 1 : 0;
      rs[i] = std::move(out[i].residuals);
    }
  };
}

bool NumericJacobian(const ResidualFunction& f, std::span<const double> x,
                     std::span<const double> r0, std::span<const double> lower,
                     std::span<const double> upper, double step, bool central, int threads,
                     Eigen::MatrixXd& jac, int64_t* evaluations) {
  return NumericJacobian(ParallelResiduals(f, threads), x, r0, lower, upper, step, central, jac,
                         evaluations);
}

bool NumericJacobian(const BatchResidualFunction& f, std::span<const double> x,
                     std::span<const double> r0, std::span<const double> lower,
                     std::span<const double> upper, double step, bool central, Eigen::MatrixXd& jac,
                     int64_t* evaluations) {
  const int n = static_cast<int>(x.size());
  const int m = static_cast<int>(r0.size());
  jac.setZero(m, n);
  // Every column's points (up and/or down), evaluated as one batch.
  struct Column {
    double up = 0, dn = 0;
    int ip = -1, im = -1;  // indices into the batch
  };
  std::vector<Column> cols(n);
  std::vector<std::vector<double>> xs;
  for (int j = 0; j < n; ++j) {
    Column& c = cols[j];
    c.up = std::min(upper[j], x[j] + step);
    c.dn = std::max(lower[j], x[j] - step);
    const bool use_up = c.up > x[j];
    const bool use_dn = c.dn < x[j] && (central || !use_up);
    if (use_up) {
      c.ip = static_cast<int>(xs.size());
      xs.emplace_back(x.begin(), x.end());
      xs.back()[j] = c.up;
    }
    if (use_dn) {
      c.im = static_cast<int>(xs.size());
      xs.emplace_back(x.begin(), x.end());
      xs.back()[j] = c.dn;
    }
  }
  std::vector<std::vector<double>> rs;
  std::vector<char> ok;
  if (!xs.empty()) f(xs, rs, ok);
  if (evaluations) *evaluations += static_cast<int64_t>(xs.size());
  bool all_ok = true;
  for (int j = 0; j < n; ++j) {
    const Column& c = cols[j];
    const bool okp = c.ip >= 0 && ok[c.ip] && rs[c.ip].size() == static_cast<size_t>(m);
    const bool okm = c.im >= 0 && ok[c.im] && rs[c.im].size() == static_cast<size_t>(m);
    if (okp && okm) {
      const auto& rp = rs[c.ip];
      const auto& rm = rs[c.im];
      for (int i = 0; i < m; ++i) jac(i, j) = (rp[i] - rm[i]) / (c.up - c.dn);
    } else if (okp) {
      const auto& rp = rs[c.ip];
      for (int i = 0; i < m; ++i) jac(i, j) = (rp[i] - r0[i]) / (c.up - x[j]);
    } else if (okm) {
      const auto& rm = rs[c.im];
      for (int i = 0; i < m; ++i) jac(i, j) = (r0[i] - rm[i]) / (x[j] - c.dn);
    } else if (c.ip >= 0 || c.im >= 0) {
      all_ok = false;
    }
  }
  return all_ok;
}

LmResult LevenbergMarquardt(const ResidualFunction& f, std::vector<double> x,
                            std::span<const double> lower, std::span<const double> upper,
                            const LmOptions& o) {
  ThrowIfError(o.Validate());
  return LevenbergMarquardt(ParallelResiduals(f, o.threads), std::move(x), lower, upper, o);
}

namespace {

/// The free variables: not held at a bound by a gradient pointing out of the box.
std::vector<int> FreeVariables(const std::vector<double>& x, const Eigen::VectorXd& g,
                               std::span<const double> lower, std::span<const double> upper) {
  std::vector<int> free;
  for (int j = 0; j < static_cast<int>(x.size()); ++j) {
    const bool at_lo = x[j] <= lower[j] && g[j] > 0;
    const bool at_hi = x[j] >= upper[j] && g[j] < 0;
    if (!at_lo && !at_hi) free.push_back(j);
  }
  return free;
}

/// JᵀJ and Jᵀr over the free variables, with the damping's diagonal (JᵀJ's, floored at 1e-12 of
/// its largest).
struct FreeSystem {
  Eigen::MatrixXd a;
  Eigen::VectorXd g, d;

  FreeSystem(const Eigen::MatrixXd& jtj, const Eigen::VectorXd& jtr, const std::vector<int>& free) {
    const int nf = static_cast<int>(free.size());
    a.resize(nf, nf);
    g.resize(nf);
    d.resize(nf);
    double dmax = 0;
    for (int i = 0; i < nf; ++i) dmax = std::max(dmax, jtj(free[i], free[i]));
    for (int i = 0; i < nf; ++i) {
      g[i] = jtr[free[i]];
      d[i] = std::max(jtj(free[i], free[i]), 1e-12 * dmax + 1e-300);
      for (int k = 0; k < nf; ++k) a(i, k) = jtj(free[i], free[k]);
    }
  }
};

}  // namespace

LmResult LevenbergMarquardt(const BatchResidualFunction& fb, std::vector<double> x,
                            std::span<const double> lower, std::span<const double> upper,
                            const LmOptions& o) {
  ThrowIfError(o.Validate());
  // One point at a time (the start and the trial steps).
  std::vector<std::vector<double>> one(1), rs1;
  std::vector<char> ok1;
  auto f = [&](std::span<const double> p, std::vector<double>& r) {
    one[0].assign(p.begin(), p.end());
    fb(one, rs1, ok1);
    r = std::move(rs1[0]);
    return ok1[0] != 0;
  };
  const int n = static_cast<int>(x.size());
  PZ_CHECK(lower.size() == x.size() && upper.size() == x.size());
  for (int j = 0; j < n; ++j) x[j] = std::clamp(x[j], lower[j], upper[j]);
  LmResult res;
  res.x = x;
  auto sq = [](const std::vector<double>& r) {
    double s = 0;
    for (double e : r) s += e * e;
    return s;
  };
  if (!f(x, res.r)) {
    res.cost = std::numeric_limits<double>::infinity();
    res.message = "initial point cannot be evaluated";
    return res;
  }
  res.evaluations = 1;
  res.cost = sq(res.r);
  double lambda = o.lambda0;
  std::vector<double> r_new;
  bool central = o.central;
  // Forward differences stopped (converged by a rule, not the iteration limit): finish with central
  // ones from there when asked. False: stop.
  auto finish_central = [&] {
    if (central || !o.central_to_finish) return false;
    central = true;
    res.converged = false;
    res.message.clear();
    if (lambda > 1e10) lambda = o.lambda0;  // the forward Jacobian found no descent step
    return true;
  };
  for (int it = 0; it < o.max_iterations; ++it) {
    NumericJacobian(fb, res.x, res.r, lower, upper, o.fd_step, central, res.jacobian,
                    &res.evaluations);
    res.iterations = it + 1;
    const Eigen::Map<const Eigen::VectorXd> rv(res.r.data(),
                                               static_cast<Eigen::Index>(res.r.size()));
    const Eigen::MatrixXd a = res.jacobian.transpose() * res.jacobian;
    const Eigen::VectorXd g = res.jacobian.transpose() * rv;
    const std::vector<int> free = FreeVariables(res.x, g, lower, upper);
    if (free.empty()) {
      res.converged = true;
      res.message = "every parameter held at a bound";
      if (finish_central()) continue;
      break;
    }
    const int nf = static_cast<int>(free.size());
    const FreeSystem sys(a, g, free);
    const Eigen::MatrixXd& af = sys.a;
    const Eigen::VectorXd &gf = sys.g, &df = sys.d;
    bool accepted = false, done = false;
    while (!accepted) {
      Eigen::MatrixXd m = af;
      for (int i = 0; i < nf; ++i) m(i, i) += lambda * df[i];
      const Eigen::VectorXd step = m.ldlt().solve(-gf);
      std::vector<double> xn = res.x;
      double smax = 0;
      for (int i = 0; i < nf; ++i) {
        const int j = free[i];
        xn[j] = std::clamp(res.x[j] + step[i], lower[j], upper[j]);
        smax = std::max(smax, std::abs(xn[j] - res.x[j]));
      }
      if (!(smax > o.xtol)) {
        done = true;
        res.converged = true;
        res.message = "step below xtol";
        break;
      }
      const bool ok = f(xn, r_new);
      ++res.evaluations;
      const double c = ok ? sq(r_new) : std::numeric_limits<double>::infinity();
      if (ok && c < res.cost) {
        const double gain = res.cost - c;
        res.x = xn;
        res.r = r_new;
        res.cost = c;
        lambda = std::max(lambda / 3.0, 1e-9);
        accepted = true;
        if (gain < o.ftol * c) {
          done = true;
          res.converged = true;
          res.message = "relative cost decrease below ftol";
        }
      } else {
        lambda *= 4.0;
        if (lambda > 1e10) {
          done = true;
          res.converged = true;
          res.message = "no descent step (damping at its limit)";
          break;
        }
      }
    }
    if (done && !finish_central()) break;
  }
  if (res.message.empty()) res.message = "iteration limit";
  return res;
}

}  // namespace pz::opt
