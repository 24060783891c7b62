// The fin's refinement of a beam model by the records engine (records/fit.h FitOptions::beam:
// bimorph-fin's bench form with hinge-friction, every run on CVODE; no search, a
// Levenberg–Marquardt polish from each of two starts, forward differences), on the bundled nominal
// bench: locally on two threads, and with the polishes' residual vectors on a piezoid-master's
// workers (svcclient/complete_service.h RecordsServiceFactory; the master's client endpoint in
// PIEZOID_BENCH_MASTER, else that case is skipped). Both give the same fit bit for bit
// (tests/system/fin_records_service_test.cc); the figure is the wall of each.
//
//   BM_BeamRefinement/local     2 threads
//   BM_BeamRefinement/service   the master's workers (bench/fin_refine_service.sh starts a local
//                               master with 2 workers of 1 thread)
//
// Figures and the command: the closing note (issue 38).
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <string>
#include <vector>

#include "io/bench_data.h"
#include "io/fin_records.h"
#include "records/fit.h"
#include "records/registry.h"
#include "svcclient/complete_service.h"

namespace pz::records {
namespace {

const io::RecordSet& Records() {
  static const io::RecordSet set = io::RecordsFromCaseSet(
      io::LoadCaseSet(std::string(PIEZOID_DATA_DIR) + "/bimorph-fin/nominal"));
  return set;
}

// The refinement's options: from a base point near a fit of the nominal bench (the unit point of
// bench_fin_records.cc), the hinge's parameters at the middle of their box, `lm` iterations.
FitOptions Refinement(int lm) {
  FitOptions o;
  o.family = "bimorph-fin";
  o.family_options.bench_form = true;
  o.effects = {model::EffectKind::Named("hinge-friction")};
  o.uncertainty = false;
  o.threads = 2;
  o.lm.threads = 2;
  o.beam.lm_iterations = lm;
  const std::vector<const io::Record*> train = Records().WithRole(model::CaseRole::kTrain);
  const DataScale scale = MeasureScale(train);
  const RecordModel base(MakeFamily("bimorph-fin", scale, o.family_options), {}, scale);
  const std::vector<double> unit = {0.25, 0.1, 0.4, 0.6, 0.7, 0.1, 0.05};
  o.polish_from = RecordMap(base).ToPhysical(unit);
  const RecordModel beam(MakeFamily("bimorph-fin", scale, o.family_options), o.effects, scale);
  for (size_t i = o.polish_from.size(); i < beam.params().size(); ++i)
    o.polish_from.push_back(0.5 * (beam.params()[i].lower + beam.params()[i].upper));
  return o;
}

void BM_BeamRefinement(benchmark::State& state, bool service) {
  FitOptions o = Refinement(static_cast<int>(state.range(0)));
  if (service) {
    const char* ep = std::getenv("PIEZOID_BENCH_MASTER");
    if (ep == nullptr || *ep == '\0') {
      state.SkipWithError("PIEZOID_BENCH_MASTER (a master's client endpoint) is not set");
      return;
    }
    svcclient::ServiceEvaluatorOptions so;
    so.client.endpoint = ep;
    so.batch_timeout_s = 600;
    o.evaluator_factory = svcclient::RecordsServiceFactory(so, o.family_options, "bench");
  }
  for (auto _ : state) {
    const FitResult r = FitRecords(Records(), o);
    state.counters["evaluations"] = static_cast<double>(r.evaluations);
    state.counters["lm_iterations"] = r.lm_iterations;
    state.counters["train_sse"] = r.train_sse;
  }
}

BENCHMARK_CAPTURE(BM_BeamRefinement, local, false)
    ->Arg(3)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_BeamRefinement, service, true)
    ->Arg(3)
    ->Iterations(1)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace pz::records

BENCHMARK_MAIN();
