#include "records/noise_floor.h"

#include <algorithm>
#include <cmath>
#include <string>

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

NoiseFloor EstimateNoiseFloor(const io::RecordSet& set,
                              const std::vector<std::vector<double>>* residuals) {
  NoiseFloor nf;
  // Rest segments (one per file: records that share a file share its rest).
  {
    double ss = 0;
    size_t n = 0;
    std::vector<std::string> seen;
    for (const io::Record& r : set.records) {
      if (r.rest_samples < 50 || std::find(seen.begin(), seen.end(), r.file.string()) != seen.end())
        continue;
      seen.push_back(r.file.string());
      const double s = DetrendedStd(std::span<const double>(r.y).first(r.rest_samples));
      ss += s * s * static_cast<double>(r.rest_samples);
      n += r.rest_samples;
    }
    if (n > 0)
      nf.estimates.push_back({"rest", std::sqrt(ss / static_cast<double>(n)), n,
                              std::to_string(seen.size()) + " rest segment(s)"});
  }
  // Periods: the drive repeats after P samples over the excited part.
  {
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
      // The last two periods, as the scatter of a bench case.
      const double s = PeriodDifferenceSquares(r.y, r.size() - 2 * period, period);
      ss += s / 4;
      n += period - 1;
      ++found;
    }
    if (n > 0)
      nf.estimates.push_back({"periods", std::sqrt(ss / static_cast<double>(n)), n,
                              std::to_string(found) + " periodic record(s)"});
  }
  // Repeats: records with the same drive.
  {
    double ss = 0;
    size_t n = 0;
    for (size_t i = 0; i < set.records.size(); ++i) {
      for (size_t j = i + 1; j < set.records.size(); ++j) {
        const io::Record &a = set.records[i], &b = set.records[j];
        if (a.file == b.file || a.size() != b.size()) continue;
        bool same = true;
        for (size_t k = 0; k < a.size() && same; ++k)
          same = std::abs(a.u[k] - b.u[k]) <= 1e-9 * (1 + std::abs(a.u[k]));
        if (!same) continue;
        double mean = 0;
        for (size_t k = 0; k < a.size(); ++k) mean += a.y[k] - b.y[k];
        mean /= static_cast<double>(a.size());
        for (size_t k = 0; k < a.size(); ++k) {
          const double d = a.y[k] - b.y[k] - mean;
          ss += d * d / 2;
        }
        n += a.size();
      }
    }
    if (n > 0)
      nf.estimates.push_back(
          {"repeats", std::sqrt(ss / static_cast<double>(n)), n, "records with the same drive"});
  }
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
        "no noise estimate is possible: no rest segment of 50 samples, no periodic drive, no "
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
  nf.sigma = nf.estimates.front().sigma;
  nf.used = nf.estimates.front().method;
  return nf;
}

}  // namespace pz::records
