// The Preisach family at 40+ levels (issue 37) on the independent relay plant
// (synth/relay_preisach_check.h: 100 Hz, 120 s of rich training drive, 12,200 samples):
//   BM_PreisachNormalEquations/dense/levels       the cell rows formed, then their Gram (before)
//   BM_PreisachNormalEquations/structured/levels  the Gram from the levels' histograms (now)
//   BM_PreisachFit/levels                          FitRecords at a fixed grid, no effects: the
//                                                  validation (2 penalties × 10 strengths × 5
//                                                  blocks) and the solve, on 2 threads
//   BM_PreisachAutoFit                             --pi-operators auto with creep-spectrum + delay:
//                                                  the effects' search on 12 levels, the levels'
//                                                  validation over 12 / 20 / 28 / 40, the weights
// Figures and the command: docs/performance.md, "Benchmarks of the parts".
#include <benchmark/benchmark.h>

#include <vector>

#include "model/preisach.h"
#include "records/fit.h"
#include "records/model.h"
#include "records/preisach_normal.h"
#include "synth/relay_preisach_check.h"

namespace pz::records {
namespace {

const synth::RelayPreisachCheckSet& Check() {
  static const synth::RelayPreisachCheckSet s =
      synth::GenerateRelayPreisachCheck(synth::RelayPreisachCheckOptions{});
  return s;
}

void BM_PreisachNormalEquations(benchmark::State& state, bool structured) {
  const io::Record& r = Check().set.records[0];
  const model::PreisachGrid g{r.u.front(), 120, static_cast<int>(state.range(0))};
  const size_t from = SimulatedFrom(r, r.end_scored), m = g.cells();
  const std::vector<double> u(r.u.begin() + static_cast<std::ptrdiff_t>(from), r.u.end());
  const auto start = model::ResolveInitialState(model::InitialState::kAuto, u[0], g.u_min, g.u_max);
  std::vector<double> reg;
  for (auto _ : state) {
    BlockedNormalEquations eq{std::vector<Eigen::MatrixXd>(kValidationBlocks),
                              std::vector<Eigen::VectorXd>(kValidationBlocks),
                              std::vector<double>(kValidationBlocks),
                              std::vector<size_t>(kValidationBlocks)};
    NormalEquationsBuilder b(eq, m, r.scored());
    if (structured) {
      AddPreisachRecordRows(g, start, r, from, u, 1, b);
    } else {
      reg.resize(u.size() * m);
      model::PreisachRegressors(g, u, reg, start);
      AddRecordRows(r, from, reg, m, 1, b);
    }
    b.Finish();
    benchmark::DoNotOptimize(eq.G[0].data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * r.scored()));
}
BENCHMARK_CAPTURE(BM_PreisachNormalEquations, dense, false)
    ->Arg(12)
    ->Arg(40)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_PreisachNormalEquations, structured, true)
    ->Arg(12)
    ->Arg(40)
    ->Unit(benchmark::kMillisecond);

void BM_PreisachFit(benchmark::State& state) {
  FitOptions o;
  o.family = "preisach";
  o.family_options.pi_operators = static_cast<int>(state.range(0));
  o.threads = 2;
  for (auto _ : state) benchmark::DoNotOptimize(FitRecords(Check().set, o).train_mse);
}
BENCHMARK(BM_PreisachFit)->Arg(12)->Arg(40)->Iterations(1)->UseRealTime()->Unit(benchmark::kSecond);

void BM_PreisachAutoFit(benchmark::State& state) {
  FitOptions o;
  o.family = "preisach";
  o.family_options.pi_operators = kAutoLevels;
  o.effects = {EffectKind::Named("creep-spectrum"), EffectKind::Named("delay")};
  o.sizing.enabled = true;
  o.threads = 2;
  for (auto _ : state) {
    const FitResult r = FitRecords(Check().set, o);
    state.counters["levels"] = r.resolution.value();
    for (size_t i = 0; i < r.metrics.size(); ++i)
      state.counters["x_floor_" + r.metrics[i].name] = r.metrics[i].rmse / Check().noise_rms_um[i];
  }
}
BENCHMARK(BM_PreisachAutoFit)->Iterations(1)->UseRealTime()->Unit(benchmark::kSecond);

}  // namespace
}  // namespace pz::records

BENCHMARK_MAIN();
