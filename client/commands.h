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
void RegisterCompensate(CLI::App& app, int& exit_code);
/// `piezoid export` (client/cmd_export.cc): a fit.json or a network file as a C99 header.
void RegisterExport(CLI::App& app, int& exit_code);

/// The service commands (client/cmd_service.cc): submit, status, list (alias jobs), cancel, prune,
/// watch, fetch and dashboard, with keygen (CURVE keys: client/cmd_keygen.cc) and doctor (what
/// this machine computes as: client/cmd_doctor.cc).
void RegisterServiceCommands(CLI::App& app, int& exit_code);
void RegisterKeygen(CLI::App& app, int& exit_code);
void RegisterDoctor(CLI::App& app, int& exit_code);

}  // namespace pz::client
