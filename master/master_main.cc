// piezoid-master: the GA master service (job store + broker). See docs/service.md.
#include <fcntl.h>
#include <spdlog/spdlog.h>
#include <sys/file.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <cerrno>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <thread>

#include "master/broker.h"
#include "master/checkpoint.h"
#include "master/job_store.h"
#include "kinds/kinds.h"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }

/// Takes an exclusive flock on DIR/master.lock (held until the process exits) so that a second
/// master refuses the same state directory; -1 with *error on failure.
int LockStateDir(const std::filesystem::path& dir, std::string* error) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) {
    *error = "--state-dir " + dir.string() + ": cannot create (" + ec.message() + ")";
    return -1;
  }
  const std::filesystem::path lock = dir / "master.lock";
  const int fd = ::open(lock.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd < 0) {
    *error = lock.string() + ": cannot open (" + std::strerror(errno) + ")";
    return -1;
  }
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    char pid[32] = {0};
    (void)!::pread(fd, pid, sizeof pid - 1, 0);
    std::string holder(pid);
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == ' ')) holder.pop_back();
    *error = "--state-dir " + dir.string() + " is in use by another piezoid-master" +
             (holder.empty() ? std::string() : " (pid " + holder + ")") +
             ": stop it first, or give this master another state directory";
    ::close(fd);
    return -1;
  }
  const std::string me = std::to_string(::getpid()) + "\n";
  (void)!::ftruncate(fd, 0);
  (void)!::pwrite(fd, me.data(), me.size(), 0);
  return fd;
}

/// The master's command line.
struct Flags {
  pz::master::BrokerOptions broker;
  pz::master::JobStoreOptions store;
  std::string log_level = "info", endpoints_file;
  std::string curve_secret, allow_workers, allow_clients;
};

void AddFlags(CLI::App& app, Flags& flags) {
  auto& [broker, store, log_level, endpoints_file, curve_secret, allow_workers, allow_clients] =
      flags;
  app.add_option("--workers", broker.worker_endpoint, "endpoint workers connect to")
      ->capture_default_str();
  app.add_option("--clients", broker.client_endpoint, "endpoint clients connect to")
      ->capture_default_str();
  app.add_option("--state-dir", store.state_dir, "checkpoints and job specs")
      ->capture_default_str();
  app.add_option("--heartbeat-ms", broker.heartbeat_ms, "heartbeat interval [ms]")
      ->check(CLI::Range(10, 60000))
      ->capture_default_str();
  app.add_option("--liveness", broker.liveness, "missed heartbeats before a worker is dead")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  app.add_option("--max-message-bytes", broker.max_message_bytes, "larger frames are refused")
      ->check(CLI::Range(int64_t{1024}, int64_t{1} << 32))
      ->capture_default_str();
  app.add_option("--max-spec-bytes", broker.max_spec_bytes,
                 "maximum data size per job: a submitted spec (with its embedded data) larger than "
                 "this serialised is refused [bytes]")
      ->check(CLI::Range(int64_t{1024}, int64_t{1} << 32))
      ->capture_default_str();
  app.add_option("--max-jobs-per-client", broker.max_jobs_per_client,
                 "running jobs one client may have (a client = its CURVE key, or its IP address "
                 "without CURVE)")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  app.add_option(
         "--client-queue", broker.client_queue,
         "messages queued for one client at most; beyond, a client that does not read loses watch "
         "events (it re-syncs when it reads again) instead of the master growing")
      ->check(CLI::Range(16, 1000000))
      ->capture_default_str();
  auto* secret_opt = app.add_option("--curve-secret", curve_secret,
                                    "require CURVE on both endpoints with this key pair (NAME.key "
                                    "from `piezoid keygen`, mode 0600)");
  app.add_option("--allow-workers", allow_workers,
                 "with --curve-secret: directory of the workers' allowed public keys (*.pub)")
      ->needs(secret_opt);
  app.add_option("--allow-clients", allow_clients,
                 "with --curve-secret: directory of the clients' allowed public keys (*.pub)")
      ->needs(secret_opt);
  app.add_flag(
      "--allow-mixed-arithmetic", broker.allow_mixed_arithmetic,
      "accept workers of any arithmetic profile (CPU instruction-set level, build, C library); by "
      "default the first worker's profile is the only one served, so that no result depends on "
      "which machine computed it");
  app.add_option("--max-batch", broker.dispatch.max_batch, "tasks per lease at most")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  app.add_option("--target-batch-s", broker.dispatch.target_batch_s,
                 "work per lease, by the worker's measured speed [s]")
      ->capture_default_str();
  app.add_option(
         "--speculate-after", broker.dispatch.speculate_after,
         "a lease running this many times longer than expected (the generation's median time per "
         "task) once its job has nothing else to hand out gets a copy on an idle worker; the first "
         "answer counts (0 = never)")
      ->check(CLI::Range(0.0, 1000.0))
      ->capture_default_str();
  app.add_option(
         "--quiet-window-s", broker.dispatch.quiet_window_s,
         "a worker's death while it runs a suspect task alone counts against the task only if no "
         "other worker left this long before or after (at least 2 liveness timeouts) [s]")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  app.add_option(
         "--keep-in-memory", store.keep_in_memory,
         "ended jobs kept whole in memory (the most recent); older ones are answered from the "
         "state "
         "directory (status from a summary, fetch from disk); `piezoid prune` deletes ended jobs")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  app.add_option("--max-jobs", store.max_running_jobs, "running jobs at most")
      ->capture_default_str();
  app.add_option("--checkpoint-interval-s", store.checkpoint_interval_s,
                 "the checkpoint is replaced after every generation; make it durable (fsync) at "
                 "most this often (0 = every generation) [s]")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  app.add_option("--endpoints-file", endpoints_file,
                 "write the bound endpoints here (two lines: workers, clients)");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->capture_default_str();
}

/// CURVE on both endpoints with --curve-secret (or a warning for an endpoint beyond loopback
/// without it); the exit code 2 after saying why it cannot, else 0.
int ConfigureCurve(Flags& flags) {
  auto& [broker, store, log_level, endpoints_file, curve_secret, allow_workers, allow_clients] =
      flags;
  if (!curve_secret.empty()) {
    if (allow_workers.empty() || allow_clients.empty()) {
      spdlog::critical(
          "--curve-secret needs --allow-workers DIR and --allow-clients DIR (the allowed public "
          "keys)");
      return 2;
    }
    pz::service::CurveServerConfig curve;
    if (pz::Status s = pz::service::LoadCurveSecretFile(curve_secret, &curve.keys); !s.ok()) {
      spdlog::critical("--curve-secret: {}", s.message());
      return 2;
    }
    curve.allow_workers = allow_workers;
    curve.allow_clients = allow_clients;
    broker.curve = std::move(curve);
  } else {
    for (const std::string* ep : {&broker.worker_endpoint, &broker.client_endpoint})
      if (!pz::service::IsLoopbackEndpoint(*ep))
        spdlog::warn(
            "{} is reachable from other hosts and CURVE is off: anyone who can connect may {}; "
            "start with --curve-secret, --allow-workers and --allow-clients (see docs/service.md, "
            "Security)",
            *ep,
            ep == &broker.worker_endpoint ? "join as a worker and see job specs"
                                          : "submit, fetch and cancel jobs");
  }
  return 0;
}

/// Serves until SIGINT or SIGTERM; the exit code.
int Serve(const Flags& flags) {
  const auto& [broker, store, log_level, endpoints_file, curve_secret, allow_workers,
               allow_clients] = flags;
  std::string lock_error;
  const int lock_fd = LockStateDir(store.state_dir, &lock_error);
  if (lock_fd < 0) {
    spdlog::critical("{}", lock_error);
    return 1;
  }

  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::signal(SIGPIPE, SIG_IGN);

  pz::master::BrokerOptions options = broker;
  if (!options.allow_mixed_arithmetic) {
    if (auto pinned = pz::master::PinnedArithmetic(pz::master::JobDirectory(store.state_dir))) {
      options.pinned_arithmetic = pinned->profile;
      options.pinned_by = pinned->why;
      spdlog::info("serving workers of arithmetic profile '{}' ({})", pinned->profile, pinned->why);
    }
  }
  pz::master::Broker b(options);
  pz::master::JobStore jobs(store, b, pz::kinds::All());
  if (pz::Status s = b.Start(&jobs); !s.ok()) {
    spdlog::critical("{}", s.message());
    return 1;
  }
  spdlog::info(
      "workers on {}, clients on {}, state in {}{}", b.worker_endpoint(), b.client_endpoint(),
      store.state_dir.string(),
      broker.curve ? ", CURVE required (public key " + broker.curve->keys.public_z85 + ")" : "");
  if (!endpoints_file.empty()) {
    const std::string tmp = endpoints_file + ".tmp";
    std::ofstream(tmp) << b.worker_endpoint() << "\n" << b.client_endpoint() << "\n";
    std::rename(tmp.c_str(), endpoints_file.c_str());
  }
  if (pz::Status s = jobs.Resume(); !s.ok()) spdlog::error("resume: {}", s.message());
  while (!g_stop) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  spdlog::info("shutting down");
  jobs.Shutdown();
  ::close(lock_fd);
  return 0;
}
}  // namespace

int main(int argc, char** argv) {
  Flags flags;
  CLI::App app{"piezoid-master — holds the GA jobs and shares the workers among them"};
  AddFlags(app, flags);
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(flags.log_level));
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ master: %v");
  if (const int code = ConfigureCurve(flags); code != 0) return code;
  return Serve(flags);
}
