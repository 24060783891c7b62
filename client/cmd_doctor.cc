// `piezoid doctor`: what this machine computes as (model/arithmetic.h): the build, the instruction-
// set level, the C library, the dense backend and its core, Eigen, and the measured fingerprint of
// the kernels, one `key: value` line each, so that two machines are compared by diffing two
// outputs. A worker logs the same lines at start; a master admits the workers whose profile (the
// build and the fingerprint, `--profile`) equals the one it serves. Registered by
// RegisterServiceCommands.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>

#include "client/commands.h"
#include "client/service_flags.h"
#include "model/arithmetic.h"

namespace pz::client {

void RegisterDoctor(CLI::App& app, int& exit_code) {
  auto profile_only = std::make_shared<bool>(false);
  auto* c = app.add_subcommand(
      "doctor",
      "what this machine computes as: build, ISA level, C library, dense backend, Eigen and the "
      "measured fingerprint of the kernels (diff two machines' outputs)");
  c->add_flag("--profile", *profile_only,
              "print only the profile a worker announces to the master (build + fingerprint)");
  c->callback([=, &exit_code] {
    if (*profile_only) {
      std::printf("%s\n", model::ArithmeticProfile().c_str());
    } else {
      for (const auto& [key, value] : model::ArithmeticReport())
        std::printf("%-20s %s\n", (key + ":").c_str(), value.c_str());
    }
    exit_code = kExitOk;
  });
}

}  // namespace pz::client
