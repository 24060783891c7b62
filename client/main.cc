// piezoid: identify piezoelectric actuator dynamics and diagnose the sim-to-real gap.
#include <CLI/CLI.hpp>
#include <cstdio>

#include "client/commands.h"
#include "client/service_flags.h"
#include "model/status.h"

int main(int argc, char** argv) {
  CLI::App app{
      "piezoid — identification of piezoelectric actuator dynamics (HGANN) and diagnosis of "
      "the sim-to-real gap"};
  app.require_subcommand(1);
  app.set_version_flag("--version", "piezoid 0.1.0");
  int exit_code = 0;
  pz::client::RegisterSimulate(app, exit_code);
  pz::client::RegisterPi(app, exit_code);
  pz::client::RegisterIdentify(app, exit_code);
  pz::client::RegisterDahl(app, exit_code);
  pz::client::RegisterDiagnose(app, exit_code);
  pz::client::RegisterDiagnoseCheck(app, exit_code);
  pz::client::RegisterBoucwen(app, exit_code);
  pz::client::RegisterCommittee(app, exit_code);
  pz::client::RegisterFit(app, exit_code);
  pz::client::RegisterRecords(app, exit_code);
  pz::client::RegisterSynthStack(app, exit_code);
  pz::client::RegisterCompensate(app, exit_code);
  pz::client::RegisterExport(app, exit_code);
  pz::client::RegisterServiceCommands(app, exit_code);
  app.footer(
      "Exit codes: 0 ok; 1 runtime failure; 2 bad input (command line, job spec with every "
      "violated field, "
      "network file); 3 master unreachable or unavailable; 4 unknown job; 5 job failed or "
      "cancelled (watch), "
      "or not in a state for the request.");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? 0 : 2;  // --help / --version: 0; a bad command line: 2 (bad input)
  } catch (const pz::InputError& e) {
    std::fprintf(stderr, "piezoid: error: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "piezoid: error: %s\n", e.what());
    return 1;
  }
  return exit_code;
}
