// Registration of the `piezoid` subcommands. Each command lives in its own cmd_*.cc file.
#pragma once

#include <CLI/CLI.hpp>

namespace pz::client {

// Each Register* adds one subcommand to app; its callback sets the process exit code through
// the reference it is given (0 ok, 1 runtime failure, 2 bad input).
void RegisterSimulate(CLI::App& app, int& exit_code);
void RegisterPi(CLI::App& app, int& exit_code);
void RegisterIdentify(CLI::App& app, int& exit_code);
void RegisterDahl(CLI::App& app, int& exit_code);
void RegisterDiagnose(CLI::App& app, int& exit_code);
void RegisterDiagnoseCheck(CLI::App& app, int& exit_code);
void RegisterBoucwen(CLI::App& app, int& exit_code);
void RegisterCommittee(CLI::App& app, int& exit_code);
void RegisterFit(CLI::App& app, int& exit_code);
void RegisterRecords(CLI::App& app, int& exit_code);
void RegisterSynthStack(CLI::App& app, int& exit_code);

}  // namespace pz::client
