// Helpers of the multi-process service tests: spawn piezoid-master / piezoid-worker on
// 127.0.0.1 with free ports and a temporary state directory; every wait is bounded.
#pragma once

#include <arpa/inet.h>
#include <fcntl.h>
#include <gtest/gtest.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstring>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "svcclient/service_client.h"
#include "master/job_runner.h"
#include "service/wire_codec.h"
#include "kinds/kinds.h"

extern char** environ;

namespace pz::testing {
namespace fs = std::filesystem;

inline fs::path BuildDir() {
  return fs::read_symlink("/proc/self/exe").parent_path().parent_path();
}

inline int FreePort() {
  int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  ::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a);
  socklen_t len = sizeof a;
  ::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len);
  ::close(fd);
  return ntohs(a.sin_port);
}

class Process {
 public:
  /// `env`: "NAME=value" entries added to this process's environment for the child.
  Process(const fs::path& exe, std::vector<std::string> args, const fs::path& log,
          std::vector<std::string> env = {}) {
    std::vector<char*> envp;  // environ, less the names `env` sets (getenv takes the first)
    for (char** e = environ; *e != nullptr; ++e) {
      const std::string_view entry(*e);
      bool replaced = false;
      for (const std::string& x : env)
        replaced |= entry.substr(0, entry.find('=') + 1) == x.substr(0, x.find('=') + 1);
      if (!replaced) envp.push_back(*e);
    }
    for (auto& e : env) envp.push_back(e.data());
    envp.push_back(nullptr);
    std::vector<char*> argv;
    std::string exe_s = exe.string();
    argv.push_back(exe_s.data());
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_APPEND, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    if (posix_spawn(&pid_, exe_s.c_str(), &fa, nullptr, argv.data(), envp.data()) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&fa);
  }
  ~Process() { Kill(SIGKILL); }
  Process(const Process&) = delete;
  pid_t pid() const { return pid_; }
  bool running() {
    if (pid_ <= 0) return false;
    int st;
    if (::waitpid(pid_, &st, WNOHANG) == pid_) {
      pid_ = -1;
      return false;
    }
    return true;
  }
  /// Sends sig and reaps the process (bounded: 10 s, then SIGKILL).
  void Kill(int sig) {
    if (pid_ <= 0) return;
    ::kill(pid_, sig);
    for (int i = 0; i < 1000; ++i) {
      int st;
      if (::waitpid(pid_, &st, WNOHANG) == pid_) {
        pid_ = -1;
        return;
      }
      if (i == 999 || (i > 0 && i % 200 == 0)) ::kill(pid_, SIGKILL);
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

 private:
  pid_t pid_ = -1;
};

/// The whole of a file ("" when it cannot be read).
inline std::string Slurp(const fs::path& p) {
  std::ifstream f(p);
  std::stringstream ss;
  ss << f.rdbuf();
  return ss.str();
}

/// Runs `piezoid` (the client CLI of this build) with `args`; stdout and stderr into *out / *err.
/// Returns its exit code (-1 if it did not exit normally).
inline int RunCli(const std::vector<std::string>& args, std::string* out = nullptr,
                  std::string* err = nullptr) {
  static int counter = 0;
  const fs::path base = fs::temp_directory_path() /
                        ("pz-cli-" + std::to_string(::getpid()) + "-" + std::to_string(counter++));
  std::string cmd = "'" + (BuildDir() / "client" / "piezoid").string() + "'";
  for (const auto& a : args) cmd += " '" + a + "'";
  cmd += " >'" + base.string() + ".out' 2>'" + base.string() + ".err' </dev/null";
  const int st = std::system(cmd.c_str());
  if (out) *out = Slurp(base.string() + ".out");
  if (err) *err = Slurp(base.string() + ".err");
  std::error_code ec;
  fs::remove(base.string() + ".out", ec);
  fs::remove(base.string() + ".err", ec);
  return WIFEXITED(st) ? WEXITSTATUS(st) : -1;
}

inline svcclient::ServiceClientOptions ClientOptions(const std::string& endpoint, int timeout_ms,
                                                     int retries) {
  svcclient::ServiceClientOptions o;
  o.endpoint = endpoint;
  o.timeout_ms = timeout_ms;
  o.retries = retries;
  return o;
}

/// A master and its workers on free loopback ports, with fast heartbeats.
class Cluster {
 public:
  explicit Cluster(const std::string& name, std::vector<std::string> master_extra = {})
      : master_extra_(std::move(master_extra)) {
    dir_ = fs::temp_directory_path() /
           ("pz-" + name + "-" + std::to_string(::getpid()) + "-" + std::to_string(FreePort()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    StartMaster();
  }
  ~Cluster() {
    workers_.clear();
    master_.reset();
    std::error_code ec;
    if (!::testing::Test::HasFailure()) fs::remove_all(dir_, ec);
  }
  /// Starts the master. The first start lets it pick free ports (port 0 = "*", never a guessed
  /// number: tests run in parallel) and reads them from its endpoints file; a restart binds the
  /// same ones again, so that the workers reconnect to it. Returns false (with a test failure)
  /// when the master did not publish its endpoints within 20 s.
  bool StartMaster() {
    const bool first = worker_ep_.empty();
    const fs::path endpoints = dir_ / "endpoints";
    std::error_code ec;
    fs::remove(endpoints, ec);
    std::vector<std::string> args = {"--workers",        first ? "tcp://127.0.0.1:*" : worker_ep_,
                                     "--clients",        first ? "tcp://127.0.0.1:*" : client_ep_,
                                     "--endpoints-file", endpoints.string(),
                                     "--state-dir",      (dir_ / "state").string(),
                                     "--heartbeat-ms",   "100",
                                     "--liveness",       "5",
                                     "--log-level",      "warn"};
    args.insert(args.end(), master_extra_.begin(), master_extra_.end());
    master_ = std::make_unique<Process>(BuildDir() / "master" / "piezoid-master", args,
                                        dir_ / "master.log");
    if (!first) return true;
    for (int i = 0; i < 2000; ++i) {
      std::ifstream f(endpoints);
      std::string w, c;
      if (f && std::getline(f, w) && std::getline(f, c) && !c.empty()) {
        worker_ep_ = w;
        client_ep_ = c;
        return true;
      }
      if (!master_->running()) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    ADD_FAILURE() << "the master did not write " << endpoints << " (see " << dir_ / "master.log"
                  << ")";
    return false;
  }
  void KillMaster(int sig = SIGKILL) { master_->Kill(sig); }
  pid_t master_pid() const { return master_->pid(); }
  Process& AddWorker(int threads, const std::vector<std::string>& extra = {},
                     const std::vector<std::string>& env = {}) {
    std::vector<std::string> args{
        "--master",         worker_ep_, "--threads",   std::to_string(threads),
        "--heartbeat-ms",   "100",      "--liveness",  "5",
        "--backoff-max-ms", "500",      "--log-level", "warn"};
    args.insert(args.end(), extra.begin(), extra.end());
    workers_.push_back(std::make_unique<Process>(BuildDir() / "worker" / "piezoid-worker", args,
                                                 dir_ / "workers.log", env));
    return *workers_.back();
  }
  std::vector<std::unique_ptr<Process>>& workers() { return workers_; }
  svcclient::ServiceClient Client(int timeout_ms = 2000, int retries = 3) {
    return svcclient::ServiceClient(ClientOptions(client_ep_, timeout_ms, retries));
  }
  const std::string& worker_endpoint() const { return worker_ep_; }
  const std::string& client_endpoint() const { return client_ep_; }
  const fs::path& dir() const { return dir_; }

 private:
  fs::path dir_;
  std::string worker_ep_, client_ep_;
  std::vector<std::string> master_extra_;
  std::unique_ptr<Process> master_;
  std::vector<std::unique_ptr<Process>> workers_;
};

inline job::JobSpec SyntheticSpec(uint64_t seed, int population, int generations,
                                  double sleep_ms = 0, int bits = 64) {
  job::JobSpec s;
  s.name = "test";
  s.seed = seed;
  job::SyntheticProblem p;
  p.cost = job::SyntheticProblem::Cost::kFunction;
  p.genome_bits = bits;
  p.sleep_ms = sleep_ms;
  s.problem = p;
  job::GaSettings ga;
  ga.population = population;
  ga.generations = generations;
  ga.stall_generations = 0;
  ga.mutation_probability = 0.02;
  s.ga = ga;
  return s;
}

/// The in-process reference run of a spec.
inline service::JobCheckpoint Reference(const job::JobSpec& spec) {
  service::JobCheckpoint c;
  Status s = master::RunJobInProcess("ref", spec, kinds::All(), &c);
  PZ_CHECK_MSG(s.ok(), s.message());
  return c;
}

/// Expects the service's best and log to equal the reference bit for bit.
inline void ExpectSameRun(const service::JobCheckpoint& ref,
                          const std::vector<service::ScoredGenome>& best,
                          const std::vector<service::GenerationRecord>& log) {
  ASSERT_EQ(log.size(), ref.log.size());
  for (size_t i = 0; i < log.size(); ++i) EXPECT_EQ(log[i], ref.log[i]) << "generation " << i;
  ASSERT_FALSE(best.empty());
  ASSERT_LE(best.size(), ref.best.size());
  for (size_t i = 0; i < best.size(); ++i) {
    EXPECT_EQ(best[i].genome, ref.best[i].genome) << "best #" << i;
    EXPECT_EQ(std::memcmp(&best[i].fitness.cost, &ref.best[i].fitness.cost, sizeof(double)), 0)
        << "best #" << i << ": " << best[i].fitness.cost << " vs " << ref.best[i].fitness.cost;
  }
}

}  // namespace pz::testing
