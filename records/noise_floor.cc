#include "records/noise_floor.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "io/quantum.h"
#include "model/format.h"
#include "model/status.h"

namespace pz::records {
namespace {

double DetrendedStd(std::span<const double> y) {
  const double n = static_cast<double>(y.size());
  double st = 0, sy = 0, stt = 0, sty = 0;
  for (size_t k = 0; k < y.size(); ++k) {
    const double t = static_cast<double>(k);
    st += t;
    sy += y[k];
    stt += t * t;
    sty += t * y[k];
  }
  const double b = (sty - st * sy / n) / (stt - st * st / n), a = (sy - b * st) / n;
  double ss = 0;
  for (size_t k = 0; k < y.size(); ++k) {
    const double e = y[k] - a - b * static_cast<double>(k);
    ss += e * e;
  }
  return std::sqrt(ss / (n - 2));
}

}  // namespace

double QuantisationRms(double quantum) { return quantum / std::sqrt(12.0); }

double PeriodDifferenceSquares(std::span<const double> y, size_t a, size_t period) {
  if (period < 2 || a + 2 * period > y.size())
    throw InputError("period difference: periods of " + std::to_string(period) +
                     " samples from sample " + std::to_string(a) + " need " +
                     std::to_string(a + 2 * period) + " samples, the series has " +
                     std::to_string(y.size()));
  const size_t b = a + period;
  // d_k = y_{b+k} − y_{a+k} = noise difference (variance 2 s²) + whatever is not periodic (creep,
  // drift: slow). First differences of d remove the slow part: var(d_k − d_{k−1}) = 4 s².
  double sum2 = 0, prev = y[b] - y[a];
  for (size_t k = 1; k < period; ++k) {
    const double d = y[b + k] - y[a + k];
    sum2 += (d - prev) * (d - prev);
    prev = d;
  }
  return sum2;
}

CaseNoise EstimateCaseNoise(std::span<const double> y, int cycles, double quantum_deg) {
  if (y.empty()) throw InputError("noise floor: empty series");
  if (cycles < 1) throw InputError(FieldError("cycles", cycles, "must be >= 1"));
  for (size_t k = 0; k < y.size(); ++k)
    if (!std::isfinite(y[k]))
      throw InputError(FieldError("y[" + std::to_string(k) + "]", y[k], "must be finite"));
  CaseNoise n;
  n.quantum_deg = quantum_deg >= 0 ? quantum_deg : io::EstimateQuantum(y);
  n.quantisation_rms_deg = QuantisationRms(n.quantum_deg);
  const size_t p = y.size() / static_cast<size_t>(cycles);
  if (cycles >= 2 && p >= 2) {
    const double sum2 = PeriodDifferenceSquares(y, (cycles - 2) * p, p);
    n.scatter_rms_deg = std::sqrt(sum2 / (p - 1) / 4.0);
    n.compared_samples = static_cast<int>(p);
  }
  n.floor_rms_deg = std::sqrt(n.quantisation_rms_deg * n.quantisation_rms_deg +
                              n.scatter_rms_deg * n.scatter_rms_deg);
  return n;
}

double SaturationAwareFloor(const CaseNoise& noise, std::span<const double> measured,
                            std::span<const double> model, double b1, double b2) {
  if (measured.size() != model.size() || measured.empty())
    throw InputError("saturation-aware floor: measured has " + std::to_string(measured.size()) +
                     " samples, model " + std::to_string(model.size()));
  const double v = noise.floor_rms_deg * noise.floor_rms_deg;
  const double tol = 1e-9 * std::max(1.0, std::max(std::abs(b1), std::abs(b2)));
  double sum = 0;
  for (size_t k = 0; k < measured.size(); ++k) {
    const bool sat = std::abs(model[k] - b1) <= tol || std::abs(model[k] - b2) <= tol;
    const double e = measured[k] - model[k];
    if (sat && noise.quantum_deg > 0 && std::abs(e) <= 1.01 * noise.quantum_deg) {
      sum += e * e;  // the plateau read off its extreme: rounding, not model error
    } else {
      sum += v;
    }
  }
  return std::sqrt(sum / static_cast<double>(measured.size()));
}

namespace {

constexpr size_t kMinRest = 50;  ///< samples of a settled hold for the rest estimate

/// The holds of a series: maximal runs of ≥ kMinRest samples whose drive stays within `tol` of
/// the run's first sample ([from, to)).
std::vector<std::pair<size_t, size_t>> Holds(const io::Record& r, double tol) {
  std::vector<std::pair<size_t, size_t>> out;
  size_t s = 0;
  for (size_t k = 1; k <= r.size(); ++k) {
    if (k < r.size() && std::abs(r.u[k] - r.u[s]) <= tol) continue;
    if (k - s >= kMinRest) out.emplace_back(s, k);
    s = k;
  }
  return out;
}

}  // namespace

SettledHold FindSettledHold(std::span<const double> y, bool trailing_motion) {
  SettledHold h;
  // The response lags the drive by a sample or two (a sensor, a transport): a hold that ends in a
  // move loses its last samples.
  const size_t n = trailing_motion ? (y.size() > 8 ? y.size() - 4 : 0) : y.size();
  h.from = n;
  h.to = n;
  if (n < kMinRest) return h;
  // Blocks of b samples, each with its own line removed: a block's scatter is the noise where the
  // hold has settled, and more where it still rings (a mode excited by the step to the hold) or
  // settles fast. The reference: the median block of the second half.
  const size_t b = std::max<size_t>(16, n / 20), blocks = n / b;
  std::vector<double> s;
  for (size_t i = 0; i < blocks; ++i) {
    const size_t a = n - (blocks - i) * b;  // aligned to the end: the tail is whole
    s.push_back(DetrendedStd(y.subspan(a, b)));
  }
  std::vector<double> tail(s.begin() + static_cast<std::ptrdiff_t>(blocks / 2), s.end());
  std::nth_element(tail.begin(), tail.begin() + static_cast<std::ptrdiff_t>(tail.size() / 2),
                   tail.end());
  const double ref = tail[tail.size() / 2];
  // The settled part: the longest run of blocks at the end within twice the reference (white
  // noise over ≥ 16 samples stays within it), the samples before the first block included when
  // every block is.
  size_t first = blocks;
  while (first > 0 && s[first - 1] <= 2 * ref) --first;
  h.from = first == 0 ? 0 : n - (blocks - first) * b;
  h.unsettled_samples = h.from;
  if (h.to - h.from < kMinRest) return h;
  // The settled blocks' scatter, pooled: each about its own line, so the hold's slow creep (a model
  // with creep follows it) stays out; noise slower than a block (a twentieth of the hold) too.
  double ss = 0;
  for (size_t i = first; i < blocks; ++i) ss += s[i] * s[i];
  h.sigma = std::sqrt(ss / static_cast<double>(blocks - first));
  return h;
}

std::string NoiseFloor::Summary(const std::string& unit) const {
  const std::string in = unit.empty() ? "" : " " + unit;
  std::string s = FormatG(sigma, 3) + in + " (" + used, others;
  for (const NoiseEstimate& e : estimates)
    if (e.method != used)
      others += (others.empty() ? "" : ", ") + e.method + " " + FormatG(e.sigma, 3);
  if (!others.empty()) s += "; " + others + in;
  return s + ")";
}

namespace {

/// Rest: the settled part of every hold of the drive (the leading rest and any inside a record),
/// one series per file (records that share a file share its holds).
void RestEstimate(const io::RecordSet& set, NoiseFloor& nf) {
  double ss = 0;
  size_t n = 0, holds = 0, unsettled = 0;
  std::vector<std::string> seen;
  for (const io::Record& r : set.records) {
    if (std::find(seen.begin(), seen.end(), r.file.string()) != seen.end() || r.size() == 0)
      continue;
    seen.push_back(r.file.string());
    double lo = *std::min_element(r.u.begin(), r.u.end());
    double hi = *std::max_element(r.u.begin(), r.u.end());
    const double tol = 1e-9 * std::max(std::abs(lo), std::abs(hi)) + 1e-12;
    for (const auto& [a, e] : Holds(r, tol)) {
      const SettledHold h =
          FindSettledHold(std::span<const double>(r.y).subspan(a, e - a), e < r.size());
      if (h.to - h.from < kMinRest) continue;
      ss += h.sigma * h.sigma * static_cast<double>(h.to - h.from);
      n += h.to - h.from;
      unsettled += h.unsettled_samples;
      ++holds;
    }
  }
  if (n == 0) return;
  std::string detail = "the settled part of " + std::to_string(holds) + " hold(s) of the drive";
  if (unsettled > 0)
    detail += " (" + std::to_string(unsettled) + " sample(s) still ringing or settling left out)";
  nf.estimates.push_back({"rest", std::sqrt(ss / static_cast<double>(n)), n, detail});
}

/// Periods: the drive repeats with a period of P samples over the excited part; the scatter of
/// every pair of consecutive periods after the first (the jump from rest settles in it).
void PeriodEstimate(const io::RecordSet& set, NoiseFloor& nf) {
  double ss = 0;
  size_t n = 0;
  int found = 0;
  std::vector<std::string> seen;
  for (const io::Record& r : set.records) {
    if (std::find(seen.begin(), seen.end(), r.file.string()) != seen.end()) continue;
    seen.push_back(r.file.string());
    const size_t start = r.rest_samples, len = r.size() - start;
    if (len < 60) continue;
    double lo = *std::min_element(r.u.begin() + static_cast<std::ptrdiff_t>(start), r.u.end());
    double hi = *std::max_element(r.u.begin() + static_cast<std::ptrdiff_t>(start), r.u.end());
    const double tol = 1e-4 * (hi - lo) + 1e-12;
    size_t period = 0;
    for (size_t P = 10; P <= len / 2 && !period; ++P) {  // two periods at least
      bool ok = true;
      for (size_t k = start; k + P < r.size() && ok; k += std::max<size_t>(1, P / 50))
        ok = std::abs(r.u[k + P] - r.u[k]) <= tol;
      if (ok) period = P;
    }
    if (!period) continue;
    // Consecutive pairs from the end back; the first period only when there are no others.
    size_t pairs = 0;
    for (size_t a = r.size() - 2 * period; a >= start; a -= period) {
      if (a < start + period && pairs > 0) break;
      ss += PeriodDifferenceSquares(r.y, a, period) / 4;
      n += period - 1;
      ++pairs;
      if (a < period) break;
    }
    ++found;
  }
  if (n > 0)
    nf.estimates.push_back({"periods", std::sqrt(ss / static_cast<double>(n)), n,
                            std::to_string(found) + " periodic record(s)"});
}

/// The samples of a record's window that a repeat compares: [first_scored, end_scored).
std::span<const double> Window(const std::vector<double>& v, const io::Record& r) {
  return std::span<const double>(v).subspan(r.first_scored, r.scored());
}

/// The lag (samples of b behind a, |lag| ≤ 50 and a tenth of the window) that matches b's drive to
/// a's best over their windows, and the RMS of the drives' difference there.
std::pair<long, double> AlignDrives(const io::Record& a, const io::Record& b) {
  const auto ua = Window(a.u, a), ub = Window(b.u, b);
  const long n = static_cast<long>(std::min(ua.size(), ub.size()));
  const long max_lag = std::min<long>(50, n / 10);
  long best = 0;
  double best_rms = std::numeric_limits<double>::infinity();
  for (long lag = -max_lag; lag <= max_lag; ++lag) {
    double ss = 0;
    long m = 0;
    for (long k = std::max<long>(0, -lag); k < n && k + lag < n; ++k, ++m)
      ss += (ua[static_cast<size_t>(k)] - ub[static_cast<size_t>(k + lag)]) *
            (ua[static_cast<size_t>(k)] - ub[static_cast<size_t>(k + lag)]);
    const double rms = m > 0 ? std::sqrt(ss / static_cast<double>(m)) : best_rms;
    if (rms < best_rms) {
      best_rms = rms;
      best = lag;
    }
  }
  return {best, best_rms};
}

/// Repeats: the records of a manifest's repeat group (recordings of one drive), else records of
/// different files whose drives are the same sample for sample. Each group's records are aligned on
/// the first one's drive, their means removed (a response offset is fitted), and the scatter about
/// the group's mean is σ² = Σ (y_ik − ȳ_k)² / ((m − 1) N).
void RepeatEstimate(const io::RecordSet& set, NoiseFloor& nf) {
  std::vector<std::vector<size_t>> groups;
  std::vector<std::string> names;
  std::vector<bool> grouped(set.records.size(), false);
  for (size_t i = 0; i < set.records.size(); ++i) {
    const std::string& g = set.records[i].repeat;
    if (g.empty() || grouped[i]) continue;
    std::vector<size_t> members;
    for (size_t j = i; j < set.records.size(); ++j)
      if (set.records[j].repeat == g) {
        members.push_back(j);
        grouped[j] = true;
      }
    if (members.size() < 2)
      throw InputError(set.records[i].Label() + ": repeat group '" + g +
                       "' has one record; a repeat group needs two or more");
    groups.push_back(std::move(members));
    names.push_back("'" + g + "'");
  }
  for (size_t i = 0; i < set.records.size(); ++i) {  // no group stated: the same drive
    if (grouped[i] || !set.records[i].repeat.empty()) continue;
    std::vector<size_t> members = {i};
    for (size_t j = i + 1; j < set.records.size(); ++j) {
      const io::Record &a = set.records[i], &b = set.records[j];
      if (grouped[j] || a.file == b.file || a.size() != b.size()) continue;
      bool same = true;
      for (size_t k = 0; k < a.size() && same; ++k)
        same = std::abs(a.u[k] - b.u[k]) <= 1e-9 * (1 + std::abs(a.u[k]));
      if (same) members.push_back(j);
    }
    if (members.size() < 2) continue;
    for (size_t j : members) grouped[j] = true;
    groups.push_back(std::move(members));
    names.push_back("same drive");
  }
  double ss = 0;
  size_t dof = 0;
  for (size_t g = 0; g < groups.size(); ++g) {
    const io::Record& first = set.records[groups[g][0]];
    double lo = *std::min_element(first.u.begin(), first.u.end());
    double hi = *std::max_element(first.u.begin(), first.u.end());
    std::vector<long> lags;
    long from = 0, to = static_cast<long>(first.scored());
    for (size_t j : groups[g]) {
      const io::Record& r = set.records[j];
      const auto [lag, rms] = AlignDrives(first, r);
      if (!(rms <= 0.02 * (hi - lo) + 1e-12))
        throw InputError(r.Label() + ": repeat group " + names[g] + ": its drive differs from " +
                         first.Label() + "'s by " + FormatG(rms, 3) + " RMS at the best lag (" +
                         std::to_string(lag) +
                         " samples), more than 2 % of the drive's range: not a repeat");
      lags.push_back(lag);
      from = std::max(from, -lag);
      to = std::min(to, static_cast<long>(r.scored()) - lag);
    }
    if (to - from < 2) continue;
    const size_t m = groups[g].size(), len = static_cast<size_t>(to - from);
    std::vector<std::vector<double>> y(m);
    for (size_t i = 0; i < m; ++i) {
      const auto w = Window(set.records[groups[g][i]].y, set.records[groups[g][i]]);
      y[i].assign(w.begin() + from + lags[i], w.begin() + to + lags[i]);
      double mean = 0;
      for (double v : y[i]) mean += v / static_cast<double>(len);
      for (double& v : y[i]) v -= mean;
    }
    for (size_t k = 0; k < len; ++k) {
      double mean = 0;
      for (size_t i = 0; i < m; ++i) mean += y[i][k] / static_cast<double>(m);
      for (size_t i = 0; i < m; ++i) ss += (y[i][k] - mean) * (y[i][k] - mean);
    }
    dof += (m - 1) * len;
  }
  if (dof == 0) return;
  std::string groups_named;
  for (const std::string& s : names) groups_named += (groups_named.empty() ? "" : ", ") + s;
  nf.estimates.push_back({"repeats", std::sqrt(ss / static_cast<double>(dof)), dof,
                          std::to_string(groups.size()) + " group(s) of records with the same " +
                              "drive (" + groups_named + ")"});
}

}  // namespace

NoiseFloor EstimateNoiseFloor(const io::RecordSet& set,
                              const std::vector<std::vector<double>>* residuals) {
  NoiseFloor nf;
  RepeatEstimate(set, nf);
  RestEstimate(set, nf);
  PeriodEstimate(set, nf);
  if (residuals) {
    double ss = 0;
    size_t n = 0;
    for (const auto& e : *residuals) {
      for (size_t k = 1; k < e.size(); ++k) ss += (e[k] - e[k - 1]) * (e[k] - e[k - 1]) / 2;
      n += e.size() > 1 ? e.size() - 1 : 0;
    }
    if (n > 0)
      nf.estimates.push_back({"residual", std::sqrt(ss / static_cast<double>(n)), n,
                              "high-frequency part of the base model's residual"});
  }
  if (nf.estimates.empty()) {
    throw InputError(
        "no noise estimate is possible: no hold of the drive of 50 samples, no periodic drive, no "
        "repeated record, no residual");
  }
  // A reading rounded to a quantum q is at least q/√12 RMS from a continuous model on a varying
  // signal, while a rest or two identical periods can cancel the rounding (σ ≪ q): no estimate
  // goes below that floor.
  double q = 0;
  for (const io::Record& r : set.records) q = std::max(q, r.quantum);
  const double q_floor = QuantisationRms(q);
  for (NoiseEstimate& e : nf.estimates) {
    if (e.sigma < q_floor) {
      e.sigma = q_floor;
      e.detail += "; raised to the quantisation floor q/√12 (q = " + FormatG(q, 3) + ")";
    }
  }
  // Repeats first (what a deterministic model is judged against: the plant does not repeat itself
  // closer than that), then the settled rest, the periods, the residual.
  nf.sigma = nf.estimates.front().sigma;
  nf.used = nf.estimates.front().method;
  const auto [lo, hi] = std::minmax_element(
      nf.estimates.begin(), nf.estimates.end(),
      [](const NoiseEstimate& a, const NoiseEstimate& b) { return a.sigma < b.sigma; });
  if (hi->sigma > kFloorDisagreement * lo->sigma) {
    nf.warning = "the floor's estimates disagree by " + FormatG(hi->sigma / lo->sigma, 2) + "× (" +
                 lo->method + " " + FormatG(lo->sigma, 3) + ", " + hi->method + " " +
                 FormatG(hi->sigma, 3) + "); the " + nf.used + " estimate is used";
    if (nf.used == "repeats")
      nf.warning += ": the records repeat no closer than that, whatever a sensor's noise";
  }
  return nf;
}

}  // namespace pz::records
