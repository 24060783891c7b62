// The migration topologies of the GA's islands (opt/ga.h): who sends migrants to whom. A light
// header of its own, so that a job spec (job/job_spec.h) can name one without the GA.
#pragma once

#include <optional>
#include <string_view>

namespace pz::opt {

enum class MigrationTopology : int {
  kRing = 1,            ///< island i receives from i − 1 (island 0 from K − 1)
  kFullyConnected = 2,  ///< every island receives from every other one
  kRandom = 3,          ///< a ring in an order drawn from the seed (fixed for the run)
};

inline constexpr MigrationTopology kTopologies[] = {
    MigrationTopology::kRing, MigrationTopology::kFullyConnected, MigrationTopology::kRandom};

/// "ring", "fully_connected", "random".
inline const char* TopologyName(MigrationTopology t) {
  switch (t) {
    case MigrationTopology::kRing:
      return "ring";
    case MigrationTopology::kFullyConnected:
      return "fully_connected";
    case MigrationTopology::kRandom:
      return "random";
  }
  return "unknown";
}

/// The inverse of TopologyName; nullopt for another text (kTopologyRule says what is allowed).
inline std::optional<MigrationTopology> ParseTopology(std::string_view name) {
  for (MigrationTopology t : kTopologies)
    if (name == TopologyName(t)) return t;
  return std::nullopt;
}

inline bool ValidTopology(MigrationTopology t) {
  for (MigrationTopology k : kTopologies)
    if (t == k) return true;
  return false;
}

inline constexpr const char* kTopologyRule = "must be \"ring\", \"fully_connected\" or \"random\"";

}  // namespace pz::opt
