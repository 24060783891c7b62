// Test helpers for tests that run this build's programs or the system's compilers.
#pragma once

#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <string>

namespace pz::testing {

/// The build folder: the test executables live in <build>/tests.
inline std::filesystem::path BuildDir() {
  return std::filesystem::read_symlink("/proc/self/exe").parent_path().parent_path();
}

/// Runs `cmd` with /bin/sh; its exit code, or -1 when it did not exit normally.
inline int Shell(const std::string& cmd) {
  const int st = std::system(cmd.c_str());
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

}  // namespace pz::testing
