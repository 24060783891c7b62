#include "records/nnls.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace pz::records {

Eigen::VectorXd NonNegativeLeastSquares(const Eigen::MatrixXd& G, const Eigen::VectorXd& h) {
  const Eigen::Index n = h.size();
  Eigen::VectorXd w = Eigen::VectorXd::Zero(n);
  std::vector<char> passive(static_cast<size_t>(n), 0);
  const double tol = 1e-12 * std::max(1.0, G.diagonal().cwiseAbs().maxCoeff()) *
                     std::max(1.0, h.cwiseAbs().maxCoeff());
  auto solve_passive = [&](Eigen::VectorXd& s) {
    std::vector<Eigen::Index> idx;
    for (Eigen::Index i = 0; i < n; ++i)
      if (passive[static_cast<size_t>(i)]) idx.push_back(i);
    const Eigen::Index m = static_cast<Eigen::Index>(idx.size());
    Eigen::MatrixXd Gp(m, m);
    Eigen::VectorXd hp(m);
    for (Eigen::Index a = 0; a < m; ++a) {
      hp(a) = h(idx[static_cast<size_t>(a)]);
      for (Eigen::Index b = 0; b < m; ++b)
        Gp(a, b) = G(idx[static_cast<size_t>(a)], idx[static_cast<size_t>(b)]);
    }
    // A tiny ridge keeps nearly collinear plays solvable.
    Gp.diagonal().array() += 1e-13 * std::max(1.0, Gp.diagonal().maxCoeff());
    const Eigen::VectorXd sp = Gp.ldlt().solve(hp);
    s.setZero(n);
    for (Eigen::Index a = 0; a < m; ++a) s(idx[static_cast<size_t>(a)]) = sp(a);
  };
  for (int outer = 0; outer < 3 * n + 10; ++outer) {
    const Eigen::Index best = EnteringVariable(h - G * w, passive, tol);
    if (best < 0) break;
    passive[static_cast<size_t>(best)] = 1;
    for (int inner = 0; inner < 3 * n + 10; ++inner) {
      Eigen::VectorXd s;
      solve_passive(s);
      bool feasible = true;
      for (Eigen::Index i = 0; i < n; ++i)
        if (passive[static_cast<size_t>(i)] && s(i) <= 0) feasible = false;
      if (feasible) {
        w = s;
        break;
      }
      double alpha = 1;
      for (Eigen::Index i = 0; i < n; ++i) {
        if (passive[static_cast<size_t>(i)] && s(i) <= 0)
          alpha = std::min(alpha, w(i) / (w(i) - s(i)));
      }
      w += alpha * (s - w);
      for (Eigen::Index i = 0; i < n; ++i) {
        if (passive[static_cast<size_t>(i)] &&
            w(i) <= 1e-15 * std::max(1.0, w.cwiseAbs().maxCoeff())) {
          passive[static_cast<size_t>(i)] = 0;
          w(i) = 0;
        }
      }
    }
  }
  return w;
}
namespace {

/// The Cholesky factor of G_PP + εI for an ordered passive set P, updated in place.
class PassiveFactor {
 public:
  PassiveFactor(const Eigen::MatrixXd& G, double ridge)
      : G_(G), ridge_(ridge), L_(G.rows(), G.rows()) {}
  const std::vector<Eigen::Index>& set() const { return P_; }
  Eigen::Index size() const { return static_cast<Eigen::Index>(P_.size()); }
  /// Factors P afresh; false when G_PP + εI is not positive definite.
  bool Reset(const std::vector<Eigen::Index>& P) {
    P_ = P;
    const Eigen::Index p = size();
    if (p == 0) return true;
    Eigen::MatrixXd S(p, p);
    for (Eigen::Index a = 0; a < p; ++a)
      for (Eigen::Index b = 0; b < p; ++b) S(a, b) = G_(P_[a], P_[b]);
    S.diagonal().array() += ridge_;
    Eigen::LLT<Eigen::MatrixXd> llt(S);
    if (llt.info() != Eigen::Success) return false;
    L_.topLeftCorner(p, p) = llt.matrixL();
    return true;
  }
  /// Appends variable j: L's new row y = L⁻¹ G_Pj, its diagonal √(G_jj + ε − yᵀy).
  void Add(Eigen::Index j) {
    const Eigen::Index p = size();
    Eigen::VectorXd y(p);
    for (Eigen::Index a = 0; a < p; ++a) y(a) = G_(P_[a], j);
    if (p > 0) L_.topLeftCorner(p, p).triangularView<Eigen::Lower>().solveInPlace(y);
    const double d2 = G_(j, j) + ridge_ - y.squaredNorm();
    L_.row(p).head(p) = y.transpose();
    L_(p, p) = std::sqrt(std::max(d2, ridge_));  // collinear to rounding: the ridge alone
    P_.push_back(j);
  }
  /// Removes the variable at position q: the rows and columns after it move up, and the trailing
  /// block takes the removed column's part by a rank-one update.
  void Remove(Eigen::Index q) {
    const Eigen::Index p = size(), t = p - 1 - q;
    Eigen::VectorXd x = L_.col(q).segment(q + 1, t);
    for (Eigen::Index i = q; i < p - 1; ++i) {
      for (Eigen::Index c = 0; c < q; ++c) L_(i, c) = L_(i + 1, c);
      for (Eigen::Index c = q; c <= i; ++c) L_(i, c) = L_(i + 1, c + 1);
    }
    for (Eigen::Index k = 0; k < t; ++k) {  // L33 L33ᵀ + x xᵀ
      const Eigen::Index kk = q + k;
      const double lkk = L_(kk, kk), r = std::hypot(lkk, x(k)), c = r / lkk, s = x(k) / lkk;
      L_(kk, kk) = r;
      for (Eigen::Index i = k + 1; i < t; ++i) {
        const Eigen::Index ii = q + i;
        L_(ii, kk) = (L_(ii, kk) + s * x(i)) / c;
        x(i) = c * x(i) - s * L_(ii, kk);
      }
    }
    P_.erase(P_.begin() + q);
  }
  /// The least squares on P: s_P = (G_PP + εI)⁻¹ h_P (others 0).
  void Solve(const Eigen::VectorXd& h, Eigen::VectorXd& s) const {
    const Eigen::Index p = size();
    Eigen::VectorXd z(p);
    for (Eigen::Index a = 0; a < p; ++a) z(a) = h(P_[a]);
    const auto L = L_.topLeftCorner(p, p);
    L.triangularView<Eigen::Lower>().solveInPlace(z);
    L.transpose().triangularView<Eigen::Upper>().solveInPlace(z);
    s.setZero(h.size());
    for (Eigen::Index a = 0; a < p; ++a) s(P_[a]) = z(a);
  }

 private:
  const Eigen::MatrixXd& G_;
  double ridge_;
  Eigen::MatrixXd L_;
  std::vector<Eigen::Index> P_;
};

}  // namespace

Eigen::Index EnteringVariable(const Eigen::VectorXd& g, const std::vector<char>& passive,
                              double tol) {
  Eigen::Index best = -1;
  double gbest = tol;
  for (Eigen::Index i = 0; i < g.size(); ++i) {
    if (!passive[static_cast<size_t>(i)] && g(i) > gbest) {
      gbest = g(i);
      best = i;
    }
  }
  return best;
}

Eigen::VectorXd NonNegativeLeastSquaresFrom(const Eigen::MatrixXd& G, const Eigen::VectorXd& h,
                                            const Eigen::VectorXd& start) {
  const Eigen::Index n = h.size();
  if (n == 0) return Eigen::VectorXd();
  const double dmax = G.diagonal().cwiseAbs().maxCoeff();
  const double tol = 1e-12 * std::max(1.0, dmax) * std::max(1.0, h.cwiseAbs().maxCoeff());
  PassiveFactor F(G, 1e-13 * std::max(1.0, dmax));
  Eigen::VectorXd w = Eigen::VectorXd::Zero(n);
  std::vector<char> passive(static_cast<size_t>(n), 0);
  std::vector<Eigen::Index> P;
  // No start: the unconstrained solution's positive part (one factorisation instead of a step per
  // positive weight from w = 0).
  Eigen::VectorXd ls;
  if (start.size() != n) {
    Eigen::MatrixXd G0 = G;
    G0.diagonal().array() += 1e-13 * std::max(1.0, dmax);
    ls = G0.ldlt().solve(h).cwiseMax(0.0);
    if (!ls.allFinite()) ls = Eigen::VectorXd::Zero(n);
  }
  const Eigen::VectorXd& from = start.size() == n ? start : ls;
  {
    for (Eigen::Index i = 0; i < n; ++i) {
      if (from(i) > 0 && std::isfinite(from(i))) {
        w(i) = from(i);
        passive[static_cast<size_t>(i)] = 1;
        P.push_back(i);
      }
    }
  }
  if (!F.Reset(P)) return NonNegativeLeastSquares(G, h);
  Eigen::VectorXd s;
  // The passive set's least squares, stepping back towards w while it is infeasible
  // (Lawson–Hanson's inner loop): w stays feasible, variables that reach zero leave.
  auto inner = [&] {
    for (int it = 0; it < 3 * n + 10; ++it) {
      F.Solve(h, s);
      bool feasible = true;
      double alpha = 1;
      for (Eigen::Index i : F.set()) {
        if (s(i) <= 0) {
          feasible = false;
          alpha = std::min(alpha, w(i) / (w(i) - s(i)));
        }
      }
      if (feasible) {
        w = s;
        return;
      }
      w += alpha * (s - w);
      const double floor = 1e-15 * std::max(1.0, w.cwiseAbs().maxCoeff());
      for (Eigen::Index q = F.size(); q-- > 0;) {
        const Eigen::Index i = F.set()[static_cast<size_t>(q)];
        if (w(i) <= floor) {
          passive[static_cast<size_t>(i)] = 0;
          w(i) = 0;
          F.Remove(q);
        }
      }
    }
  };
  if (F.size() > 0) inner();
  for (int outer = 0; outer < 3 * n + 10; ++outer) {
    const Eigen::Index best = EnteringVariable(h - G * w, passive, tol);
    if (best < 0) break;
    passive[static_cast<size_t>(best)] = 1;
    F.Add(best);
    inner();
  }
  return w;
}

}  // namespace pz::records
