// Test helper: runs piezoid commands in-process, as `piezoid` would parse them.
#pragma once

#include <CLI/CLI.hpp>
#include <gtest/gtest.h>

#include <initializer_list>
#include <string>
#include <vector>

namespace pz::testing {

using RegisterCommand = void (*)(CLI::App& app, int& exit_code);

/// Parses args for a fresh app holding `commands`; returns the exit code the command set.
inline int RunCommands(std::initializer_list<RegisterCommand> commands,
                       const std::vector<std::string>& args) {
  CLI::App app{"piezoid"};
  app.require_subcommand(1);
  int exit_code = 0;
  for (RegisterCommand r : commands) r(app, exit_code);
  std::vector<const char*> argv = {"piezoid"};
  for (const auto& a : args) argv.push_back(a.c_str());
  app.parse(static_cast<int>(argv.size()), argv.data());
  return exit_code;
}

/// RunCommands with stdout captured: what the command printed (a non-zero exit fails the test).
inline std::string CapturedCommands(std::initializer_list<RegisterCommand> commands,
                                    const std::vector<std::string>& args) {
  ::testing::internal::CaptureStdout();
  const int code = RunCommands(commands, args);
  const std::string out = ::testing::internal::GetCapturedStdout();
  EXPECT_EQ(code, 0) << out;
  return out;
}

}  // namespace pz::testing
