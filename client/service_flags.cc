#include "client/service_flags.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>

#include "service/security.h"

namespace pz::client {

std::string EnvOr(const char* name, const char* fallback) {
  const char* env = std::getenv(name);
  return env && *env ? env : fallback;
}

int ExitCodeOf(const Status& s) {
  switch (s.code()) {
    case StatusCode::kOk:
      return kExitOk;
    case StatusCode::kInvalidArgument:
      return kExitBadInput;
    case StatusCode::kUnavailable:
      return kExitUnreachable;
    case StatusCode::kNotFound:
      return kExitUnknownJob;
    case StatusCode::kFailedPrecondition:
      return kExitJobNotOk;
    default:
      return kExitFailure;
  }
}

svcclient::ServiceClientOptions ClientOptionsOf(const std::string& master, int timeout_ms,
                                                int retries, const std::string& curve_secret,
                                                const std::string& master_public) {
  svcclient::ServiceClientOptions o;
  o.endpoint = master;
  o.timeout_ms = timeout_ms;
  o.retries = retries;
  if (curve_secret.empty() != master_public.empty())
    throw InputError(curve_secret.empty() ? "--master-public (or PIEZOID_MASTER_PUBLIC) needs "
                                            "--curve-secret (or PIEZOID_CURVE_SECRET)"
                                          : "--curve-secret (or PIEZOID_CURVE_SECRET) needs "
                                            "--master-public (or PIEZOID_MASTER_PUBLIC)");
  if (!curve_secret.empty()) {
    service::CurveKeyPair keys;
    if (Status s = service::LoadCurveSecretFile(curve_secret, &keys); !s.ok())
      throw InputError("--curve-secret: " + s.message());
    if (Status s = service::LoadCurvePublicFile(master_public, &o.master_public); !s.ok())
      throw InputError("--master-public: " + s.message());
    o.curve = keys;
  }
  return o;
}

int ReportStatus(const Status& s) {
  if (s.ok()) return kExitOk;
  std::fprintf(stderr, "piezoid: error: %s\n", s.message().c_str());
  return ExitCodeOf(s);
}

int ReportViolations(const std::string& what, const std::vector<job::FieldViolation>& v,
                     const Status& s) {
  if (v.empty()) return ReportStatus(s);
  std::fprintf(stderr, "piezoid: error: %s is invalid (%zu violation%s):\n", what.c_str(), v.size(),
               v.size() == 1 ? "" : "s");
  for (const auto& x : v) std::fprintf(stderr, "  %s\n", x.description.c_str());
  return kExitBadInput;
}

int WriteTextFile(const std::string& path, const std::string& text) {
  std::ofstream f(path, std::ios::binary);
  f << text;
  f.close();
  return f ? kExitOk : ReportStatus({StatusCode::kInternal, path + ": cannot write"});
}

// ---- the flags of searches on a master ----

CompleteServiceFlags::CompleteServiceFlags()
    : curve_secret(EnvOr("PIEZOID_CURVE_SECRET")), master_public(EnvOr("PIEZOID_MASTER_PUBLIC")) {}

svcclient::ServiceEvaluatorOptions CompleteServiceFlags::Options() const {
  svcclient::ServiceEvaluatorOptions o;
  o.client = ClientOptionsOf(master, timeout_ms, retries, curve_secret, master_public);
  return o;
}

void AddCompleteServiceFlags(CLI::App* cmd, CompleteServiceFlags& f) {
  cmd->add_option("--master", f.master,
                  "run every evaluation of the searches on the workers of this piezoid-master (its "
                  "client endpoint, "
                  "e.g. tcp://127.0.0.1:5556), one evaluation session per search or fit: the same "
                  "result, bit for "
                  "bit, as the local run")
      ->type_name("ENDPOINT");
  cmd->add_option("--timeout-ms", f.timeout_ms, "with --master: per-request timeout [ms]")
      ->check(CLI::Range(10, 3600000))
      ->capture_default_str();
  cmd->add_option("--retries", f.retries, "with --master: attempts per request")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  cmd->add_option(
      "--curve-secret", f.curve_secret,
      "with --master, CURVE: this client's key pair, NAME.key from `piezoid keygen` (default: "
      "$PIEZOID_CURVE_SECRET)");
  cmd->add_option(
      "--master-public", f.master_public,
      "with --master, CURVE: the master's public key file (default: $PIEZOID_MASTER_PUBLIC)");
}

}  // namespace pz::client
