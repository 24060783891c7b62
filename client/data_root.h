// The bundled data (the source tree's data/, or an install's), found when the program runs rather
// than compiled in: no path of the building machine ends up in the binary or its --help.
#pragma once

#include <filesystem>
#include <string_view>

namespace pz::client {

/// $PIEZOID_DATA when set; else the first folder named `data` (or `share/piezoid/data`) that holds
/// `bimorph-fin/`, beside the program or up to four folders above it (build/client/piezoid finds
/// the source tree's data/; /opt/piezoid/bin/piezoid finds /opt/piezoid/data); else `data` under
/// the working folder.
std::filesystem::path DataRoot();

/// DataRoot() / sub.
std::filesystem::path BundledData(std::string_view sub);

/// Throws InputError when `dir` is the bundled `sub` (the flag left at its default) and it does not
/// exist: the message says where the data were looked for, and which flag or variable to set.
void CheckBundledData(const std::filesystem::path& dir, std::string_view sub,
                      std::string_view flag);

/// How a default under the bundled data is found, for --help texts.
inline constexpr const char* kDataRootHelp =
    "the bundled data: $PIEZOID_DATA, else the data/ folder found beside the program or above it";

}  // namespace pz::client
