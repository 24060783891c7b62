// Registration of the `piezoid` subcommands. Each command lives in its own cmd_*.cc file.
#pragma once

#include <CLI/CLI.hpp>

#include <string>

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

/// `piezoid export FIT.json`: the fitted model as a self-contained C99 header
/// (controller/export_header.h) written to `out` (stdout when empty), its functions named `name`
/// (default: out's stem). Throws InputError on a bad fit.json. Returns the exit code.
int ExportFit(const std::string& fit_json, const std::string& out, const std::string& name);

}  // namespace pz::client
