// `piezoid keygen --out DIR --name NAME`: a CURVE key pair for the service (master, worker or
// client): DIR/NAME.key (secret, mode 0600) and DIR/NAME.pub, in czmq's zcert text format
// (service/security.h). Registered by RegisterServiceCommands.
#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>

#include "client/commands.h"
#include "client/service_flags.h"
#include "service/security.h"

namespace pz::client {

void RegisterKeygen(CLI::App& app, int& exit_code) {
  auto out = std::make_shared<std::string>();
  auto name = std::make_shared<std::string>();
  auto* c = app.add_subcommand(
      "keygen",
      "write a CURVE key pair for the service: NAME.key (secret, mode 0600) and NAME.pub");
  c->add_option("--out,-o", *out, "directory to write to (created if missing)")->required();
  c->add_option("--name", *name, "file name of the pair, e.g. master, worker-node3, alice")
      ->required();
  c->callback([=, &exit_code] {
    service::CurveKeyPair pair;
    Status s = service::GenerateCurveKeyPair(&pair);
    if (s.ok()) s = service::WriteCurveKeyFiles(*out, *name, pair);
    if (!s.ok()) {
      std::fprintf(stderr, "piezoid: error: %s\n", s.message().c_str());
      exit_code =
          s.code() == StatusCode::kInvalidArgument || s.code() == StatusCode::kFailedPrecondition
              ? kExitBadInput
              : kExitFailure;
      return;
    }
    const std::string base = (std::filesystem::path(*out) / *name).string();
    std::printf("%s.key  secret key (keep it private: mode 0600)\n%s.pub  public key %s\n",
                base.c_str(), base.c_str(), pair.public_z85.c_str());
    exit_code = kExitOk;
  });
}

}  // namespace pz::client
