// The fin bench fitted by the fin engine (diagnose/fin_fit.h FitGlobal over
// diagnose::DiagnosisModel) and by the records engine (records/fit.h FitRecords, bimorph-fin's
// bench form over io::RecordsFromCaseSet's records), on the bundled nominal bench
// (data/bimorph-fin/ nominal, six training cases): the two give the same fit bit for bit
// (tests/diagnose/fin_records_test.cc), so what differs is the cost of the records path's
// bookkeeping around the same simulations.
//
//   BM_Evaluation/<engine>/fast    one cost evaluation of the base model (modal path), at the same
//                                  unit point
//   BM_Evaluation/<engine>/cvode   one cost evaluation with hinge-friction (CVODE)
//   BM_Residuals/<engine>          one training residual vector of the base model (a Jacobian
//                                  column of the polish)
//   BM_RecordsSetup                what a records fit builds before it searches: the family (its
//                                  plant's FE assembly and modes), the model, the fitness
//   BM_BaseFit/<engine>            the base fit with the fin engine's budget: DE 40 × ≤ 80
//                                  generations, stall 15 (seed 7), LM ≤ 40 iterations, two threads,
//                                  no uncertainty table (the records engine builds its family's
//                                  plant in each fit, the fin engine's model is built once)
//
// Figures and the command: the closing note (issue 38).
#include <benchmark/benchmark.h>

#include <memory>
#include <string>
#include <vector>

#include "diagnose/fin_fit.h"
#include "diagnose/problem.h"
#include "io/bench_data.h"
#include "io/fin_records.h"
#include "records/fit.h"

namespace pz::records {
namespace {

using model::EffectKind;

const io::CaseSet& Bench() {
  static const io::CaseSet set =
      io::LoadCaseSet(std::string(PIEZOID_DATA_DIR) + "/bimorph-fin/nominal");
  return set;
}

const diagnose::DiagnosisModel& FinModel() {
  static const diagnose::DiagnosisModel m(std::make_shared<const model::BimorphPlant>(),
                                          diagnose::CasesFromCaseSet(Bench()));
  return m;
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

void BM_Evaluation(benchmark::State& state, const std::string& engine, bool cvode) {
  const std::vector<double> u = UnitPoint(cvode);
  opt::Genome g;
  if (engine == "fin") {
    const diagnose::DiagnosisFitness f(FinModel(), diagnose::ParameterLayout(Effects(cvode)));
    g.reals = u;
    for (auto _ : state) benchmark::DoNotOptimize(f.Evaluate(g).cost);
    return;
  }
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
void BM_Residuals(benchmark::State& state, const std::string& engine) {
  const std::vector<double> u = UnitPoint(false);
  std::vector<double> r;
  if (engine == "fin") {
    const diagnose::ParameterLayout layout({});
    const std::vector<double> x = layout.FromUnit(u);
    for (auto _ : state) benchmark::DoNotOptimize(FinModel().Residuals(layout, x, true, r));
    return;
  }
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
  d.population = 40;  // the fin engine's base fit (diagnose/fin_diagnose.h DiagnoseOptions)
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

void BM_BaseFit(benchmark::State& state, const std::string& engine) {
  for (auto _ : state) {
    if (engine == "fin") {
      diagnose::FitOptions o;
      o.threads = 2;
      o.de = De();
      o.lm = Lm();
      o.uncertainty = false;
      const diagnose::FitResult r =
          diagnose::FitGlobal(FinModel(), diagnose::ParameterLayout({}), o);
      state.counters["evaluations"] = static_cast<double>(r.evaluations);
      state.counters["train_pi"] = r.train_pi;
    } else {
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
}

BENCHMARK_CAPTURE(BM_Evaluation, fin / fast, std::string("fin"), false)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Evaluation, records / fast, std::string("records"), false)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Evaluation, fin / cvode, std::string("fin"), true)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Evaluation, records / cvode, std::string("records"), true)
    ->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Residuals, fin, std::string("fin"))->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_Residuals, records, std::string("records"))->Unit(benchmark::kMillisecond);
BENCHMARK(BM_RecordsSetup)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(BM_BaseFit, fin, std::string("fin"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_BaseFit, records, std::string("records"))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace pz::records

BENCHMARK_MAIN();
