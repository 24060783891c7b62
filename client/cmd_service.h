// The service subcommands of `piezoid` (submit, status, jobs, cancel, watch, fetch).
#pragma once

#include <CLI/CLI.hpp>

namespace pz::client {
/// Adds the subcommands; their callbacks set exit_code (0 ok, 1 runtime failure, 2 bad input).
void RegisterServiceCommands(CLI::App& app, int& exit_code);
}  // namespace pz::client
