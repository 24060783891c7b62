// The fin bench fitted by the records engine (records/fit.h FitRecords, bimorph-fin's bench form
// over io::RecordsFromCaseSet's records) on the bundled nominal bench (data/bimorph-fin/nominal,
// six training cases): what one evaluation, one residual vector, a fit's setup and the base fit
// cost. (The fit is the former fin engine's bit for bit: tests/diagnose/fin_records_test.cc pins
// its figures.)
//
//   BM_Evaluation/fast    one cost evaluation of the base model (modal path) at a unit point
//   BM_Evaluation/cvode   one cost evaluation with hinge-friction (CVODE)
//   BM_Residuals          one training residual vector of the base model (a Jacobian column of
//                         the polish)
//   BM_RecordsSetup       what a records fit builds before it searches: the family (its plant's
//                         FE assembly and modes), the model, the fitness
//   BM_BaseFit            the base fit with the bench's budget: DE 40 × ≤ 80 generations, stall
//                         15 (seed 7), LM ≤ 40 iterations, two threads, no uncertainty table
//
// Run: build/bench/bench_fin_records
#include <benchmark/benchmark.h>

#include <string>
#include <vector>

#include "io/bench_data.h"
#include "io/fin_records.h"
#include "records/fit.h"
#include "records/registry.h"

namespace pz::records {
namespace {

using model::EffectKind;

const io::CaseSet& Bench() {
  static const io::CaseSet set =
      io::LoadCaseSet(std::string(PIEZOID_DATA_DIR) + "/bimorph-fin/nominal");
  return set;
}

const io::RecordSet& Records() {
  static const io::RecordSet set = io::RecordsFromCaseSet(Bench());
  return set;
}

std::vector<EffectKind> Effects(bool cvode) {
  if (cvode) return {EffectKind::Named("hinge-friction")};
  return {};
}

// A point of the unit box near a fit of the nominal bench (μ, δ, α, β, γ/β, a1, a2, then the
// hinge's fc_n and σ).
std::vector<double> UnitPoint(bool cvode) {
  std::vector<double> u = {0.25, 0.1, 0.4, 0.6, 0.7, 0.1, 0.05};
  if (cvode) u.insert(u.end(), {0.02, 0.5});
  return u;
}

void BM_Evaluation(benchmark::State& state, bool cvode) {
  const std::vector<double> u = UnitPoint(cvode);
  opt::Genome g;
  FamilyOptions fo;
  fo.bench_form = true;
  const std::vector<const io::Record*> train = Records().WithRole(model::CaseRole::kTrain);
  const DataScale scale = MeasureScale(train);
  const RecordModel m(MakeFamily("bimorph-fin", scale, fo), Effects(cvode), scale);
  const RecordFitness f(m, train);
  g.reals = RecordMap(m).ToPhysical(u);  // what FitModel hands the fitness
  for (auto _ : state) benchmark::DoNotOptimize(f.Evaluate(g).cost);
}

// One residual vector of the base model (what each column of the polish's Jacobian costs).
void BM_Residuals(benchmark::State& state) {
  const std::vector<double> u = UnitPoint(false);
  std::vector<double> r;
  FamilyOptions fo;
  fo.bench_form = true;
  const std::vector<const io::Record*> train = Records().WithRole(model::CaseRole::kTrain);
  const DataScale scale = MeasureScale(train);
  const RecordModel m(MakeFamily("bimorph-fin", scale, fo), {}, scale);
  const RecordFitness f(m, train);
  const std::vector<double> x = RecordMap(m).ToPhysical(u);
  for (auto _ : state) benchmark::DoNotOptimize(f.Residuals(x, r));
}

// What a records fit builds before its search: the family (its plant's FE assembly and modes),
// the model and the fitness.
void BM_RecordsSetup(benchmark::State& state) {
  FamilyOptions fo;
  fo.bench_form = true;
  const std::vector<const io::Record*> train = Records().WithRole(model::CaseRole::kTrain);
  for (auto _ : state) {
    const DataScale scale = MeasureScale(train);
    const RecordModel m(MakeFamily("bimorph-fin", scale, fo), {}, scale);
    const RecordFitness f(m, train);
    benchmark::DoNotOptimize(f.samples());
  }
}

opt::DeOptions De() {
  opt::DeOptions d;
  d.population = 40;  // the bench's base fit (diagnose/fin_diagnose.h DiagnoseOptions)
  d.generations = 80;
  d.stall_generations = 15;
  d.seed = 7;
  return d;
}

opt::LmOptions Lm() {
  opt::LmOptions l;
  l.max_iterations = 40;
  l.threads = 2;
  return l;
}

void BM_BaseFit(benchmark::State& state) {
  for (auto _ : state) {
    FitOptions o;
    o.family = "bimorph-fin";
    o.family_options.bench_form = true;
    o.search.algorithm = opt::SearchAlgorithm::kDe;
    o.search.de = De();
    o.search.repetitions = 1;
    o.lm = Lm();
    o.uncertainty = false;
    o.threads = 2;
    const FitResult r = FitRecords(Records(), o);
    state.counters["evaluations"] = static_cast<double>(r.evaluations);
    state.counters["train_pi"] = r.train_sse;
  }
}

BENCHMARK_CAPTURE(BM_Evaluation, fast, false)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Evaluation, cvode, true)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Residuals)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RecordsSetup)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_BaseFit)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace
}  // namespace pz::records

BENCHMARK_MAIN();
