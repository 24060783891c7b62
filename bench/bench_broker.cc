// Service benchmarks (figures in docs/performance.md). A Broker bound to tcp://127.0.0.1 and
// pz::worker::Worker engines on their own threads (each with its own sockets, exactly as the
// piezoid-worker process) exchange real messages over loopback.
//  * BM_NullCostThroughput: individuals dispatched and collected per second when the fitness
//    returns at once (synthetic COST_NULL), batches of `n` genomes of 64 bits, 2 workers.
//  * BM_FixedCostEfficiency/<population>/<islands>: the GA over a 10 ms-per-evaluation fitness
//    (a sleep: no CPU), 64 worker threads in 4 workers; one generation of K islands is one dispatch
//    of K × (population − elite) evaluations; efficiency = evaluations/s ÷ (64 / 10 ms).
// Measured 2026-11-22 on the 2-core shared build VM (Release, load average 3–5; docs/performance.md):
//   null cost, 2000-genome generations: 255 k individuals/s; 20000-genome generations: 580 k/s
//   10 ms fixed cost, 64 threads / 4 workers, population 4000 (2000 new): 5960 evals/s = 93.1 %
//   same, population 400 (200 new): 4330 evals/s = 67.6 % (ceiling 78 %: 200/64 → 4 rounds)
// Resident memory is measured by bench/memory.sh (real processes): idle master 10.2 MB, idle
// worker 9.8 MB, master holding 10 running paper-scale hgann jobs 41.7 MB.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <unistd.h>
#include <sstream>
#include <fstream>
#include <filesystem>
#include <thread>

#include "master/broker.h"
#include "master/job_runner.h"
#include "service/wire_codec.h"
#include "worker/worker.h"
#include "kinds/kinds.h"

namespace pz {
namespace {

struct NullHandler final : master::ClientHandler {
  service::ClientReplyMsg Handle(const service::ClientRequestMsg&) override { return {}; }
};

struct Rig {
  Rig(int workers, int threads) {
    master::BrokerOptions o;
    o.worker_endpoint = "tcp://127.0.0.1:*";
    o.client_endpoint = "tcp://127.0.0.1:*";
    broker = std::make_unique<master::Broker>(o);
    PZ_CHECK(broker->Start(&handler).ok());
    for (int i = 0; i < workers; ++i) {
      worker::WorkerOptions w;
      w.master = broker->worker_endpoint();
      w.threads = threads;
      engines.push_back(std::make_unique<worker::Worker>(w, kinds::All()));
      auto* e = engines.back().get();
      threads_.emplace_back([this, e] { e->Run(stop); });
    }
    for (int i = 0; i < 500 && broker->stats().workers < workers; ++i)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ~Rig() {
    stop = true;
    for (auto& t : threads_) t.join();
    broker->Stop();
  }
  NullHandler handler;
  std::unique_ptr<master::Broker> broker;
  std::atomic<bool> stop{false};
  std::vector<std::unique_ptr<worker::Worker>> engines;
  std::vector<std::thread> threads_;
};

job::JobSpec Synthetic(bool null_cost, double sleep_ms, int population, int islands = 1) {
  job::JobSpec s;
  s.seed = 1;
  job::SyntheticProblem p;
  p.cost = null_cost ? job::SyntheticProblem::Cost::kNull
                     : job::SyntheticProblem::Cost::kFunction;
  p.genome_bits = 64;
  p.sleep_ms = sleep_ms;
  s.problem = p;
  job::GaSettings g;
  g.population = population;
  g.generations = 1000000;
  g.stall_generations = 0;
  g.islands = islands;
  s.ga = g;
  return s;
}

/// CPU seconds (user + system) the broker thread ("pz-broker") has used so far; < 0 if not found.
double BrokerThreadCpuSeconds() {
  namespace fs = std::filesystem;
  std::error_code ec;
  for (const auto& t : fs::directory_iterator("/proc/self/task", ec)) {
    std::ifstream comm(t.path() / "comm");
    std::string name;
    if (!std::getline(comm, name) || name != "pz-broker") continue;
    std::ifstream stat(t.path() / "stat");
    std::string line;
    std::getline(stat, line);
    std::istringstream rest(line.substr(line.rfind(')') + 2));  // after "pid (comm) "
    std::string field;
    double utime = 0, stime = 0;
    for (int i = 3; i <= 15 && rest >> field; ++i) {
      if (i == 14) utime = std::stod(field);
      if (i == 15) stime = std::stod(field);
    }
    return (utime + stime) / static_cast<double>(::sysconf(_SC_CLK_TCK));
  }
  return -1;
}

void BM_NullCostThroughput(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int bits = state.range(1) > 0 ? static_cast<int>(state.range(1)) : 64;
  Rig rig(2, 1);
  job::JobSpec spec = Synthetic(true, 0, 2);
  std::get<job::SyntheticProblem>(spec.problem).genome_bits = bits;
  rig.broker->RegisterJob("bench", service::EncodeJobSpec(spec), spec.limits);
  std::vector<opt::Genome> genomes(n, opt::Genome{std::vector<uint8_t>(bits, 1), {}});
  std::vector<int> indices(n);
  for (int i = 0; i < n; ++i) indices[i] = i;
  std::vector<opt::FitnessResult> out(n);
  master::BrokerEvaluator eval(*rig.broker, "bench");
  uint64_t gen = 0;
  int64_t done = 0;
  const double cpu0 = BrokerThreadCpuSeconds();
  for (auto _ : state) {
    eval.Evaluate({gen++, genomes, indices}, out);
    done += n;
  }
  const double cpu = BrokerThreadCpuSeconds() - cpu0;
  state.counters["individuals/s"] = benchmark::Counter(static_cast<double>(done),
                                                       benchmark::Counter::kIsRate);
  // The master's own cost: its broker thread's CPU per individual dispatched and collected, and the
  // rate one master core could sustain at that cost.
  if (cpu0 >= 0 && cpu > 0) {
    state.counters["broker_us/individual"] = 1e6 * cpu / static_cast<double>(done);
    state.counters["one_core_individuals/s"] = static_cast<double>(done) / cpu;
  }
}
// Args: genomes per generation, bits per genome (64; the paper's 1415).
BENCHMARK(BM_NullCostThroughput)
    ->Args({2000, 64})
    ->Args({20000, 64})
    ->Args({2000, 1415})
    ->Args({20000, 1415})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_FixedCostEfficiency(benchmark::State& state) {
  const int population = static_cast<int>(state.range(0)), islands = static_cast<int>(state.range(1));
  Rig rig(4, 16);
  const job::JobSpec spec = Synthetic(false, 10, population, islands);
  rig.broker->RegisterJob("bench", service::EncodeJobSpec(spec), spec.limits);
  master::JobRunner runner("bench", spec);
  PZ_CHECK(runner.Init(kinds::All()).ok());
  master::BrokerEvaluator eval(*rig.broker, "bench");
  runner.Step(eval);  // generation 0 (all individuals) outside the timing
  int64_t evals = 0, generations = 0;
  for (auto _ : state) {
    evals += runner.Step(eval).evaluations;
    ++generations;
  }
  state.counters["evals/generation"] = static_cast<double>(evals) / std::max<int64_t>(1, generations);
  state.counters["evals/s"] = benchmark::Counter(static_cast<double>(evals),
                                                 benchmark::Counter::kIsRate);
  state.counters["efficiency"] = benchmark::Counter(
      static_cast<double>(evals) / 6400.0, benchmark::Counter::kIsRate);
}
BENCHMARK(BM_FixedCostEfficiency)
    ->Args({4000, 1})
    ->Args({400, 1})
    ->Args({400, 4})
    ->Args({400, 16})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(3);

}  // namespace
}  // namespace pz

BENCHMARK_MAIN();
