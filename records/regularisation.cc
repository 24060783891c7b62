#include "records/regularisation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <stdexcept>
#include <thread>

#include "model/format.h"
#include "model/status.h"
#include "records/nnls.h"

namespace pz::records {
namespace {

std::string Short(double x) { return FormatG(x, 4); }

}  // namespace

std::string WeightValidation::Describe() const {
  if (!used) return "none";
  if (relatives.empty()) return "none chosen (no validation ran)";
  std::string s = (penalty_name.empty() ? "" : penalty_name + ", ") + "strength " +
                  Short(relative) + " × tr(AᵀA)/tr(R) (λ = " + Short(lambda) + ") chosen by " +
                  std::to_string(folds) + "-fold blocked cross-validation; CV RMSE:";
  for (size_t i = 0; i < relatives.size(); ++i)
    s += (i ? ", " : " ") + Short(relatives[i]) + " → " + Short(cv_rmse[i]);
  if (candidates.size() > 1) {
    s += "; kept against";
    for (size_t k = 0, n = 0; k < candidates.size(); ++k) {
      if (k == penalty) continue;
      s += std::string(n++ ? "," : "") + " " + candidates[k] + " (CV RMSE " +
           Short(candidates_cv_rmse[k]) + " at " + Short(compared_at) + ", this one's " +
           Short(candidates_cv_rmse[penalty]) + ")";
    }
  }
  return s;
}

WeightValidation ChoosePenalty(const BlockedNormalEquations& eq,
                               const std::vector<Eigen::MatrixXd>& Rs,
                               const std::vector<std::string>& names) {
  if (Rs.empty() || Rs.size() != names.size())
    throw std::logic_error("ChoosePenalty: no penalty, or names mismatch");
  std::vector<WeightValidation> v;
  for (size_t k = 0; k < Rs.size(); ++k) {
    v.push_back(ChooseStrength(eq, Rs[k]));
    v.back().penalty = k;
    v.back().penalty_name = names[k];
  }
  if (v.size() == 1) return v.front();
  // The first candidate strength above every chosen one (the candidates are the same for all).
  const std::vector<double>& rel = v.front().relatives;
  size_t at = 0;
  for (const WeightValidation& w : v) {
    const size_t chosen =
        static_cast<size_t>(std::find(rel.begin(), rel.end(), w.relative) - rel.begin());
    at = std::max(at, chosen + 1);
  }
  at = std::min(at, rel.size() - 1);
  size_t kept = 0;
  for (size_t k = 1; k < v.size(); ++k)
    if (v[k].cv_rmse[at] < v[kept].cv_rmse[at]) kept = k;
  WeightValidation out = v[kept];
  out.compared_at = rel[at];
  for (size_t k = 0; k < v.size(); ++k) {
    out.candidates.push_back(names[k]);
    out.candidates_cv_rmse.push_back(v[k].cv_rmse[at]);
  }
  return out;
}

WeightValidation ChooseStrength(const BlockedNormalEquations& eq, const Eigen::MatrixXd& R) {
  Eigen::MatrixXd G = eq.G[0];
  for (size_t b = 1; b < eq.G.size(); ++b) G += eq.G[b];
  const double trR = R.trace();
  return ChooseStrength(eq, R, trR > 0 ? G.trace() / trR : 0, StrengthRule{});
}

NormalEquationsBuilder::NormalEquationsBuilder(BlockedNormalEquations& eq, size_t columns,
                                               size_t samples)
    : eq_(eq), samples_(samples) {
  constexpr Eigen::Index kChunk = 256;
  const auto m = static_cast<Eigen::Index>(columns);
  for (size_t b = 0; b < eq.G.size(); ++b) {
    eq.G[b] = Eigen::MatrixXd::Zero(m, m);
    eq.h[b] = Eigen::VectorXd::Zero(m);
    eq.bb[b] = 0;
    eq.samples[b] = 0;
  }
  A_.resize(m, kChunk);
  b_.resize(kChunk);
}

double* NormalEquationsBuilder::Row() {
  if (filled_ == A_.cols()) Flush();
  return A_.data() + filled_ * A_.rows();
}

void NormalEquationsBuilder::Add(double target) {
  const size_t blocks = eq_.G.size();
  const size_t blk = blocks == 1 ? 0 : index_ * blocks / samples_;
  if (blk != block_ &&
      filled_ > 0) {  // the chunk so far is the previous block's: flushed without this row
    const Eigen::VectorXd row = A_.col(filled_);
    Flush();
    A_.col(0) = row;
  }
  block_ = blk;
  b_(filled_++) = target;
  ++index_;
}

void NormalEquationsBuilder::Flush() {
  if (filled_ == 0) return;
  const auto cols = A_.leftCols(filled_);
  const auto b = b_.head(filled_);
  eq_.G[block_].selfadjointView<Eigen::Lower>().rankUpdate(cols);
  eq_.h[block_].noalias() += cols * b;
  eq_.bb[block_] += b.squaredNorm();
  eq_.samples[block_] += static_cast<size_t>(filled_);
  filled_ = 0;
}

size_t NormalEquationsBuilder::BlockAhead(size_t ahead) const {
  const size_t blocks = eq_.G.size();
  return blocks == 1 ? 0 : (index_ + ahead) * blocks / samples_;
}

void NormalEquationsBuilder::AddSums(size_t block, const Eigen::MatrixXd& G,
                                     const Eigen::VectorXd& h, double bb, size_t rows) {
  if (rows == 0) return;
  if (block >= eq_.G.size() || BlockAhead(0) != block || BlockAhead(rows - 1) != block ||
      G.rows() != A_.rows() || h.size() != A_.rows())
    throw std::logic_error(
        "NormalEquationsBuilder::AddSums: rows outside their block or sizes mismatch");
  Flush();  // the rows so far first (their block's sums in row order)
  eq_.G[block].triangularView<Eigen::Lower>() += G;
  eq_.h[block] += h;
  eq_.bb[block] += bb;
  eq_.samples[block] += rows;
  index_ += rows;
  block_ = block;
}

void NormalEquationsBuilder::Finish() {
  Flush();
  for (Eigen::MatrixXd& G : eq_.G) G.triangularView<Eigen::StrictlyUpper>() = G.transpose();
}

Eigen::MatrixXd SpectrumRoughness(size_t n) {
  const auto m = static_cast<Eigen::Index>(n);
  Eigen::MatrixXd D = Eigen::MatrixXd::Zero(std::max<Eigen::Index>(m - 1, 0), m);
  for (Eigen::Index i = 0; i + 1 < m; ++i) {
    D(i, i) = -1;
    D(i, i + 1) = 1;
  }
  return D;
}

WeightValidation ChooseStrength(const BlockedNormalEquations& eq, const Eigen::MatrixXd& R,
                                double scale, const StrengthRule& rule) {
  const size_t K = eq.G.size();
  WeightValidation v;
  v.used = true;
  v.folds = static_cast<int>(K);
  size_t total = 0;
  for (size_t b = 0; b < K; ++b) {
    if (eq.samples[b] == 0)
      throw InputError("regularisation: fewer training samples than validation blocks");
    total += eq.samples[b];
  }
  Eigen::MatrixXd G = eq.G[0];
  Eigen::VectorXd h = eq.h[0];
  for (size_t b = 1; b < K; ++b) {
    G += eq.G[b];
    h += eq.h[b];
  }
  v.relatives = {0, 1e-6, 1e-5, 1e-4, 1e-3, 1e-2, 1e-1, 1, 10, 100};
  std::vector<std::vector<double>> err(v.relatives.size(), std::vector<double>(K));
  // Many unknowns (kIncrementalNnlsFrom): each block's solves in order of strength, each from the
  // previous one's weights (records/nnls.h; the same optimum to rounding).
  // Many unknowns (kIncrementalNnlsFrom): records/nnls.h, each solve from a neighbouring one's
  // weights (the same optimum to rounding; a few steps instead of one per positive weight from
  // w = 0): every block's first strength from all the blocks' weights there (four fifths of the
  // same rows; those from the unconstrained solution's positive part), its next strengths from its
  // previous one; the blocks on kValidationThreads threads (each block's solves its own: the same
  // result whatever the threads).
  const bool incremental = G.rows() >= kIncrementalNnlsFrom;
  Eigen::VectorXd all;
  if (incremental)  // from the unconstrained solution's positive part
    all = NonNegativeLeastSquaresFrom(G + (v.relatives[0] * scale) * R, h, Eigen::VectorXd());
  auto block = [&](size_t b) {
    Eigen::VectorXd w = all;
    for (size_t c = 0; c < v.relatives.size(); ++c) {
      const Eigen::MatrixXd Gm = G - eq.G[b] + (v.relatives[c] * scale) * R;
      w = incremental ? NonNegativeLeastSquaresFrom(Gm, h - eq.h[b], w)
                      : NonNegativeLeastSquares(Gm, h - eq.h[b]);
      err[c][b] = std::max(0.0, w.dot(eq.G[b] * w) - 2 * eq.h[b].dot(w) + eq.bb[b]);
    }
  };
  if (incremental) {
    std::vector<std::thread> pool;
    for (size_t t = 0; t < static_cast<size_t>(kValidationThreads); ++t)
      pool.emplace_back([&, t] {
        for (size_t b = t; b < K; b += static_cast<size_t>(kValidationThreads)) block(b);
      });
    for (std::thread& th : pool) th.join();
  } else {
    for (size_t b = 0; b < K; ++b) block(b);
  }
  for (size_t c = 0; c < v.relatives.size(); ++c) {
    double sse = 0;
    for (size_t b = 0; b < K; ++b) sse += err[c][b];
    v.cv_rmse.push_back(std::sqrt(sse / static_cast<double>(total)));
  }
  size_t best = 0;
  for (size_t c = 1; c < v.cv_rmse.size(); ++c)
    if (v.cv_rmse[c] < v.cv_rmse[best]) best = c;
  size_t chosen = best;
  for (size_t c = best + 1; c < v.relatives.size(); ++c) {
    double mean = 0, sq = 0;
    for (size_t b = 0; b < K; ++b) mean += err[c][b] - err[best][b];
    mean /= static_cast<double>(K);
    for (size_t b = 0; b < K; ++b)
      sq += (err[c][b] - err[best][b] - mean) * (err[c][b] - err[best][b] - mean);
    const double se = std::sqrt(sq / static_cast<double>(K - 1) / static_cast<double>(K));
    const bool negligible =
        rule.rmse_tolerance > 0 && v.cv_rmse[c] <= (1 + rule.rmse_tolerance) * v.cv_rmse[best];
    if (mean > se && !negligible) {
      if (rule.contiguous) break;
      continue;
    }
    chosen = c;
  }
  v.relative = v.relatives[chosen];
  v.lambda = v.relative * scale;
  v.block_sse = err[chosen];
  return v;
}

std::string ResolutionChoice::Describe() const {
  if (!used) return "given";
  std::string s =
      std::to_string(value()) + " " + what + " by " + std::to_string(kValidationBlocks) +
      "-fold blocked cross-validation (the fewest within one standard error of the best, " +
      std::to_string(candidates[best]) + "); CV RMSE:";
  for (size_t i = 0; i < candidates.size(); ++i) {
    s += (i ? ", " : " ") + std::to_string(candidates[i]) + " → " +
         (refused[i].empty() ? Short(cv_rmse[i]) : "not tried (" + refused[i] + ")");
  }
  return s;
}

ResolutionChoice ChooseResolution(const std::vector<int>& candidates,
                                  const std::vector<WeightValidation>& v,
                                  const std::vector<std::string>& refused) {
  if (candidates.empty() || v.size() != candidates.size() || refused.size() != candidates.size())
    throw std::logic_error("ChooseResolution: sizes mismatch");
  ResolutionChoice c;
  c.used = true;
  c.candidates = candidates;
  c.refused = refused;
  std::vector<double> sses;  // per candidate (refused: +inf)
  bool any = false;
  for (size_t i = 0; i < v.size(); ++i) {
    if (!refused[i].empty()) {
      c.cv_rmse.push_back(std::numeric_limits<double>::infinity());
      sses.push_back(std::numeric_limits<double>::infinity());
      continue;
    }
    if (v[i].block_sse.size() != static_cast<size_t>(kValidationBlocks) ||
        v[i].folds != kValidationBlocks)
      throw std::logic_error("ChooseResolution: a candidate without its blocks' errors");
    double sse = 0;
    for (double e : v[i].block_sse) sse += e;
    sses.push_back(sse);
    const auto at = std::find(v[i].relatives.begin(), v[i].relatives.end(), v[i].relative) -
                    v[i].relatives.begin();
    c.cv_rmse.push_back(v[i].cv_rmse.at(static_cast<size_t>(at)));  // the chosen strength's
    if (!any || sse < sses[c.best]) c.best = i;
    any = true;
  }
  if (!any) throw std::logic_error("ChooseResolution: every candidate refused");
  const size_t K = static_cast<size_t>(kValidationBlocks);
  c.chosen = c.best;
  for (size_t i = 0; i < c.best; ++i) {
    if (!refused[i].empty()) continue;
    double mean = 0, sq = 0;
    for (size_t b = 0; b < K; ++b) mean += v[i].block_sse[b] - v[c.best].block_sse[b];
    mean /= static_cast<double>(K);
    for (size_t b = 0; b < K; ++b) {
      const double d = v[i].block_sse[b] - v[c.best].block_sse[b] - mean;
      sq += d * d;
    }
    if (mean <= std::sqrt(sq / static_cast<double>(K - 1) / static_cast<double>(K))) {
      c.chosen = i;
      break;
    }
  }
  return c;
}

}  // namespace pz::records
