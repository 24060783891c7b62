#include "records/preisach_normal.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "records/model.h"

namespace pz::records {
namespace {

/// The grid's widths: half-widths, constants, cells and histogram slots (n − i + 1 levels each).
struct Widths {
  int n = 0;
  double delta = 0, u_min = 0;
  std::vector<double> r, base, k;
  std::vector<size_t> cell0, slot0;  ///< first cell / first histogram slot of width i
  std::vector<size_t> pair0;         ///< pair (i < i'): first entry of its histogram, i * n + i'
  size_t cells = 0, slots = 0, pair_entries = 0;
  explicit Widths(const model::PreisachGrid& g) : n(g.levels), delta(g.step()), u_min(g.u_min) {
    for (int i = 0; i < n; ++i) {
      r.push_back(g.half_width(i));
      base.push_back(g.u_min + r.back());
      k.push_back((g.u_min + r.back()) / (n - i));
      cell0.push_back(cells);
      slot0.push_back(slots);
      cells += static_cast<size_t>(n - i);
      slots += static_cast<size_t>(n - i + 1);
    }
    pair0.assign(static_cast<size_t>(n) * static_cast<size_t>(n), 0);
    for (int i = 0; i < n; ++i)
      for (int q = i + 1; q < n; ++q) {
        pair0[static_cast<size_t>(i) * static_cast<size_t>(n) + static_cast<size_t>(q)] =
            pair_entries;
        pair_entries += static_cast<size_t>(n - i + 1) * static_cast<size_t>(n - q + 1);
      }
  }
  size_t cells_of(int i) const { return static_cast<size_t>(n - i); }
};

/// Per-thread buffers, kept from call to call.
struct Scratch {
  std::vector<double> H;                   ///< pair histograms, 4 per entry: 1, f', f, f f'
  std::vector<double> c0, c1, c2, e0, e1;  ///< per slot: 1, f, f², t, f t
  std::vector<int32_t> J;                  ///< per row and width
  std::vector<double> f;
  std::vector<double> tail;  ///< T0(a) = Σ_{J ≥ a} c0 of one width
  Eigen::MatrixXd G;
  Eigen::VectorXd sv, svt, c;
};

/// The segment's sums of v vᵀ, v and v t from the histograms (then zeroed) into s.G, s.sv, s.svt.
void Sums(const Widths& w, Scratch& s) {
  const int n = w.n;
  const double d = w.delta, d2 = d * d;
  s.G.setZero(static_cast<Eigen::Index>(w.cells), static_cast<Eigen::Index>(w.cells));
  s.sv.resize(static_cast<Eigen::Index>(w.cells));
  s.svt.resize(static_cast<Eigen::Index>(w.cells));
  for (int i = 0; i < n; ++i) {
    const size_t ni = w.cells_of(i), o = w.slot0[i], c = w.cell0[i];
    // Suffix sums T0(a) = Σ_{J ≥ a} c0, E0(a) = Σ_{J ≥ a} e0.
    double t0 = s.c0[o + ni], e0 = s.e0[o + ni];  // the level past the last cell: every cell full
    std::vector<double>& T0 = s.tail;
    T0.resize(ni + 1);
    T0[ni] = t0;
    for (size_t j = ni; j-- > 0;) {
      // T0[j + 1] holds Σ_{J > j}; the cell j: Σ v = Δ (Σ_{J > j} + f at J = j).
      s.sv(static_cast<Eigen::Index>(c + j)) = d * (t0 + s.c1[o + j]);
      s.svt(static_cast<Eigen::Index>(c + j)) = d * (e0 + s.e1[o + j]);
      t0 += s.c0[o + j];
      e0 += s.e0[o + j];
      T0[j] = t0;
    }
    for (size_t j = 0; j < ni; ++j) {
      for (size_t q = j; q < ni; ++q) {
        const double v = d2 * (T0[q + 1] + (j < q ? s.c1[o + q] : s.c2[o + j]));
        s.G(static_cast<Eigen::Index>(c + q), static_cast<Eigen::Index>(c + j)) = v;
      }
    }
  }
  for (int i = 0; i < n; ++i) {
    for (int q = i + 1; q < n; ++q) {
      const size_t a = w.cells_of(i) + 1,
                   b = w.cells_of(q) + 1;  // histogram rows (J_i), columns (J_q)
      double* h =
          s.H.data() +
          4 * w.pair0[static_cast<size_t>(i) * static_cast<size_t>(n) + static_cast<size_t>(q)];
      auto at = [&](size_t J, size_t Jq, int t) -> double& {
        return h[4 * (J * b + Jq) + static_cast<size_t>(t)];
      };
      // In place: H0 → its suffix sums over both axes, H1 over J, H2 over J'.
      for (size_t J = a; J-- > 0;) {
        for (size_t Jq = b; Jq-- > 0;) {
          if (Jq + 1 < b) {
            at(J, Jq, 0) += at(J, Jq + 1, 0);
            at(J, Jq, 2) += at(J, Jq + 1, 2);
          }
        }
        if (J + 1 < a) {
          for (size_t Jq = 0; Jq < b; ++Jq) {
            at(J, Jq, 0) += at(J + 1, Jq, 0);
            at(J, Jq, 1) += at(J + 1, Jq, 1);
          }
        }
      }
      const size_t ci = w.cell0[static_cast<size_t>(i)], cq = w.cell0[static_cast<size_t>(q)];
      for (size_t j = 0; j + 1 < a; ++j) {
        for (size_t jq = 0; jq + 1 < b; ++jq) {
          const double v =
              d2 * (at(j + 1, jq + 1, 0) + at(j + 1, jq, 1) + at(j, jq + 1, 2) + at(j, jq, 3));
          s.G(static_cast<Eigen::Index>(cq + jq), static_cast<Eigen::Index>(ci + j)) =
              v;  // lower: q > i
        }
      }
      std::fill(h, h + 4 * a * b, 0.0);
    }
  }
  std::fill(s.c0.begin(), s.c0.end(), 0.0);
  std::fill(s.c1.begin(), s.c1.end(), 0.0);
  std::fill(s.c2.begin(), s.c2.end(), 0.0);
  std::fill(s.e0.begin(), s.e0.end(), 0.0);
  std::fill(s.e1.begin(), s.e1.end(), 0.0);
}

}  // namespace

bool AddPreisachRecordRows(const model::PreisachGrid& grid, model::InitialState start,
                           const io::Record& r, size_t from, std::span<const double> u, int pol,
                           NormalEquationsBuilder& builder) {
  ThrowIfError(grid.Validate());
  if (r.scored() == 0) return true;
  for (double v : u)
    if (!std::isfinite(v)) return false;
  model::RequireResolved(start, "AddPreisachRecordRows");
  const Widths w(grid);
  const int n = w.n;
  const size_t rows = u.size(), nn = static_cast<size_t>(n);
  if (rows == 0 || RegressorRow(r.end_scored - 1, from) >= rows)
    throw InputError("AddPreisachRecordRows: " + std::to_string(rows) +
                     " drive rows for the record's window");
  thread_local Scratch s;
  // Every row's levels: the plays from rest at u[0], as PreisachRegressors runs them.
  s.J.resize(rows * nn);
  s.f.resize(rows * nn);
  {
    std::vector<double> p(nn);
    for (size_t i = 0; i < nn; ++i) p[i] = model::PlayRest(u[0], w.r[i], start);
    for (size_t k = 0; k < rows; ++k) {
      for (size_t i = 0; i < nn; ++i) {
        p[i] = std::max(u[k] - w.r[i], std::min(u[k] + w.r[i], p[i]));
        const double top = static_cast<double>(w.cells_of(static_cast<int>(i)));
        const double L = std::clamp((p[i] - w.base[i]) / w.delta, 0.0, top);
        const double J = std::min(std::floor(L), top);
        s.J[k * nn + i] = static_cast<int32_t>(J);
        s.f[k * nn + i] = L - J;
      }
    }
  }
  const Eigen::Index m = static_cast<Eigen::Index>(w.cells);
  // The row of a level pattern (without the constants): v_ij = Δ (1[j < J] + f 1[j = J]).
  auto row_of = [&](size_t row, Eigen::VectorXd& v) {
    v.setZero(m);
    for (size_t i = 0; i < nn; ++i) {
      const size_t J = static_cast<size_t>(s.J[row * nn + i]), c = w.cell0[i],
                   ni = w.cells_of(static_cast<int>(i));
      for (size_t j = 0; j < std::min(J, ni); ++j) v(static_cast<Eigen::Index>(c + j)) = w.delta;
      if (J < ni) v(static_cast<Eigen::Index>(c + J)) = w.delta * s.f[row * nn + i];
    }
  };
  // The centre of the rows in v (RecordCentre: the mean row, the rest row, or none: −k) and d.
  Eigen::VectorXd kvec(m);
  for (size_t i = 0; i < nn; ++i)
    for (size_t j = 0; j < w.cells_of(static_cast<int>(i)); ++j)
      kvec(static_cast<Eigen::Index>(w.cell0[i] + j)) = w.k[i];
  double d = 0;
  Eigen::VectorXd& c = s.c;
  if (r.offset_mode == io::OffsetMode::kFit) {
    c.setZero(m);
    Eigen::VectorXd v;
    for (size_t k = r.first_scored; k < r.end_scored; ++k) {
      row_of(RegressorRow(k, from), v);
      c += v;
      d += r.y[k];
    }
    c /= static_cast<double>(r.scored());
    d /= static_cast<double>(r.scored());
  } else if (r.offset_mode == io::OffsetMode::kRest) {
    row_of(0, c);
    d = r.offset;
  } else {
    c = -kvec;
    d = r.offset;
  }
  // Histograms per segment (the record's samples of one validation block).
  s.H.assign(4 * w.pair_entries, 0.0);
  for (std::vector<double>* h : {&s.c0, &s.c1, &s.c2, &s.e0, &s.e1}) h->assign(w.slots, 0.0);
  size_t k = r.first_scored;
  while (k < r.end_scored) {
    const size_t block = builder.BlockAhead(0);
    size_t end = k;
    double st = 0, stt = 0;
    while (end < r.end_scored && builder.BlockAhead(end - k) == block) {
      const size_t row = RegressorRow(end, from);
      const int32_t* J = s.J.data() + row * nn;
      const double* f = s.f.data() + row * nn;
      const double t = r.y[end] - d;
      st += t;
      stt += t * t;
      for (size_t i = 0; i < nn; ++i) {
        const size_t o = w.slot0[i] + static_cast<size_t>(J[i]);
        s.c0[o] += 1;
        s.c1[o] += f[i];
        s.c2[o] += f[i] * f[i];
        s.e0[o] += t;
        s.e1[o] += f[i] * t;
      }
      for (size_t i = 0; i < nn; ++i) {
        const size_t Ji = static_cast<size_t>(J[i]);
        const double fi = f[i];
        for (size_t q = i + 1; q < nn; ++q) {
          const size_t b = w.cells_of(static_cast<int>(q)) + 1;
          double* h = s.H.data() + 4 * (w.pair0[i * nn + q] + Ji * b + static_cast<size_t>(J[q]));
          h[0] += 1;
          h[1] += f[q];
          h[2] += fi;
          h[3] += fi * f[q];
        }
      }
      ++end;
    }
    Sums(w, s);
    const double cnt = static_cast<double>(end - k);
    // Σ (v − c)(v − c)ᵀ, its lower triangle; Σ pol (v − c) t.
    Eigen::MatrixXd& G = s.G;
    G.triangularView<Eigen::Lower>() -=
        s.sv * c.transpose() + c * s.sv.transpose() - cnt * c * c.transpose();
    const Eigen::VectorXd h = pol * (s.svt - st * c);
    builder.AddSums(block, G, h, stt, end - k);
    k = end;
  }
  return true;
}

}  // namespace pz::records
