// What the operating-point law's committee says (hgann/operating_law.h CommitteeOf): which withheld
// cases the training cases leave open and which operating point to measure next. Plain data, so
// that the hgann job kind can return it with a fetch (proto/wire.proto FetchReply.committee) and
// the client's report is identify's.
#pragma once

#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include "model/network.h"

namespace pz::job {

struct LawCommittee {
  int members = 0;
  /// The candidates of `next`: (V, f) and the case index (−1 for a point of the user's list).
  struct Candidate {
    double amplitude_v = 0, frequency_hz = 0;
    int case_index = -1;
    bool operator==(const Candidate&) const = default;
  };
  std::vector<Candidate> candidates;
  /// Per case: the kept network's Σ (Δy)² from the law [deg²] (0 without a kept network).
  std::vector<double> kept_disagreement;
  std::vector<double> floor;         ///< per case: σ² N [deg²]
  std::vector<double> disagreement;  ///< per case: the largest member's Σ (Δy)² [deg²]
  std::vector<bool> open;            ///< per case: withheld and disagreement ≥ 2 floors
  /// Per case: each parameter's lowest and highest value over the law and the members.
  std::vector<std::array<double, model::kNetworkOutputs>> lo, hi;
  /// Candidates (indices into `candidates`) best first, with what would remain open [floors].
  std::vector<std::pair<int, double>> next;
  int64_t simulations = 0;
  bool operator==(const LawCommittee&) const = default;
};

}  // namespace pz::job
