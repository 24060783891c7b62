// Cost per sample of a fitted model in a controller (records/stepper.h, issue 23): the step kernels
// of model/kernels/ — the code the exported C header runs — one sample at a time, on a 1 Hz sine of
// slowly varying amplitude with a 7 Hz ripple at 5 kHz (minor loops):
//   BM_Forward/<case>   NAME_step: drive -> response
//   BM_Inverse/<case>   NAME_inverse_step: desired response -> drive (bisection on the one-step
//   map)
// cases: 0 prandtl-ishlinskii (30 plays), 1 backlash-like, 2 stack-bouc-wen + driver-lowpass,
// 3 duhem, 4 preisach (12 levels), 5 asymmetric-pi (12 plays), 6 bw-oscillator (4 RK4 steps).
// Figures and the command: docs/performance.md, "Benchmarks of the parts".
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "records/stepper.h"

namespace pz::records {
namespace {

constexpr size_t kSamples = 20000;
constexpr double kDt = 2e-4;

struct Case {
  const char* family;
  std::vector<EffectKind> effects;
  int operators;
};
const Case kCases[] = {{"prandtl-ishlinskii", {}, 30},
                       {"backlash-like", {}, 12},
                       {"stack-bouc-wen", {EffectKind::Named("driver-lowpass")}, 12},
                       {"duhem", {}, 12},
                       {"preisach", {}, 12},
                       {"asymmetric-pi", {}, 12},
                       {"bw-oscillator", {}, 12}};

const io::Record& Drive() {
  static const io::Record r = [] {
    io::Record rec;
    for (size_t k = 0; k < kSamples; ++k) {
      const double t = static_cast<double>(k) * kDt;
      rec.t.push_back(t);
      rec.u.push_back(75 +
                      60 * std::sin(2 * std::numbers::pi * t) * (0.7 + 0.3 * std::sin(0.9 * t)) +
                      5 * std::sin(2 * std::numbers::pi * 7 * t));
      rec.y.push_back(0.3 * rec.u.back());
    }
    rec.dt = kDt;
    rec.end_scored = kSamples;
    rec.rest_samples = 1;
    return rec;
  }();
  return r;
}

/// The middle of every parameter's box, positive weights (a monotone operator).
ModelSpec Spec(const Case& c) {
  const io::Record& r = Drive();
  ModelSpec s;
  s.family = c.family;
  s.effects = c.effects;
  s.pi_operators = c.operators;
  s.scale = MeasureScale({&r});
  s.dt = kDt;
  s.drive_min = s.scale.u_min;
  s.drive_max = s.scale.u_max;
  const auto model = s.Model();
  for (const auto& p : model->params())
    s.params.push_back(p.log_scale ? std::sqrt(p.lower * p.upper) : 0.5 * (p.lower + p.upper));
  if (s.family == "backlash-like")
    s.params = {2 / s.scale.u_half, 0.4, 0.25};  // B1 >= c/2: monotone
  if (model->family().linear())
    for (size_t j = 0; j < model->family().regressors(); ++j)
      s.weights.push_back(0.01 + 0.002 * static_cast<double>(j % 7));
  return s;
}

void BM_Forward(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  Stepper st(Spec(c));
  const auto& u = Drive().u;
  st.Init(u[0]);
  size_t k = 1;
  double acc = 0;
  for (auto _ : state) {
    acc += st.Step(u[k]);
    if (++k == u.size()) k = 1, st.Init(u[0]);
  }
  benchmark::DoNotOptimize(acc);
  state.SetLabel(std::string(c.family) + (c.effects.empty() ? "" : " + driver-lowpass"));
  state.SetItemsProcessed(state.iterations());
}

void BM_Inverse(benchmark::State& state) {
  const Case& c = kCases[state.range(0)];
  const ModelSpec s = Spec(c);
  Stepper fwd(s);
  const auto& u = Drive().u;
  std::vector<double> ref(u.size());
  ref[0] = fwd.Init(u[0]);
  for (size_t k = 1; k < u.size(); ++k) ref[k] = fwd.Step(u[k]);
  Stepper inv(s);
  inv.Init(u[0]);
  size_t k = 1;
  double acc = 0;
  for (auto _ : state) {
    acc += inv.InverseStep(ref[k]);
    if (++k == u.size()) k = 1, inv.Init(u[0]);
  }
  benchmark::DoNotOptimize(acc);
  state.SetLabel(std::string(c.family) + (c.effects.empty() ? "" : " + driver-lowpass"));
  state.SetItemsProcessed(state.iterations());
}

BENCHMARK(BM_Forward)->DenseRange(0, 6);
BENCHMARK(BM_Inverse)->DenseRange(0, 6);

}  // namespace
}  // namespace pz::records

BENCHMARK_MAIN();
