// Cost per evaluation of the rate-independent families with return-point memory (model/preisach.h,
// issue 22) on a 15,000-sample record (3 s at 5 kHz, the real recording's training window; a 1 Hz
// sine whose amplitude ramps down and back: nested minor loops):
//   BM_PreisachApply/levels        the forward model with given weights: samples/s
//   BM_PreisachRegressors/levels   the cell regressors (what every least-squares evaluation
//   computes) BM_PreisachInverse/levels      the exact inverse (one-step bisection): samples/s
//   BM_AsymmetricPiApply / BM_AsymmetricPiInverse   the same for asymmetric-pi (12 plays, 6 knots)
// Figures and the command: docs/performance.md, "Benchmarks of the parts".
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "model/prandtl_ishlinskii.h"
#include "model/preisach.h"

namespace pz::model {
namespace {

constexpr size_t kSamples = 15000;

const std::vector<double>& Drive() {
  static const std::vector<double> u = [] {
    std::vector<double> v(kSamples);
    for (size_t k = 0; k < kSamples; ++k) {
      const double t = static_cast<double>(k) / 5000, a = std::abs(1 - 2 * t / 3);
      v[k] = 75 - 75 * a * std::cos(2 * std::numbers::pi * t);
    }
    return v;
  }();
  return u;
}

std::vector<double> Weights(const PreisachGrid& g) {
  std::vector<double> w;
  for (int i = 0; i < g.levels; ++i)
    for (int j = 0; j < g.levels - i; ++j)
      w.push_back(0.02 * std::exp(-i / 4.0) * (1 + 0.2 * j / g.levels));
  return w;
}

void BM_PreisachApply(benchmark::State& state) {
  const PreisachGrid g{0, 150, static_cast<int>(state.range(0))};
  const auto w = Weights(g);
  std::vector<double> y(kSamples);
  for (auto _ : state) {
    ApplyPreisach(g, w, Drive(), y);
    benchmark::DoNotOptimize(y.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * kSamples));
}
BENCHMARK(BM_PreisachApply)->Arg(8)->Arg(12)->Arg(20)->Unit(benchmark::kMillisecond);

void BM_PreisachRegressors(benchmark::State& state) {
  const PreisachGrid g{0, 150, static_cast<int>(state.range(0))};
  std::vector<double> reg(kSamples * g.cells());
  for (auto _ : state) {
    PreisachRegressors(g, Drive(), reg);
    benchmark::DoNotOptimize(reg.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * kSamples));
}
BENCHMARK(BM_PreisachRegressors)->Arg(8)->Arg(12)->Arg(20)->Unit(benchmark::kMillisecond);

void BM_PreisachInverse(benchmark::State& state) {
  const PreisachGrid g{0, 150, static_cast<int>(state.range(0))};
  const auto w = Weights(g);
  std::vector<double> ref(kSamples), u(kSamples);
  ApplyPreisach(g, w, Drive(), ref);
  for (auto _ : state) {
    benchmark::DoNotOptimize(InvertPreisach(g, w, ref, 0, 150, u));
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * kSamples));
}
BENCHMARK(BM_PreisachInverse)->Arg(8)->Arg(12)->Arg(20)->Unit(benchmark::kMillisecond);

AsymmetricPi Operator() {
  AsymmetricPi op;
  op.w0 = 0.05;
  op.thresholds = PiThresholds(12, 75);
  for (size_t i = 0; i < 12; ++i)
    op.weights.push_back(0.02 * std::exp(-static_cast<double>(i) / 4));
  op.knots = AsymmetricPiKnots(6, 0, 150);
  op.up = {0, 0, 0, 0.005, 0.01, 0.02};
  op.down = {0.01, 0.005, 0, 0, 0, 0};
  return op;
}

void BM_AsymmetricPiApply(benchmark::State& state) {
  const AsymmetricPi op = Operator();
  std::vector<double> y(kSamples);
  for (auto _ : state) {
    ApplyAsymmetricPi(op, Drive(), y);
    benchmark::DoNotOptimize(y.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * kSamples));
}
BENCHMARK(BM_AsymmetricPiApply)->Unit(benchmark::kMillisecond);

void BM_AsymmetricPiInverse(benchmark::State& state) {
  const AsymmetricPi op = Operator();
  std::vector<double> ref(kSamples), u(kSamples);
  ApplyAsymmetricPi(op, Drive(), ref);
  for (auto _ : state) {
    InvertAsymmetricPi(op, ref, u);
    benchmark::DoNotOptimize(u.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * kSamples));
}
BENCHMARK(BM_AsymmetricPiInverse)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace pz::model

BENCHMARK_MAIN();
