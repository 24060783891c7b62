// Cost of one evaluation of a `piezoid fit --records` search (records/fit.h
// RecordFitness::Evaluate: the simulation of the training records, the offset and the MSE) for the
// searched families, on a synthetic record the size of the 150 V recording
// (docs/real-recording.md): 10 s at 5 kHz, 3.257 s of rest at 0 V, then a 1 Hz ±150 V sine starting
// at −87 V; the training window 4–7 s, so that an evaluation simulates the 18,714 samples from the
// rest's end to 7 s. The response is the stack-bouc-wen's at a fitted point, plus a fixed
// pseudo-random 0.05 µm (the recording is not in the project). Each iteration alternates between
// two parameter points near the real fit's, as a search does (the fin's other geometry costs its FE
// assembly and modal discretisation each time).
//
//   BM_RecordEvaluation/<family>       one evaluation
//   BM_RecordEvaluationPair/<family>[+<effects>]   two evaluations side by side (a family with
//   lanes;
//       with drive effects each on its own drive)
//   BM_RecordEvaluationFour/<family>[+<effects>]   four side by side (the bw-oscillator's lanes())
//   BM_RecordEvaluation/<family>+<effects>   one evaluation with effects (issue 22's 10 s target):
//   a
//       linear family's weights solved for the effects' parameters (the regressors of the delayed /
//       crept drive, the regularised normal equations, the non-negative solve, the output); the
//       effects' parameters at 30 % / 31 % of their ranges (log ranges in log), the family's as
//       above. A linear family with `creep-spectrum` (records/spectrum_solve.h): the search's
//       genome is the other parameters (the delay), the spectrum's weights solved with the family's
//       in every evaluation — what `piezoid fit` evaluates; `…/searched` evaluates every parameter
//       given (the spectrum's weights too: one build of the normal equations of the filtered
//       regressors, the path of a searched spectrum)
//
// Figures and the command: docs/performance.md, "Benchmarks of the parts".
#include <benchmark/benchmark.h>

#include <cmath>
#include <map>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "io/records.h"
#include "model/stack_models.h"
#include "records/families.h"
#include "records/fit.h"
#include "records/model.h"
#include "records/registry.h"

namespace pz::records {
namespace {

constexpr double kFs = 5000;
constexpr size_t kSamples = 50001;

const io::Record& Recording() {
  static const io::Record r = [] {
    io::Record rec;
    rec.name = "synthetic-150V";
    rec.dt = 1 / kFs;
    rec.t.resize(kSamples);
    rec.u.resize(kSamples);
    rec.y.resize(kSamples);
    const double t_on = 3.2572;
    for (size_t k = 0; k < kSamples; ++k) {
      const double t = static_cast<double>(k) / kFs;
      rec.t[k] = t;
      rec.u[k] = t < t_on ? 0.0 : 150 * std::sin(2 * std::numbers::pi * t - 46.2178545458);
    }
    rec.rest_samples = static_cast<size_t>(std::ceil(t_on * kFs));
    model::SimulateStackBoucWen(
        model::BoucWenFromVector(std::vector<double>{0.40, 0.0075, 0.004, 0.13, 60}), rec.u, rec.dt,
        rec.y);
    uint64_t s = 0x9E3779B97F4A7C15ULL;
    for (double& v : rec.y) {
      s = s * 6364136223846793005ULL + 1442695040888963407ULL;
      v += -1.68 +
           0.05 * (static_cast<double>(s >> 11) / 9007199254740992.0 - 0.5) * std::sqrt(12.0);
    }
    rec.first_scored = 4 * static_cast<size_t>(kFs);
    rec.end_scored = 7 * static_cast<size_t>(kFs);
    rec.offset_mode = io::OffsetMode::kFit;
    return rec;
  }();
  return r;
}

// Two points near the fits of docs/real-recording.md (the family's parameter order).
const std::map<std::string, std::vector<std::vector<double>>>& Points() {
  static const std::map<std::string, std::vector<std::vector<double>>> p = {
      {"stack-bouc-wen", {{0.40, 0.0075, 0.004, 0.13, 60}, {0.41, 0.0074, 0.0041, 0.131, 61}}},
      {"duhem", {{0.01, 0.12, 1e-7, 0.02, 0.5}, {0.011, 0.121, 1.1e-7, 0.021, 0.51}}},
      {"bw-oscillator",
       {{0.1227, 13.66, 0.413, 0.214, 0.0535, 0.000225},
        {0.1230, 13.7, 0.41, 0.215, 0.054, 0.00022}}},
      {"bimorph-fin",
       {{184.2, 0.01688, 4.04e-4, 7.47e-3, 7.47e-3, 0, 0, 55.9, 2.20, 25.17, 0.08896, 0.013626},
        {185.0, 0.01690, 4.05e-4, 7.46e-3, 7.45e-3, 0, 0, 55.8, 2.21, 25.2, 0.08900, 0.013630}}},
  };
  return p;
}

std::vector<EffectKind> Effects(const std::string& names) {
  std::vector<EffectKind> out;
  for (size_t a = 0; a < names.size();) {
    const size_t b = std::min(names.find(',', a), names.size());
    out.push_back(ParseEffect(names.substr(a, b - a)));
    a = b + 1;
  }
  return out;
}

// The fitness of the family with `effects` (comma-separated, may be empty) on the synthetic
// record's training window.
struct Setup {
  explicit Setup(const std::string& family, const std::string& effects = "")
      : train{&Recording()},
        scale(MeasureScale(train)),
        model(MakeFamily(family, scale), Effects(effects), scale),
        fitness(model, train) {}
  // The two points: the family's (Points(); none for a linear family), then each effect parameter
  // at 30 % / 31 % of its range.
  std::vector<std::vector<double>> points(const std::string& family) const {
    std::vector<std::vector<double>> p =
        model.family().linear() ? std::vector<std::vector<double>>(2) : Points().at(family);
    for (size_t i = model.family_param_count(); i < model.params().size(); ++i) {
      const ParamInfo& q = model.params()[i];
      for (size_t j = 0; j < 2; ++j) {
        const double f = 0.30 + 0.01 * static_cast<double>(j);
        p[j].push_back(q.log_scale ? q.lower * std::pow(q.upper / q.lower, f)
                                   : q.lower + f * (q.upper - q.lower));
      }
    }
    return p;
  }
  std::vector<const io::Record*> train;
  DataScale scale;
  RecordModel model;
  RecordFitness fitness;
};

void BM_RecordEvaluation(benchmark::State& state, const std::string& family,
                         const std::string& effects = "", bool every_parameter = false) {
  const io::Record& rec = Recording();
  const Setup setup(family, effects);
  const RecordFitness& fitness = setup.fitness;
  auto points = setup.points(family);
  if (fitness.spectrum_solved() &&
      !every_parameter) {  // the searched parameters alone: the solve's path
    for (std::vector<double>& p : points) {
      std::vector<double> q;
      for (size_t i : fitness.searched()) q.push_back(p[i]);
      p = std::move(q);
    }
  }
  opt::Genome g;
  size_t i = 0;
  for (auto _ : state) {
    g.reals = points[i++ % points.size()];
    const opt::FitnessResult r = fitness.Evaluate(g);
    if (r.status != opt::FitnessStatus::kOk) {
      state.SkipWithError((family + ": " + r.reason).c_str());
      break;
    }
    benchmark::DoNotOptimize(r.cost);
  }
  state.counters["samples"] = static_cast<double>(rec.end_scored - (rec.rest_samples - 1));
}
// The same two points evaluated side by side (RecordFitness::EvaluateMany, what the thread pool
// hands a family with lanes): time per evaluation.
void BM_RecordEvaluationPair(benchmark::State& state, const std::string& family,
                             const std::string& effects = "") {
  const Setup setup(family, effects);
  const RecordFitness& fitness = setup.fitness;
  const auto points = setup.points(family);
  opt::Genome a, b;
  a.reals = points[0];
  b.reals = points[1];
  const opt::Genome* pair[2] = {&a, &b};
  opt::FitnessResult out[2];
  for (auto _ : state) {
    fitness.EvaluateMany(pair, out);
    benchmark::DoNotOptimize(out[0].cost);
  }
  state.SetItemsProcessed(2 * static_cast<int64_t>(state.iterations()));  // evaluations/s
}
// Four at once (the bw-oscillator's lanes(): two vector chains), the two points twice.
void BM_RecordEvaluationFour(benchmark::State& state, const std::string& family,
                             const std::string& effects = "") {
  const Setup setup(family, effects);
  const auto points = setup.points(family);
  std::vector<opt::Genome> g(4);
  for (size_t l = 0; l < g.size(); ++l) g[l].reals = points[l % 2];
  const opt::Genome* group[4] = {&g[0], &g[1], &g[2], &g[3]};
  opt::FitnessResult out[4];
  for (auto _ : state) {
    setup.fitness.EvaluateMany(group, out);
    benchmark::DoNotOptimize(out[0].cost);
  }
  state.SetItemsProcessed(4 * static_cast<int64_t>(state.iterations()));  // evaluations/s
}
BENCHMARK_CAPTURE(BM_RecordEvaluationFour, bw - oscillator, std::string("bw-oscillator"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluationFour, bw - oscillator + delay, std::string("bw-oscillator"),
                  std::string("delay"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluationFour, bw - oscillator + creep - spectrum + delay,
                  std::string("bw-oscillator"), std::string("creep-spectrum,delay"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluationPair, bw - oscillator, std::string("bw-oscillator"))
    ->Unit(benchmark::kMillisecond);
// With effects: each genome its own delayed / crept drive, its own output effects.
BENCHMARK_CAPTURE(BM_RecordEvaluationPair, bw - oscillator + delay, std::string("bw-oscillator"),
                  std::string("delay"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluationPair, bw - oscillator + creep, std::string("bw-oscillator"),
                  std::string("creep"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluationPair, bw - oscillator + creep - spectrum + delay,
                  std::string("bw-oscillator"), std::string("creep-spectrum,delay"))
    ->Unit(benchmark::kMillisecond);

BENCHMARK_CAPTURE(BM_RecordEvaluation, stack - bouc - wen, std::string("stack-bouc-wen"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluation, duhem, std::string("duhem"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluation, bw - oscillator, std::string("bw-oscillator"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluation, bimorph - fin, std::string("bimorph-fin"))
    ->Unit(benchmark::kMillisecond);
// With effects (issue 22): what the 10 s target's heaviest searches evaluate.
BENCHMARK_CAPTURE(BM_RecordEvaluation, preisach + delay, std::string("preisach"),
                  std::string("delay"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluation, preisach + creep - spectrum + delay, std::string("preisach"),
                  std::string("creep-spectrum,delay"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluation, preisach + creep - spectrum + delay / searched,
                  std::string("preisach"), std::string("creep-spectrum,delay"), true)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluation, prandtl - ishlinskii + creep - spectrum + delay,
                  std::string("prandtl-ishlinskii"), std::string("creep-spectrum,delay"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluation, prandtl - ishlinskii + creep,
                  std::string("prandtl-ishlinskii"), std::string("creep"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluation, asymmetric - pi + delay, std::string("asymmetric-pi"),
                  std::string("delay"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluation, stack - bouc - wen + delay, std::string("stack-bouc-wen"),
                  std::string("delay"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluation, bw - oscillator + delay, std::string("bw-oscillator"),
                  std::string("delay"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluation, bimorph - fin + delay, std::string("bimorph-fin"),
                  std::string("delay"))
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_RecordEvaluation, bimorph - fin + creep, std::string("bimorph-fin"),
                  std::string("creep"))
    ->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace pz::records

BENCHMARK_MAIN();
