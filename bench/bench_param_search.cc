// Speed of the complete-model optimisers (opt/param_search.h) on the Bouc–Wen benchmark
// oscillator's fitness, and of the simulator itself (model/bw_oscillator.h).
//   BM_BwSimulate/S          one 8192-sample multisine period at S RK4 sub-steps: samples/s
//   BM_Search_Bw/alg/threads a whole search (1 repetition, 20 particles / individuals, 10
//   iterations)
//                            on one 8192-sample period of train_A at 4 sub-steps, the benchmark's
//                            fitness (complete/boucwen_benchmark.h, the records engine's):
//                            evaluations/s
//   BM_Search_Sphere/alg     the same search on a 6-D sphere: the optimisers' own overhead
// Figures and the command: docs/performance.md, "Benchmarks of the parts" and "Studies against
// published figures".
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "complete/boucwen_benchmark.h"
#include "io/csv.h"
#include "opt/inline_evaluator.h"
#include "opt/param_search.h"
#include "opt/thread_pool_evaluator.h"
#include "model/bw_oscillator.h"

namespace pz::opt {

namespace {

struct Data {
  std::vector<double> u, y;
};

const Data& TrainA() {
  static const Data d = [] {
    const io::CsvTable t =
        io::ReadCsvFile(std::string(PIEZOID_DATA_DIR) + "/boucwen-benchmark/train_A_multisine.csv");
    Data r;
    for (size_t i = 0; i < 8192; ++i) {
      r.u.push_back(t.Number(i, t.RequireColumn("u_N")));
      r.y.push_back(t.Number(i, t.RequireColumn("y_m")));
    }
    return r;
  }();
  return d;
}

model::BwInput Input(int substeps) {
  model::BwInputOptions o;
  o.substeps = substeps;
  o.interpolation = model::InputInterpolation::kPeriodicFourier;
  return model::BwInput(TrainA().u, o);
}

void BM_BwSimulate(benchmark::State& state) {
  const model::BwInput in = Input(static_cast<int>(state.range(0)));
  std::vector<double> y(in.samples());
  for (auto _ : state) {
    benchmark::DoNotOptimize(model::SimulateBw(model::BwParams{}, in, y).ok());
    benchmark::ClobberMemory();
  }
  state.counters["samples/s"] =
      benchmark::Counter(state.iterations() * in.samples(), benchmark::Counter::kIsRate);
  state.counters["rk4_steps/s"] = benchmark::Counter(
      state.iterations() * (in.samples() - 1) * state.range(0), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_BwSimulate)->Arg(4)->Arg(20)->Unit(benchmark::kMillisecond);

SearchOptions SmallSearch(SearchAlgorithm a) {
  SearchOptions o;
  o.algorithm = a;
  o.repetitions = 1;
  o.pso.particles = o.ga_real.population = o.ga_binary.ga.population_size = 20;
  o.pso.iterations = o.ga_real.generations = o.ga_binary.ga.max_generations = 10;
  o.pso.stall_iterations = o.ga_real.stall_generations = o.ga_binary.ga.stall_generations = 0;
  o.ga_real.elite_fraction = 0.1;
  o.ga_binary.ga.elite_fraction = 0.1;  // evaluations per generation as for the real GA
  return o;
}

void RunSearch(benchmark::State& state, const ParamBox& box, const FitnessFunction& fitness) {
  const auto algorithm = static_cast<SearchAlgorithm>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  InlineEvaluator inline_evaluator(fitness);
  ThreadPoolEvaluator pool(fitness, threads);
  BatchEvaluator& evaluator = threads == 0 ? static_cast<BatchEvaluator&>(inline_evaluator) : pool;
  int64_t evaluations = 0;
  for (auto _ : state) evaluations += Search(box, SmallSearch(algorithm), evaluator).evaluations;
  state.SetLabel(std::string(SearchAlgorithmName(algorithm)) +
                 (threads == 0 ? " inline" : " pool"));
  state.counters["evaluations/s"] =
      benchmark::Counter(static_cast<double>(evaluations), benchmark::Counter::kIsRate);
}

void BM_Search_Bw(benchmark::State& state) {
  // The benchmark's protocol (complete/boucwen_benchmark.h): the records engine's fitness.
  std::vector<io::Record> records;
  records.push_back(
      complete::MakeBwRecord("train_A", model::CaseRole::kTrain, TrainA().u, TrainA().y, 0));
  const complete::BwTraining fitness(
      std::move(records),
      complete::BwProtocol(4, model::InputInterpolation::kPeriodicFourier, 8192), 1.0);
  RunSearch(state, fitness.Box(), fitness);
}
BENCHMARK(BM_Search_Bw)
    ->ArgsProduct({{static_cast<int>(SearchAlgorithm::kPso),
                    static_cast<int>(SearchAlgorithm::kGaReal),
                    static_cast<int>(SearchAlgorithm::kGaBinary)},
                   {0, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_Search_Sphere(benchmark::State& state) {
  FunctionFitness fitness([](std::span<const double> x) {
    double f = 0;
    for (double v : x) f += v * v;
    return FitnessResult{f, FitnessStatus::kOk, {}};
  });
  ParamBox box;
  for (int i = 0; i < 6; ++i) {
    box.names.push_back("x" + std::to_string(i));
    box.lower.push_back(-1);
    box.upper.push_back(1);
  }
  RunSearch(state, box, fitness);
}
BENCHMARK(BM_Search_Sphere)
    ->ArgsProduct({{static_cast<int>(SearchAlgorithm::kPso),
                    static_cast<int>(SearchAlgorithm::kGaReal),
                    static_cast<int>(SearchAlgorithm::kGaBinary)},
                   {0}})
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace pz::opt

BENCHMARK_MAIN();
