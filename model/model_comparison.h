// Comparing two models on the same withheld samples, honestly (issue 14). Residuals of a model on
// a time series are correlated from sample to sample, so a χ² difference over N samples overstates
// the evidence by the correlation time; the comparison is made on B contiguous blocks instead:
//
//   d_k = e_a,k² − e_b,k²,  D_j = Σ_{k in block j} d_k,  z = mean(D) / (sd(D) / √B)
//
// z > 0 when model b has the smaller squared errors; P(b is better) ≈ Φ(z) (the blocks are nearly
// independent when each spans many correlation times). And the reliability of stated confidences:
// binned confidence against the observed frequency of being right. Pure.
#pragma once

#include <span>
#include <vector>

namespace pz::model {

/// The paired block z statistic of squared errors a (model a) against b (model b), same length;
/// 0 when there are fewer than 2 samples per block; ±50 when the blocks agree exactly in sign
/// with zero spread. blocks ≥ 2.
double PairedBlockZ(std::span<const double> a_squared, std::span<const double> b_squared,
                    int blocks = 20);

/// Φ(z), the standard normal CDF.
double NormalCdf(double z);

struct ReliabilityBin {
  double lo = 0, hi = 0;  ///< confidence range [lo, hi)
  int count = 0;
  double mean_confidence = 0;  ///< mean stated confidence in the bin
  double frequency_right = 0;  ///< share of the bin that was right
};
/// Bins [0.5, 0.7), [0.7, 0.9), [0.9, 0.99), [0.99, 1]; lower confidences go to a [0, 0.5) bin.
std::vector<ReliabilityBin> ReliabilityTable(std::span<const double> confidence,
                                             std::span<const char> right);

}  // namespace pz::model
