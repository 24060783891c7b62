// Service benchmarks (figures in docs/performance.md). A Broker bound to tcp://127.0.0.1 and
// pz::worker::Worker engines on their own threads (each with its own sockets, exactly as the
// piezoid-worker process) exchange real messages over loopback.
//  * BM_NullCostThroughput/<genomes>/<bits>: individuals dispatched and collected per second when
//    the fitness returns at once (synthetic COST_NULL), 2 workers; with the CPU the broker thread
//    and the submitting (job) thread spend per individual.
//  * BM_FixedCostEfficiency/<population>/<islands>: the GA over a 10 ms-per-evaluation fitness
//    (a sleep: no CPU), 64 worker threads in 4 workers; one generation of K islands is one dispatch
//    of K × (population − elite) evaluations; efficiency = evals/s ÷ (64 / 10 ms).
//  * BM_SleepCost50us/<workers>/<threads>: the same with 50 µs per evaluation, population 4000.
//  * BM_SleepCeiling/<threads>: those 50 µs sleeps on threads of one process with no master (the
//    machine's ceiling for BM_SleepCost50us; one thread: the kernel's real length of a 50 µs
//    sleep).
// Measured 2026-11-22 on the 2-core shared build VM (Release, load average 3–5;
// docs/performance.md):
//   null cost, 2000-genome generations: 255 k individuals/s; 20000-genome generations: 580 k/s
//   10 ms fixed cost, 64 threads / 4 workers, population 4000 (2000 new): 5960 evals/s = 93.1 %
//   same, population 400 (200 new): 4330 evals/s = 67.6 % (ceiling 78 %: 200/64 → 4 rounds)
// Resident memory is measured by bench/memory.sh (real processes): idle master 10.2 MB, idle
// worker 9.8 MB, master holding 10 running paper-scale hgann jobs 41.7 MB.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <atomic>
#include <barrier>
#include <sys/prctl.h>
#include <time.h>
#include <unistd.h>
#include <sstream>
#include <fstream>
#include <filesystem>
#include <thread>

#include "master/broker.h"
#include "master/job_runner.h"
#include "opt/inline_evaluator.h"
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
  p.cost = null_cost ? job::SyntheticProblem::Cost::kNull : job::SyntheticProblem::Cost::kFunction;
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

/// CPU seconds the calling thread has used so far.
double ThisThreadCpuSeconds() {
  timespec t{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
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
  const double cpu0 = BrokerThreadCpuSeconds(), job0 = ThisThreadCpuSeconds();
  for (auto _ : state) {
    eval.Evaluate({gen++, genomes, indices}, out);
    done += n;
  }
  const double cpu = BrokerThreadCpuSeconds() - cpu0, job_cpu = ThisThreadCpuSeconds() - job0;
  state.counters["individuals/s"] =
      benchmark::Counter(static_cast<double>(done), benchmark::Counter::kIsRate);
  // The master's own cost: its broker thread's CPU per individual dispatched and collected, and the
  // rate one master core could sustain at that cost.
  if (cpu0 >= 0 && cpu > 0) {
    state.counters["broker_us/individual"] = 1e6 * cpu / static_cast<double>(done);
    state.counters["one_core_individuals/s"] = static_cast<double>(done) / cpu;
  }
  // The submitting (job) thread's CPU: packing the genomes into wire bytes, and taking the results.
  state.counters["job_thread_us/individual"] =
      1e6 * job_cpu / static_cast<double>(std::max<int64_t>(1, done));
}
// Args: genomes per generation, bits per genome (64; the paper's 1415).
BENCHMARK(BM_NullCostThroughput)
    ->Args({2000, 64})
    ->Args({20000, 64})
    ->Args({2000, 1415})
    ->Args({20000, 1415})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

/// Forwards to the broker's evaluator and times the waits: the rest of a generation is the GA's own
/// work on the job thread (selection, crossover, mutation, the record).
struct TimedEvaluator final : opt::BatchEvaluator {
  explicit TimedEvaluator(opt::BatchEvaluator& inner) : inner(inner) {}
  void Evaluate(const opt::EvalBatch& batch, std::span<opt::FitnessResult> out) override {
    const auto t0 = std::chrono::steady_clock::now();
    inner.Evaluate(batch, out);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  }
  int concurrency() const override { return inner.concurrency(); }
  opt::BatchEvaluator& inner;
  double seconds = 0;
};

/// The GA over a fitness that sleeps `sleep_ms` per evaluation (no CPU), on `workers` workers of
/// `threads` threads. Efficiency = evaluations/s ÷ (threads / sleep_ms): the share of the ideal
/// rate. The evaluation's own time is measured too (the worker's summed wall time per task, as
/// reported with the results), since a sleep lasts longer than asked on a loaded machine:
/// utilisation = Σ evaluation time ÷ (threads × wall), the share of thread time spent evaluating.
void FixedCost(benchmark::State& state, int workers, int threads, double sleep_ms, int population,
               int islands) {
  // The sleeps are the fitness's cost: timer slack (50 µs by default, inherited by the threads made
  // from here) would add up to 50 µs to each 50 µs evaluation.
  ::prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);
  Rig rig(workers, threads);
  const job::JobSpec spec = Synthetic(false, sleep_ms, population, islands);
  rig.broker->RegisterJob("bench", service::EncodeJobSpec(spec), spec.limits);
  master::JobRunner runner("bench", spec);
  PZ_CHECK(runner.Init(kinds::All()).ok());
  master::BrokerEvaluator broker_eval(*rig.broker, "bench");
  TimedEvaluator eval(broker_eval);
  runner.Step(eval);  // generation 0 (all individuals) outside the timing
  eval.seconds = 0;
  int64_t evals = 0, generations = 0;
  const master::BrokerStats s0 = rig.broker->stats();
  const double cpu0 = BrokerThreadCpuSeconds();
  const auto t0 = std::chrono::steady_clock::now();
  for (auto _ : state) {
    evals += runner.Step(eval).evaluations;
    ++generations;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const double cpu = BrokerThreadCpuSeconds() - cpu0;
  const master::BrokerStats s1 = rig.broker->stats();
  const double total_threads = static_cast<double>(workers) * threads;
  const double e = static_cast<double>(std::max<int64_t>(1, evals));
  state.counters["threads"] = total_threads;
  state.counters["evals/generation"] =
      static_cast<double>(evals) / std::max<int64_t>(1, generations);
  state.counters["evals/s"] =
      benchmark::Counter(static_cast<double>(evals), benchmark::Counter::kIsRate);
  state.counters["efficiency"] =
      static_cast<double>(evals) * sleep_ms / 1000.0 / (total_threads * wall);
  state.counters["utilisation"] = (s1.eval_seconds - s0.eval_seconds) / (total_threads * wall);
  state.counters["eval_us"] = 1e6 * (s1.eval_seconds - s0.eval_seconds) / e;
  state.counters["leases/generation"] =
      static_cast<double>(s1.leases_sent - s0.leases_sent) / std::max<int64_t>(1, generations);
  state.counters["generation_ms"] = 1e3 * wall / std::max<int64_t>(1, generations);
  state.counters["ga_ms"] = 1e3 * (wall - eval.seconds) / std::max<int64_t>(1, generations);
  if (cpu0 >= 0) state.counters["broker_us/eval"] = 1e6 * cpu / e;
}

/// The job thread's own work per generation (the serial part of a generation: selection, crossover,
/// mutation, the record and the checkpoint's state), stepped with the synthetic fitness inline
/// and no cost. Arg: population (64-bit genomes, one island).
void BM_JobStepInline(benchmark::State& state) {
  const job::JobSpec spec = Synthetic(true, 0, static_cast<int>(state.range(0)));
  std::unique_ptr<opt::FitnessFunction> fitness;
  PZ_CHECK(kinds::All().MakeFitness(spec, &fitness).ok());
  opt::InlineEvaluator eval(*fitness);
  master::JobRunner runner("bench", spec);
  PZ_CHECK(runner.Init(kinds::All()).ok());
  runner.Step(eval);
  for (auto _ : state) runner.Step(eval);
}
BENCHMARK(BM_JobStepInline)->Arg(400)->Arg(4000)->Unit(benchmark::kMillisecond);

// 10 ms per evaluation, 64 threads in 4 workers. Args: population, islands.
void BM_FixedCostEfficiency(benchmark::State& state) {
  FixedCost(state, 4, 16, 10, static_cast<int>(state.range(0)), static_cast<int>(state.range(1)));
}
BENCHMARK(BM_FixedCostEfficiency)
    ->Args({4000, 1})
    ->Args({400, 1})
    ->Args({400, 4})
    ->Args({400, 16})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(3);

// 50 µs per evaluation (issue 24), population 4000 (2000 new individuals a generation).
// Args: workers, threads per worker: 16 = 1 × 16, 64 = 4 × 16, 256 = 4 × 64.
void BM_SleepCost50us(benchmark::State& state) {
  FixedCost(state, static_cast<int>(state.range(0)), static_cast<int>(state.range(1)), 0.05, 4000,
            1);
}
BENCHMARK(BM_SleepCost50us)
    ->Args({1, 16})
    ->Args({4, 16})
    ->Args({4, 64})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(3);

/// The machine's own ceiling for BM_SleepCost50us: `threads` threads of this process take the 2000
/// evaluations of a generation (each a 50 µs sleep, as the synthetic fitness sleeps) from an atomic
/// counter and meet at a barrier, generation after generation: no GA, no messages, no master. What
/// a perfect dispatcher would reach on this machine; with one thread, `eval_us` is the kernel's
/// real length of a 50 µs sleep (its granularity and wake-up latency). Arg: threads.
void BM_SleepCeiling(benchmark::State& state) {
  ::prctl(PR_SET_TIMERSLACK, 1UL, 0UL, 0UL, 0UL);  // as FixedCost: the sleep is the cost
  const int threads = static_cast<int>(state.range(0));
  constexpr int kEvals = 2000;
  constexpr auto kCost = std::chrono::microseconds(50);
  std::atomic<int> next{0};
  std::atomic<bool> quit{false};
  std::atomic<int64_t> slept_ns{0};
  std::barrier start(threads + 1), end(threads + 1);
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t)
    pool.emplace_back([&] {
      for (;;) {
        start.arrive_and_wait();
        if (quit.load()) return;
        int64_t ns = 0;
        while (next.fetch_add(1, std::memory_order_relaxed) < kEvals) {
          const auto t0 = std::chrono::steady_clock::now();
          std::this_thread::sleep_for(kCost);
          ns += std::chrono::duration_cast<std::chrono::nanoseconds>(
                    std::chrono::steady_clock::now() - t0)
                    .count();
        }
        slept_ns += ns;
        end.arrive_and_wait();
      }
    });
  int64_t generations = 0;
  const auto t0 = std::chrono::steady_clock::now();
  for (auto _ : state) {
    next = 0;
    start.arrive_and_wait();
    end.arrive_and_wait();
    ++generations;
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  quit = true;
  start.arrive_and_wait();
  for (auto& t : pool) t.join();
  const double evals = static_cast<double>(generations) * kEvals;
  state.counters["threads"] = threads;
  state.counters["efficiency"] = evals * 50e-6 / (threads * wall);
  state.counters["eval_us"] = 1e-3 * static_cast<double>(slept_ns.load()) / evals;
  state.counters["generation_ms"] =
      1e3 * wall / static_cast<double>(std::max<int64_t>(1, generations));
}
BENCHMARK(BM_SleepCeiling)
    ->Arg(1)
    ->Arg(16)
    ->Arg(64)
    ->Arg(256)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime()
    ->MinTime(2);

}  // namespace
}  // namespace pz

BENCHMARK_MAIN();
