// PLACEHOLDER — replaced by cmd_simulate.cc and cmd_pi.cc.
#include "client/commands.h"
namespace pz::client {
void RegisterSimulate(CLI::App& app, int&) { app.add_subcommand("simulate", "simulate (coming)"); }
void RegisterPi(CLI::App& app, int&) { app.add_subcommand("pi", "pi (coming)"); }
}  // namespace pz::client
