// piezoid-master: the GA master service (job store + broker). See docs/service.md.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <csignal>
#include <fstream>
#include <thread>

#include "master/broker.h"
#include "diagnose/job_kind.h"
#include "master/job_store.h"

namespace {
volatile std::sig_atomic_t g_stop = 0;
void OnSignal(int) { g_stop = 1; }
}  // namespace

int main(int argc, char** argv) {
  pz::master::BrokerOptions broker;
  pz::master::JobStoreOptions store;
  std::string log_level = "info", endpoints_file;
  CLI::App app{"piezoid-master — holds the GA jobs and shares the workers among them"};
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
  app.add_option("--max-batch", broker.dispatch.max_batch, "tasks per lease at most")
      ->check(CLI::Range(1, 1000000))
      ->capture_default_str();
  app.add_option("--target-batch-s", broker.dispatch.target_batch_s,
                 "work per lease, by the worker's measured speed [s]")
      ->capture_default_str();
  app.add_option("--max-jobs", store.max_running_jobs, "running jobs at most")
      ->capture_default_str();
  app.add_option("--checkpoint-interval-s", store.checkpoint_interval_s,
                 "the checkpoint is replaced after every generation; make it durable (fsync) at most this often (0 = every generation) [s]")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  app.add_option("--endpoints-file", endpoints_file,
                 "write the bound endpoints here (two lines: workers, clients)");
  app.add_option("--log-level", log_level, "trace, debug, info, warn, error")
      ->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  spdlog::set_level(spdlog::level::from_str(log_level));
  spdlog::set_pattern("%Y-%m-%dT%H:%M:%S.%e %^%l%$ master: %v");

  std::signal(SIGINT, OnSignal);
  std::signal(SIGTERM, OnSignal);
  std::signal(SIGPIPE, SIG_IGN);

  pz::master::Broker b(broker);
  pz::diagnose::RegisterDiagnoseJobKind(pz::master::JobKindRegistry::Default());
  pz::master::JobStore jobs(store, b, pz::master::JobKindRegistry::Default());
  if (pz::Status s = b.Start(&jobs); !s.ok()) {
    spdlog::critical("{}", s.message());
    return 1;
  }
  spdlog::info("workers on {}, clients on {}, state in {}", b.worker_endpoint(),
               b.client_endpoint(), store.state_dir.string());
  if (!endpoints_file.empty()) {
    const std::string tmp = endpoints_file + ".tmp";
    std::ofstream(tmp) << b.worker_endpoint() << "\n" << b.client_endpoint() << "\n";
    std::rename(tmp.c_str(), endpoints_file.c_str());
  }
  if (pz::Status s = jobs.Resume(); !s.ok()) spdlog::error("resume: {}", s.message());
  while (!g_stop) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  spdlog::info("shutting down");
  jobs.Shutdown();
  return 0;
}
