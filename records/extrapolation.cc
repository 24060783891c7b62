#include "records/extrapolation.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "io/csv.h"
#include "records/excitation.h"

namespace pz::records {
namespace {

constexpr double kDriveShare = 0.02;  ///< of the training drive range
constexpr double kTermRmse = 3;       ///< × the training RMSE
constexpr double kRateFaster = 1.5;   ///< × the training's largest |du/dt|

/// The largest |du/dt| over the record's scored window, and the count of samples above `limit`.
double MaxRate(const io::Record& r, double limit, size_t* above = nullptr) {
  double m = 0;
  for (size_t k = r.first_scored; k + 1 < r.end_scored; ++k) {
    const double v = std::abs(r.u[k + 1] - r.u[k]) / r.dt;
    m = std::max(m, v);
    if (above && v > limit) ++*above;
  }
  return m;
}

/// The regressor rows of the record's samples [from, end_scored) at the fitted parameters.
size_t RegressorRows(const RecordModel& m, std::span<const double> params, const io::Record& r,
                     std::vector<double>& reg) {
  const size_t from = SimulatedFrom(r, r.end_scored);
  std::vector<double> ue;
  m.EffectiveDrive(r, params.subspan(m.family_param_count()), from, r.end_scored, ue);
  reg.resize(ue.size() * m.family().regressors());
  m.family().Regressors(ue, reg);
  return from;
}

}  // namespace

std::string ExtrapolationCheck::Describe(const std::string& du, const std::string& yu) const {
  std::string s = record + ": " + (flagged ? "FLAGGED" : "inside the training range");
  if (rate_ratio > 1) {
    s += "; rates up to " + io::FormatNumber(rate_ratio) + " × the fastest in training (" +
         io::FormatNumber(100 * rate_beyond_share) +
         " % of its samples faster): the rate-dependent lag is extrapolated";
  }
  if (drive_beyond > 0) {
    s += "; the drive goes " + io::FormatNumber(drive_beyond) + " " + du +
         " beyond the training drive range (" + io::FormatNumber(100 * drive_beyond_share) +
         " % of its samples)";
  }
  if (terms > 0) {
    s += "; " + std::to_string(terms) +
         " weighted term(s) leave their training range, carrying up to " +
         io::FormatNumber(term_max) + " " + yu + " of the prediction (RMS " +
         io::FormatNumber(term_rms) + " " + yu + ")";
  }
  return s;
}

std::vector<ExtrapolationCheck> CheckExtrapolation(const io::RecordSet& set, const FitResult& fit) {
  const RecordModel& m = *fit.model;
  const DataScale& s = m.scale();
  const double train_rmse = std::sqrt(std::max(fit.train_mse, 0.0));
  const bool linear = m.family().linear() && fit.weights.size() == m.family().regressors();
  const size_t nw = linear ? fit.weights.size() : 0;
  std::vector<double> lo(nw, std::numeric_limits<double>::infinity()),
      hi(nw, -std::numeric_limits<double>::infinity());
  std::vector<double> reg;
  if (linear) {
    for (const io::Record* r : set.WithRole(model::CaseRole::kTrain)) {
      const size_t from = RegressorRows(m, fit.params, *r, reg);
      for (size_t k = r->first_scored; k < r->end_scored; ++k) {
        const double* row = reg.data() + RegressorRow(k, from) * nw;
        for (size_t j = 0; j < nw; ++j) {
          lo[j] = std::min(lo[j], row[j]);
          hi[j] = std::max(hi[j], row[j]);
        }
      }
    }
  }
  const bool rates = std::any_of(m.effects().begin(), m.effects().end(), NeedsRateCoverage);
  double train_rate = 0;
  if (rates)
    for (const io::Record* r : set.WithRole(model::CaseRole::kTrain))
      train_rate = std::max(train_rate, MaxRate(*r, 0));
  std::vector<ExtrapolationCheck> out;
  for (const io::Record& r : set.records) {
    if (r.role == model::CaseRole::kTrain) continue;
    ExtrapolationCheck c;
    c.record = r.name;
    size_t outside = 0;
    for (size_t k = r.first_scored; k < r.end_scored; ++k) {
      const double e = std::max(s.u_min - r.u[k], r.u[k] - s.u_max);
      if (e > 0) {
        ++outside;
        c.drive_beyond = std::max(c.drive_beyond, e);
      }
    }
    c.drive_beyond_share = static_cast<double>(outside) / static_cast<double>(r.scored());
    if (linear) {
      const size_t from = RegressorRows(m, fit.params, r, reg);
      std::vector<char> left(nw, 0);
      double sq = 0;
      for (size_t k = r.first_scored; k < r.end_scored; ++k) {
        const double* row = reg.data() + RegressorRow(k, from) * nw;
        double e = 0;
        for (size_t j = 0; j < nw; ++j) {
          const double x = row[j], d = x - std::clamp(x, lo[j], hi[j]);
          if (d != 0 && fit.weights[j] != 0) {
            left[j] = 1;
            e += fit.weights[j] * d;
          }
        }
        c.term_max = std::max(c.term_max, std::abs(e));
        sq += e * e;
      }
      c.term_rms = std::sqrt(sq / static_cast<double>(r.scored()));
      c.terms = static_cast<size_t>(std::count(left.begin(), left.end(), 1));
    }
    c.flagged =
        c.drive_beyond > kDriveShare * (s.u_max - s.u_min) || c.term_max >= kTermRmse * train_rmse;
    if (c.term_max == 0 && c.drive_beyond == 0) c.flagged = false;
    if (rates && train_rate > 0) {
      size_t faster = 0;
      c.rate_ratio = MaxRate(r, train_rate, &faster) / train_rate;
      c.rate_beyond_share = static_cast<double>(faster) / static_cast<double>(r.scored());
      if (c.rate_ratio > kRateFaster) c.flagged = true;
    }
    out.push_back(std::move(c));
  }
  return out;
}

std::vector<DepthBin> ErrorByReversalDepth(const io::Record& r, std::span<const double> yhat,
                                           double range) {
  if (yhat.size() < r.end_scored)
    throw InputError("ErrorByReversalDepth: model output shorter than the window");
  if (!(range > 0)) throw InputError("ErrorByReversalDepth: the training drive range must be > 0");
  constexpr int kBins = 5;
  std::vector<DepthBin> bins(kBins);
  std::vector<double> sse(kBins, 0.0);
  for (int b = 0; b < kBins; ++b) {
    bins[static_cast<size_t>(b)].lo = 0.2 * b;
    bins[static_cast<size_t>(b)].hi =
        b + 1 < kBins ? 0.2 * (b + 1) : std::numeric_limits<double>::infinity();
  }
  const double thr = 0.01 * range;
  auto close = [&](size_t first, size_t end) {  // the piece [first, end): its swing and errors
    if (end <= first) return;
    // The swing from the turning point before the piece (its last sample) to the piece's end.
    const size_t from = first > r.first_scored ? first - 1 : first;
    double lo = r.u[from], hi = lo;
    for (size_t k = from; k < end; ++k) {
      lo = std::min(lo, r.u[k]);
      hi = std::max(hi, r.u[k]);
    }
    const size_t b = std::min<size_t>(kBins - 1, static_cast<size_t>((hi - lo) / range / 0.2));
    ++bins[b].pieces;
    for (size_t k = first; k < end; ++k) {
      const double e = r.y[k] - yhat[k];
      sse[b] += e * e;
      ++bins[b].samples;
    }
  };
  // Turning points with a dead band of thr: a piece ends at the extreme the drive then leaves by
  // thr.
  size_t start = r.first_scored, hi = start, lo = start;
  int dir = 0;  // +1 rising, −1 falling, 0 not yet known
  for (size_t k = r.first_scored; k < r.end_scored; ++k) {
    if (r.u[k] > r.u[hi]) hi = k;
    if (r.u[k] < r.u[lo]) lo = k;
    if (dir >= 0 && r.u[k] < r.u[hi] - thr) {  // a maximum at hi passed
      if (dir > 0) {
        close(start, hi + 1);
        start = hi + 1;
      }
      dir = -1;
      lo = k;
    } else if (dir <= 0 && r.u[k] > r.u[lo] + thr) {  // a minimum at lo passed
      if (dir < 0) {
        close(start, lo + 1);
        start = lo + 1;
      }
      dir = 1;
      hi = k;
    }
  }
  close(start, r.end_scored);
  for (size_t b = 0; b < bins.size(); ++b)
    if (bins[b].samples > 0)
      bins[b].rmse = std::sqrt(sse[b] / static_cast<double>(bins[b].samples));
  return bins;
}

std::string DescribeDepthBins(const std::vector<DepthBin>& bins) {
  std::string s;
  for (const DepthBin& b : bins) {
    if (b.samples == 0) continue;
    s += (s.empty() ? "" : "; ") + std::string("swing ") +
         io::FormatNumber(std::round(100 * b.lo)) +
         (std::isfinite(b.hi) ? "–" + io::FormatNumber(std::round(100 * b.hi)) + " %"
                              : " % and more") +
         ": RMSE " + io::FormatNumber(std::round(b.rmse * 1e4) / 1e4) + " (" +
         std::to_string(b.pieces) + " piece(s), " + std::to_string(b.samples) + " samples)";
  }
  return s;
}

std::vector<double> ResidualTrend(const io::Record& r, std::span<const double> yhat,
                                  double window_s) {
  if (yhat.size() < r.end_scored)
    throw InputError("ResidualTrend: model output shorter than the window");
  if (!std::isfinite(window_s) || window_s < 0) {
    throw InputError("ResidualTrend: the averaging window must be finite and ≥ 0, got " +
                     io::FormatNumber(window_s));
  }
  const size_t n = r.end_scored - r.first_scored;
  std::vector<double> prefix(n + 1, 0.0);  // Σ of the residual over the first i scored samples
  for (size_t i = 0; i < n; ++i) {
    const size_t k = r.first_scored + i;
    prefix[i + 1] = prefix[i] + (r.y[k] - yhat[k]);
  }
  // Half the window in samples, at most the window's length (a window of years on a record of
  // seconds: the cast of a huge count would be undefined).
  const size_t half =
      static_cast<size_t>(std::min(std::floor(0.5 * window_s / r.dt), static_cast<double>(n)));
  std::vector<double> out(n);
  for (size_t i = 0; i < n; ++i) {
    const size_t a = i >= half ? i - half : 0, b = std::min(n, i + half + 1);
    out[i] = (prefix[b] - prefix[a]) / static_cast<double>(b - a);
  }
  return out;
}

}  // namespace pz::records
