// piezoid-worker: evaluates individuals for a piezoid-master. See docs/service.md.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <thread>

#include "model/arithmetic.h"
#include "worker/worker.h"
#include "kinds/kinds.h"

namespace {
std::atomic<bool> g_stop{false};
void OnSignal(int) { g_stop = true; }
}  // namespace

int main(int argc, char** argv) {
  pz::worker::WorkerOptions o;
  o.threads = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  std::string log_level = "info", curve_secret, master_public;
  CLI::App app{"piezoid-worker — evaluates GA individuals for a piezoid-master"};
  app.add_option("--master", o.master, "the master's worker endpoint")->capture_default_str();
  app.add_option("--threads", o.threads, "evaluation threads")
      ->check(CLI::Range(1, 4096))
      ->capture_default_str();
  app.add_option("--heartbeat-ms", o.heartbeat_ms, "heartbeat interval [ms] (as the master's)")
      ->check(CLI::Range(10, 60000))
      ->capture_default_str();
  app.add_option("--liveness", o.liveness, "missed heartbeats before reconnecting")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  app.add_option("--backoff-max-ms", o.backoff_max_ms, "reconnect delay cap [ms]")
      ->capture_default_str();
  auto* secret =
      app.add_option("--curve-secret", curve_secret,
                     "CURVE: this worker's key pair (NAME.key from `piezoid keygen`, mode 0600; "
                     "its NAME.pub must be in the master's --allow-workers directory)");
  auto* pub = app.add_option("--master-public", master_public,
                             "CURVE: the master's public key file (its NAME.pub)");
  secret->needs(pub);
  pub->needs(secret);
  app.add_option(
      "--arithmetic", o.arithmetic,
      "announce this arithmetic profile instead of the measured one (`piezoid doctor`); only "
      "to declare two kinds of machine equivalent after checking that they give the same "
      "results");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ worker %P: %v");
  if (!curve_secret.empty()) {
    pz::service::CurveKeyPair keys;
    if (pz::Status s = pz::service::LoadCurveSecretFile(curve_secret, &keys); !s.ok()) {
      spdlog::critical("--curve-secret: {}", s.message());
      return 2;
    }
    if (pz::Status s = pz::service::LoadCurvePublicFile(master_public, &o.master_public); !s.ok()) {
      spdlog::critical("--master-public: {}", s.message());
      return 2;
    }
    o.curve = keys;
  }
  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::signal(SIGPIPE, SIG_IGN);
  // What this process computes as (model/arithmetic.h): the lines of `piezoid doctor`, and the
  // profile announced to the master, which admits workers that compute alike.
  for (const auto& [key, value] : pz::model::ArithmeticReport())
    spdlog::info("arithmetic {}: {}", key, value);
  pz::worker::Worker w(o, pz::kinds::All());
  spdlog::info("{} threads, master {}{}", o.threads, o.master, o.curve ? " (CURVE)" : "");
  const auto stats = w.Run(g_stop);
  if (!stats.refused.empty()) return 3;  // the reason is logged
  spdlog::info("stopped: {} tasks in {} leases, {} reconnects", stats.tasks, stats.leases,
               stats.reconnects);
  if (stats.stuck_threads > 0) {  // an evaluation that would not end: the process ends it
    spdlog::warn("exiting with {} evaluation(s) unfinished", stats.stuck_threads);
    spdlog::shutdown();
    std::_Exit(0);
  }
  return 0;
}
