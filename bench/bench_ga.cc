// Speed of the GA's operators alone (selection, two-point crossover, mutation by geometric gaps,
// ranking, bookkeeping) at the paper's size, population 400 × 1415 bits, with a null or a cheap
// fitness; and of the chromosome decode + forward pass that every HGANN fitness evaluation starts
// with. Figures: docs/performance.md, "Benchmarks of the parts".
#include <benchmark/benchmark.h>

#include <algorithm>

#include "opt/ga.h"
#include "opt/inline_evaluator.h"
#include "opt/random.h"
#include "opt/thread_pool_evaluator.h"
#include "model/chromosome.h"

namespace pz::opt {

namespace {

class NullFitness final : public FitnessFunction {
 public:
  FitnessResult Evaluate(const Genome&) const override { return {}; }
};

class OneMax final : public FitnessFunction {
 public:
  FitnessResult Evaluate(const Genome& g) const override {
    return {static_cast<double>(std::count(g.bits.begin(), g.bits.end(), 0)), FitnessStatus::kOk,
            ""};
  }
};

// One iteration = one generation (Step) of the paper's GA: 200 offspring of 1415 bits.
void RunSteps(benchmark::State& state, BatchEvaluator* evaluator) {
  GaOptions options;  // population 400, 1415 bits, 50 % elitism, binary tournament, pm 0.01
  GeneticAlgorithm ga(options, evaluator);
  ga.Initialize();
  for (auto _ : state) {
    benchmark::DoNotOptimize(ga.Step().best_cost);
  }
  state.counters["generations/s"] =
      benchmark::Counter(state.iterations(), benchmark::Counter::kIsRate);
  state.counters["offspring/s"] =
      benchmark::Counter(state.iterations() * (options.population_size - options.elite_count()),
                         benchmark::Counter::kIsRate);
}

void BM_GaStep_NullFitness_Inline(benchmark::State& state) {
  const NullFitness fitness;
  InlineEvaluator evaluator(fitness);
  RunSteps(state, &evaluator);
}
BENCHMARK(BM_GaStep_NullFitness_Inline)->Unit(benchmark::kMillisecond);

void BM_GaStep_OneMax_Inline(benchmark::State& state) {
  const OneMax fitness;
  InlineEvaluator evaluator(fitness);
  RunSteps(state, &evaluator);
}
BENCHMARK(BM_GaStep_OneMax_Inline)->Unit(benchmark::kMillisecond);

void BM_GaStep_NullFitness_ThreadPool(benchmark::State& state) {
  const NullFitness fitness;
  ThreadPoolEvaluator evaluator(fitness, static_cast<int>(state.range(0)));
  RunSteps(state, &evaluator);
}
BENCHMARK(BM_GaStep_NullFitness_ThreadPool)
    ->Arg(1)
    ->Arg(2)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// The generator alone: one Bernoulli draw (the crossover decision), and one geometric gap (the
// mutation: one per flipped bit plus one per genome, ≈ 15 a genome at p = 0.01 on 1415 bits, where
// a per-bit test would take 1415 Bernoulli draws).
void BM_RngBernoulli(benchmark::State& state) {
  Rng rng(1);
  const BernoulliThreshold p(0.01);
  for (auto _ : state) benchmark::DoNotOptimize(rng.Bernoulli(p));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RngBernoulli);

void BM_RngGeometricGap(benchmark::State& state) {
  Rng rng(1);
  const GeometricGaps gaps(0.01, 1415);
  for (auto _ : state) benchmark::DoNotOptimize(rng.Gap(gaps));
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_RngGeometricGap);

// Decode a 1415-bit chromosome into a network and predict the parameters of four cases.
void BM_DecodeAndPredict(benchmark::State& state) {
  Rng rng(2);
  std::vector<uint8_t> bits(model::kChromosomeBits);
  for (uint8_t& b : bits) b = static_cast<uint8_t>(rng.NextU64() >> 63);
  const model::InputNormalization norm{375, 750, 0.25, 1.0};
  const double cases[4][2] = {{375, 0.25}, {500, 0.5}, {500, 1.0}, {750, 0.25}};
  for (auto _ : state) {
    const model::Network n = model::DecodeChromosome(bits, norm, {});
    for (const auto& c : cases) benchmark::DoNotOptimize(n.Predict(c[0], c[1]).mu);
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_DecodeAndPredict);

}  // namespace
}  // namespace pz::opt

BENCHMARK_MAIN();
