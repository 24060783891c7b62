#include "model/model_comparison.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace pz::model {

double NormalCdf(double z) { return 0.5 * std::erfc(-z / std::sqrt(2.0)); }

double PairedBlockZ(std::span<const double> a, std::span<const double> b, int blocks) {
  const size_t n = std::min(a.size(), b.size());
  if (blocks < 2 || n < static_cast<size_t>(blocks) * 2) return 0;
  std::vector<double> sums(static_cast<size_t>(blocks), 0.0);
  for (size_t k = 0; k < n; ++k) sums[k * static_cast<size_t>(blocks) / n] += a[k] - b[k];
  const double mean = std::accumulate(sums.begin(), sums.end(), 0.0) / blocks;
  double var = 0;
  for (double s : sums) var += (s - mean) * (s - mean);
  var /= (blocks - 1);
  const double se = std::sqrt(var / blocks);
  if (!(se > 0)) return mean > 0 ? 50 : (mean < 0 ? -50 : 0);
  return std::clamp(mean / se, -50.0, 50.0);
}

std::vector<ReliabilityBin> ReliabilityTable(std::span<const double> confidence,
                                             std::span<const char> right) {
  std::vector<ReliabilityBin> bins = {
      {0, 0.5}, {0.5, 0.7}, {0.7, 0.9}, {0.9, 0.99}, {0.99, 1.0000001}};
  for (size_t i = 0; i < confidence.size() && i < right.size(); ++i) {
    for (ReliabilityBin& b : bins) {
      if (confidence[i] >= b.lo && confidence[i] < b.hi) {
        ++b.count;
        b.mean_confidence += confidence[i];
        b.frequency_right += right[i] ? 1 : 0;
        break;
      }
    }
  }
  for (ReliabilityBin& b : bins) {
    if (b.count > 0) {
      b.mean_confidence /= b.count;
      b.frequency_right /= b.count;
    }
  }
  return bins;
}

}  // namespace pz::model
