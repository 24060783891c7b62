// Wall time of one GA fitness evaluation: the four training cases of the spec (1: 375 V 0.25 Hz,
// 5: 500 V 0.5 Hz, 6: 500 V 1 Hz, 7: 750 V 0.25 Hz; three cycles at 100 Hz) simulated at the
// nominal truth parameters of data/bimorph-fin/nominal/truth.json, on the fast modal path and on
// the CVODE path; and the same drives sampled (u linear between the samples) on the sampled path
// and on the C step kernel alone (model/kernels/bimorph_fin.h: the sinusoid path's and the
// vectorised mode loop's yardstick, docs/architecture.md "The fin's step"). Figures and the command
// line: docs/performance.md, "Benchmarks of the parts".
#include <benchmark/benchmark.h>

#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "model/bimorph.h"
#include "model/kernels/pzk.h"
#include "model/modal_simulator.h"

namespace pz::model {
namespace {

struct TrainingCase {
  int id;
  Sinusoid drive;
  BimorphParams params;
};

// Nominal truth (data/bimorph-fin/nominal/truth.json): μ, δ, α, β, γ, a1, a2 shared, b1/b2 per
// case.
std::array<TrainingCase, 4> TrainingCases() {
  auto p = [](double b1, double b2) {
    BimorphParams x;
    x.mu = 95.0;
    x.delta = 0.1;
    x.alpha = 2.5e-3;
    x.beta = 6e-3;
    x.gamma = 4e-3;
    x.a1 = 0.1;
    x.a2 = 0.15;
    x.b1 = b1;
    x.b2 = b2;
    return x;
  };
  return {{{1, Sinusoid{375.0, 0.25, 3.0, 100.0}, p(1.37, -1.5)},
           {5, Sinusoid{500.0, 0.5, 3.0, 100.0}, p(2.05, -1.91)},
           {6, Sinusoid{500.0, 1.0, 3.0, 100.0}, p(1.73, -1.66)},
           {7, Sinusoid{750.0, 0.25, 3.0, 100.0}, p(4.21, -4.03)}}};
}

const BimorphPlant& Plant() {
  static const BimorphPlant plant;
  return plant;
}

// How the parameters change between evaluations, which decides how often the per-(μ, δ) modal
// discretisation is recomputed:
//   0: the same parameters every evaluation (cache always hit: the pure simulation cost);
//   1: new μ, δ every evaluation, shared by the four cases (one recomputation per evaluation);
//   2: new μ, δ for every case (four recomputations: a network mapping (V, f) to parameters).
void BM_FitnessModal(benchmark::State& state) {
  const int mode = static_cast<int>(state.range(0));
  const ModalSimulator sim(Plant());
  ModalWorkspace ws;
  std::array<TrainingCase, 4> cases = TrainingCases();
  std::array<std::vector<double>, 4> out;
  for (size_t c = 0; c < cases.size(); ++c) out[c].resize(cases[c].drive.NumSamples());
  long evaluations = 0;
  for (auto _ : state) {
    double cost = 0;
    for (size_t c = 0; c < cases.size(); ++c) {
      BimorphParams p = cases[c].params;
      if (mode == 1) p.mu += 1e-9 * static_cast<double>(evaluations % 1000);
      if (mode == 2) p.mu += 1e-9 * static_cast<double>((evaluations % 1000) * 4 + c);
      const SimulationSummary s = sim.SimulateAngle(p, cases[c].drive, out[c], ws);
      if (!s.ok()) {
        state.SkipWithError(("modal path failed: " + s.BriefReport()).c_str());
        return;
      }
      for (double y : out[c]) cost += y * y;  // stands in for the PI against measured data
    }
    benchmark::DoNotOptimize(cost);
    ++evaluations;
  }
  state.counters["evals/s"] =
      benchmark::Counter(static_cast<double>(evaluations), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_FitnessModal)->Arg(0)->Arg(1)->Arg(2)->Unit(benchmark::kMicrosecond);

// The general entry point model::Simulate on the fast path (validation, full trace, allocation).
void BM_FitnessModalFullTrace(benchmark::State& state) {
  const std::array<TrainingCase, 4> cases = TrainingCases();
  for (auto _ : state) {
    double cost = 0;
    for (const TrainingCase& c : cases) {
      const BimorphTrace t = Simulate(Plant(), c.params, c.drive);
      if (!t.summary.ok()) {
        state.SkipWithError(("modal path failed: " + t.summary.BriefReport()).c_str());
        return;
      }
      cost += t.angle_deg.back();
    }
    benchmark::DoNotOptimize(cost);
  }
}
BENCHMARK(BM_FitnessModalFullTrace)->Unit(benchmark::kMicrosecond);

// The training cases' drives sampled at their rate: u linear between the samples (the sampled
// path's drive, not the sinusoid's: the outputs differ by the hold, not the arithmetic).
SampledSignal Sampled(const Sinusoid& s) {
  SampledSignal x;
  for (int k = 0; k < s.NumSamples(); ++k) {
    const double t = k / s.sample_rate_hz;
    x.t.push_back(t);
    x.u.push_back(s.amplitude_v * std::sin(2 * std::numbers::pi * s.frequency_hz * t));
  }
  return x;
}

// ModalSimulator on the sampled drives (the same parameters every evaluation).
void BM_FitnessModalSampled(benchmark::State& state) {
  const ModalSimulator sim(Plant());
  ModalWorkspace ws;
  const std::array<TrainingCase, 4> cases = TrainingCases();
  std::array<DriveSignal, 4> drives;
  std::array<std::vector<double>, 4> out;
  for (size_t c = 0; c < cases.size(); ++c) {
    drives[c] = Sampled(cases[c].drive);
    out[c].resize(cases[c].drive.NumSamples());
  }
  for (auto _ : state) {
    double cost = 0;
    for (size_t c = 0; c < cases.size(); ++c) {
      const SimulationSummary s = sim.SimulateAngle(cases[c].params, drives[c], out[c], ws);
      if (!s.ok()) {
        state.SkipWithError(("sampled path failed: " + s.BriefReport()).c_str());
        return;
      }
      for (double y : out[c]) cost += y * y;
    }
    benchmark::DoNotOptimize(cost);
  }
}
BENCHMARK(BM_FitnessModalSampled)->Unit(benchmark::kMicrosecond);

// The C step kernel alone on the same sampled drives: pzk_fin_init, then pzk_fin_step per sample
// (every mode through pzk_fin_mode_update, one at a time), as the records family and the exported
// plant step.
void BM_FitnessKernelSampled(benchmark::State& state) {
  const ModalSimulator sim(Plant());
  const std::array<TrainingCase, 4> cases = TrainingCases();
  const int n = sim.num_modes();
  std::vector<double> w{1.0 / sim.length_m()};
  for (auto v : {sim.omega2(), sim.tip_gain_u(), sim.tip_gain_z()})
    w.insert(w.end(), v.begin(), v.end());
  std::array<SampledSignal, 4> drives;
  std::array<std::array<double, 11>, 4> ps;
  for (size_t c = 0; c < cases.size(); ++c) {
    drives[c] = Sampled(cases[c].drive);
    const BimorphParams& p = cases[c].params;
    ps[c] = {p.mu, p.delta, p.alpha, p.beta, p.gamma, p.a1, p.a2, p.b1, -p.b2, 1.0, 0.0};
  }
  std::vector<double> cs(static_cast<size_t>(PZK_FIN_C * n)), ds(static_cast<size_t>(2 * n + 4));
  for (auto _ : state) {
    double cost = 0;
    for (size_t c = 0; c < cases.size(); ++c) {
      pzk::pzk_block b{};
      b.kind = pzk::PZK_BIMORPH_FIN;
      b.n = n;
      b.dt = drives[c].t[1] - drives[c].t[0];
      b.p = ps[c].data();
      b.np = static_cast<int>(ps[c].size());
      b.w = w.data();
      b.nw = static_cast<int>(w.size());
      const std::vector<double>& u = drives[c].u;
      double y = pzk::pzk_fin_init(&b, cs.data(), ds.data(), u[0]);
      cost += y * y;
      for (size_t k = 1; k < u.size(); ++k) {
        y = pzk::pzk_fin_step(&b, cs.data(), ds.data(), ds.data(), u[k]);
        cost += y * y;
      }
    }
    benchmark::DoNotOptimize(cost);
  }
}
BENCHMARK(BM_FitnessKernelSampled)->Unit(benchmark::kMicrosecond);

// The CVODE path (Solver::kCvode) at its default tolerances. Reports an error, not a crash, while
// that path is unavailable or fails.
void BM_FitnessCvode(benchmark::State& state) {
  const std::array<TrainingCase, 4> cases = TrainingCases();
  SimulateOptions options;
  options.solver = Solver::kCvode;
  long steps = 0, rhs = 0, evaluations = 0;
  for (auto _ : state) {
    double cost = 0;
    for (const TrainingCase& c : cases) {
      const BimorphTrace t = Simulate(Plant(), c.params, c.drive, options);
      if (!t.summary.ok()) {
        state.SkipWithError(("cvode path failed: " + t.summary.BriefReport()).c_str());
        return;
      }
      steps += t.summary.steps;
      rhs += t.summary.rhs_calls;
      cost += t.angle_deg.back();
    }
    benchmark::DoNotOptimize(cost);
    ++evaluations;
  }
  if (evaluations > 0) {
    state.counters["steps/eval"] = static_cast<double>(steps) / static_cast<double>(evaluations);
    state.counters["rhs/eval"] = static_cast<double>(rhs) / static_cast<double>(evaluations);
  }
}
BENCHMARK(BM_FitnessCvode)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace pz::model

BENCHMARK_MAIN();
