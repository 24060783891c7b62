#include "client/data_root.h"

#include <cstdlib>
#include <string>
#include <system_error>

#include "model/status.h"

namespace pz::client {
namespace {

std::filesystem::path ProgramFolder() {
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::filesystem::path() : exe.parent_path();
}

bool HoldsBenches(const std::filesystem::path& dir) {
  std::error_code ec;
  return std::filesystem::is_directory(dir / "bimorph-fin", ec);
}

}  // namespace

std::filesystem::path DataRoot() {
  if (const char* env = std::getenv("PIEZOID_DATA"); env != nullptr && *env != '\0')
    return std::filesystem::path(env);
  std::filesystem::path dir = ProgramFolder();
  for (int up = 0; up <= 4 && !dir.empty(); ++up) {
    for (const auto& candidate : {dir / "data", dir / "share" / "piezoid" / "data"})
      if (HoldsBenches(candidate)) return candidate.lexically_normal();
    if (dir == dir.root_path()) break;
    dir = dir.parent_path();
  }
  return "data";
}

std::filesystem::path BundledData(std::string_view sub) { return DataRoot() / sub; }

void CheckBundledData(const std::filesystem::path& dir, std::string_view sub,
                      std::string_view flag) {
  std::error_code ec;
  if (dir != BundledData(sub) || std::filesystem::exists(dir, ec)) return;
  throw InputError("the bundled data (" + dir.string() + ") is not here: give " +
                   std::string(flag) +
                   ", or set PIEZOID_DATA to the data/ folder of a piezoid checkout (looked for a "
                   "data/ folder holding bimorph-fin/ beside the program, up to four folders "
                   "above it, and in the working folder)");
}

}  // namespace pz::client
