// Network files (proto/network.proto): a trained HGANN network with its normalisation, parameter
// ranges, chromosome and provenance, saved as binary protobuf (.pb) or protobuf JSON (.json).
// Protobuf types stop here: callers handle SavedNetwork only (ToProto/FromProto are for embedding
// a network in another message). Loading validates everything and returns field-named errors.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "model/network.h"
#include "model/status.h"

namespace pz::proto {
class NetworkFile;
}

namespace pz::io {

inline constexpr uint32_t kNetworkFormatVersion = 1;

/// Where a network came from.
struct NetworkProvenance {
  std::string job_id;
  uint64_t seed = 0;                        ///< the GA's seed
  uint64_t generation = 0;                  ///< generation the network was found in
  double fitness = 0;                       ///< its cost (Σ PI over the training cases), finite
  int64_t created_unix_ms = 0;              ///< when written [ms since 1970-01-01 UTC]; 0 = unknown
  std::string piezoid_version;              ///< e.g. "0.1.0"
  std::vector<std::string> training_cases;  ///< e.g. {"case1", "case5", "case6", "case7"}
  bool operator==(const NetworkProvenance&) const = default;
};

/// The content of a network file.
struct SavedNetwork {
  model::Network network;
  std::vector<uint8_t> chromosome;  ///< the 1415 0/1 bits it was decoded from, or empty
  NetworkProvenance provenance;
  bool operator==(const SavedNetwork&) const = default;
};

enum class NetworkFormat : int { kBinary = 0, kJson = 1 };

/// kJson for a path ending in ".json" (any case), else kBinary.
NetworkFormat NetworkFormatForPath(const std::string& path);

/// network.Validate(); the chromosome, if present, is valid and decodes (with the stored
/// normalisation and ranges) to exactly the stored network; the provenance fitness is finite.
Status ValidateSavedNetwork(const SavedNetwork& saved);

/// Fills `out` (cleared first). Requires nothing; write what is there.
void ToProto(const SavedNetwork& saved, proto::NetworkFile* out);
/// Decodes and validates; on error `out` is untouched and the message names the field, e.g.
/// "w1: has 5 values, expected 2 x H = 6".
Status FromProto(const proto::NetworkFile& file, SavedNetwork* out);

/// Validates, then serialises to binary protobuf or to (indented) protobuf JSON.
Status SerializeNetwork(const SavedNetwork& saved, NetworkFormat format, std::string* out);
/// Parses and validates.
Status ParseNetwork(std::string_view data, NetworkFormat format, SavedNetwork* out);

/// Validates and writes `path` (format from the extension; written to path + ".tmp", then renamed).
Status SaveNetwork(const SavedNetwork& saved, const std::string& path);
/// Reads `path` (format from the extension) and validates. Errors start with the path.
Status LoadNetwork(const std::string& path, SavedNetwork* out);

}  // namespace pz::io
