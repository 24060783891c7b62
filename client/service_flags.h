// What the commands that talk to a piezoid-master share: the exit codes and how a failure is told,
// the options of a client of the master, and the flags that run another command's searches on a
// master (CompleteServiceFlags: `piezoid fit`, `boucwen`, `committee`, `diagnose`) over the
// service-client library (svcclient/). The commands themselves: client/commands.h.
#pragma once

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "job/job_spec.h"
#include "model/status.h"
#include "svcclient/complete_service.h"
#include "svcclient/service_client.h"

namespace pz::client {

/// Exit codes of the service subcommands (documented in docs/service.md and `piezoid --help`).
enum ExitCode : int {
  kExitOk = 0,
  kExitFailure = 1,      ///< any other runtime failure (I/O, internal error)
  kExitBadInput = 2,     ///< bad command line, unreadable or invalid job spec / network file
  kExitUnreachable = 3,  ///< the master did not answer (or answered "unavailable, retry later")
  kExitUnknownJob = 4,   ///< no such job at the master
  kExitJobNotOk = 5,     ///< the job failed or was cancelled (watch), or cannot do that now
                         ///< (cancel of a finished job, fetch before the first generation)
};

/// The exit code of a status (kOk → 0, kInvalidArgument → 2, kUnavailable → 3, kNotFound → 4,
/// kFailedPrecondition → 5, anything else → 1).
int ExitCodeOf(const Status& s);

/// Says `s` on stderr ("piezoid: error: …") unless it is ok; returns ExitCodeOf(s).
int ReportStatus(const Status& s);

/// Prints every violation of the job spec `what` (else `s`); returns the exit code for an invalid
/// spec.
int ReportViolations(const std::string& what, const std::vector<job::FieldViolation>& v,
                     const Status& s);

/// Writes `text` to `path`: kExitOk, or the exit code after saying that it cannot.
int WriteTextFile(const std::string& path, const std::string& text);

/// The environment variable `name`, or `fallback` when it is unset or empty.
std::string EnvOr(const char* name, const char* fallback = "");

/// The options of a client of the master at `master` (timeout per attempt, attempts); CURVE when
/// both key files are given (this client's NAME.key from `piezoid keygen`, the master's public
/// key). Throws InputError naming the flag (--curve-secret, --master-public) on a missing partner
/// or a bad key file. Used by every command that talks to a master.
svcclient::ServiceClientOptions ClientOptionsOf(const std::string& master, int timeout_ms,
                                                int retries, const std::string& curve_secret,
                                                const std::string& master_public);

/// The flags of a command whose searches run every evaluation as evaluation sessions on a master
/// (--master, --timeout-ms, --retries, --curve-secret, --master-public).
struct CompleteServiceFlags {
  std::string master;  ///< the master's client endpoint; empty = evaluate locally
  int timeout_ms = 4000;
  int retries = 3;
  std::string curve_secret,
      master_public;  ///< default: $PIEZOID_CURVE_SECRET, $PIEZOID_MASTER_PUBLIC
  CompleteServiceFlags();
  bool enabled() const { return !master.empty(); }
  /// The session options of these flags (CURVE keys loaded); throws InputError naming the flag.
  svcclient::ServiceEvaluatorOptions Options() const;
};

/// Adds the flags to `cmd`.
void AddCompleteServiceFlags(CLI::App* cmd, CompleteServiceFlags& flags);

}  // namespace pz::client
