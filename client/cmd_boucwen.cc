// `piezoid boucwen`: complete-model identification of the Bouc–Wen benchmark oscillator (issue 7,
// data/boucwen-benchmark/README.md). The six identifiable parameters θ = (m, c, k, α, β·γ, β·δ)
// (ν = 1; β only appears in the products) are searched by PSO, the real-coded GA or the binary GA
// (opt/param_search.h) on the training records train_A and train_B, minimising the output-error
// MSE of a free-run simulation (train_A from rest; train_B, a steady-state record, after a
// one-period warm-up). The test records are read only afterwards, to report the
// simulation RMS error of the identified model (and of the true one, the floor) on the official
// multisine and sine-sweep sets (the protocol: complete/boucwen_benchmark.h). Its report.json,
// report.md, CSVs and figures: reports/boucwen_report.h.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "client/commands.h"
#include "client/data_root.h"
#include "client/service_flags.h"
#include "complete/boucwen_benchmark.h"
#include "complete/job_kind.h"
#include "io/csv.h"
#include "io/proto_json.h"
#include "model/bw_oscillator.h"
#include "model/criteria.h"
#include "opt/param_search.h"
#include "opt/thread_pool_evaluator.h"
#include "reports/boucwen_report.h"
#include "svcclient/complete_service.h"

namespace pz::client {
namespace {

using complete::kBwPeriod;
using complete::kBwSampleRateHz;
using complete::LoadBwBenchmark;
using complete::MakeBwTrainingRecord;
using complete::SimulateBwMultisineTest;
using complete::SimulateBwSweepTest;

struct BoucwenArgs {
  std::string data_dir = BundledData("boucwen-benchmark").string();
  std::string out_dir = "boucwen-out";
  std::string algorithm = "pso";
  int repetitions = 5;
  uint64_t seed = 1;
  int threads = 0;
  int iterations = -1;  // PSO iterations / GA generations; -1 = the algorithm's default below
  int population = -1;  // particles / individuals; -1 = default
  int stall = -1;
  int substeps = 4;       // RK4 steps per sample during the search
  int train_periods = 0;  // 0 = all periods of both training records
  int progress = 25;
  bool no_plots = false;
  CompleteServiceFlags service;  ///< --master: the search's evaluations on the service
};

opt::SearchOptions MakeOptions(const BoucwenArgs& a) {
  opt::SearchOptions o;
  o.algorithm = opt::ParseSearchAlgorithm(a.algorithm);
  o.repetitions = a.repetitions;
  o.pso.seed = o.ga_real.seed = o.ga_binary.ga.seed = a.seed;
  o.pso.particles = 40;
  o.pso.iterations = 400;
  o.pso.stall_iterations = 60;
  o.pso.tolerance = 1e-4;
  o.ga_real.population = 60;
  o.ga_real.generations = 400;
  o.ga_real.stall_generations = 60;
  o.ga_real.tolerance = 1e-4;
  o.ga_binary.bits_per_parameter = 24;
  o.ga_binary.ga.population_size = 60;
  o.ga_binary.ga.max_generations = 400;
  o.ga_binary.ga.stall_generations = 60;
  if (a.iterations >= 0)
    o.pso.iterations = o.ga_real.generations = o.ga_binary.ga.max_generations = a.iterations;
  if (a.population > 0)
    o.pso.particles = o.ga_real.population = o.ga_binary.ga.population_size = a.population;
  if (a.stall >= 0)
    o.pso.stall_iterations = o.ga_real.stall_generations = o.ga_binary.ga.stall_generations =
        a.stall;
  return o;
}

/// The training problem: train_A from rest and train_B after a one-period warm-up (all their whole
/// periods, or the first --train-periods), output-error MSE; a diverging simulation costs 1 m².
complete::BwTraining MakeTraining(const BoucwenArgs& a, const io::RecordSet& train) {
  auto samples_of = [&](const io::Record& r) {
    const size_t all = r.size() - r.size() % kBwPeriod;
    return a.train_periods > 0 ? std::min(all, static_cast<size_t>(a.train_periods) * kBwPeriod)
                               : all;
  };
  const io::Record& train_a = *train.Find("train_A");
  const io::Record& train_b = *train.Find("train_B");
  std::vector<io::Record> records;
  records.push_back(MakeBwTrainingRecord(train_a, samples_of(train_a), false));
  records.push_back(MakeBwTrainingRecord(train_b, samples_of(train_b), true));
  return complete::BwTraining(
      std::move(records),
      complete::BwProtocol(a.substeps, model::InputInterpolation::kPeriodicFourier, kBwPeriod),
      1.0);
}

/// What a run found and how: the search, where it ran, the benchmark's true parameters and the
/// test sets' scores (read only after the search).
/// The search on a thread pool, or with --master in one evaluation session (the spec carries the
/// records). Fills options, box, result, threads, n_train and where; a service error is printed
/// and its exit code returned.
std::optional<int> Search(const BoucwenArgs& a, const complete::BwTraining& fitness,
                          reports::BwOutcome* o) {
  o->n_train = fitness.counted_samples();
  o->box = fitness.Box();
  o->options = MakeOptions(a);
  const int progress = a.progress;
  o->options.on_progress = [progress](const opt::SearchProgress& p) {
    if (progress > 0 && p.iteration % progress == 0) {
      std::fprintf(stderr, "rep %d it %4d  evals %7lld  best rms %.4e m  overall %.4e m\n",
                   p.repetition, p.iteration, static_cast<long long>(p.evaluations),
                   std::sqrt(p.best_cost), std::sqrt(p.overall_best_cost));
    }
  };
  ThrowIfError(o->options.Validate(o->box));
  o->where =
      a.service.enabled() ? " worker thread(s) of " + a.service.master : std::string(" thread(s)");
  try {
    std::unique_ptr<opt::BatchEvaluator> evaluator;
    if (a.service.enabled()) {
      evaluator = std::make_unique<svcclient::ServiceEvaluator>(
          a.service.Options(),
          complete::CompleteModelJobSpec(
              complete::CompleteModelProblemOf(fitness),
              std::string("boucwen ") + opt::SearchAlgorithmName(o->options.algorithm)),
          "piezoid boucwen");
    } else {
      evaluator = std::make_unique<opt::ThreadPoolEvaluator>(fitness, a.threads);
    }
    std::cout << "piezoid boucwen: " << opt::SearchAlgorithmName(o->options.algorithm) << ", "
              << o->options.repetitions << " repetition(s) from seed " << a.seed << ", "
              << evaluator->concurrency() << o->where << "; training on " << o->n_train
              << " samples (train_A from rest, train_B in steady state after a one-period "
                 "warm-up), RK4 with "
              << a.substeps << " sub-steps per sample, Fourier-interpolated input" << std::endl;
    o->result = opt::Search(o->box, o->options, *evaluator);
    o->threads = evaluator->concurrency();
  } catch (const svcclient::ServiceError& e) {  // the evaluator's destructor has closed the session
    std::cerr << "piezoid boucwen: error: " << e.what() << "\n";
    return ExitCodeOf(e.status());
  }
  return std::nullopt;
}

/// The identified and the true model on the test sets (read only now), and the trace's reach.
void ScoreTests(const std::filesystem::path& data, reports::BwOutcome* o) {
  o->theta_true = model::BwIdentifiable(model::BwParams{});  // benchmark Table 1
  o->train_rms = std::sqrt(o->result.best_cost);
  const io::RecordSet test = LoadBwBenchmark(data, model::CaseRole::kTest);
  const io::Record& test_ms = *test.Find("test_multisine");
  const io::Record& test_sw = *test.Find("test_sinesweep");
  o->measured_ms = test_ms.y;
  o->measured_sw = test_sw.y;
  o->yms = SimulateBwMultisineTest(o->result.best, test_ms);
  o->ysw = SimulateBwSweepTest(o->result.best, test_sw);
  o->yms_true = SimulateBwMultisineTest(o->theta_true, test_ms);
  o->ysw_true = SimulateBwSweepTest(o->theta_true, test_sw);
  o->rms_ms = model::Rmse(test_ms.y, o->yms), o->rms_sw = model::Rmse(test_sw.y, o->ysw);
  o->rms_ms_true = model::Rmse(test_ms.y, o->yms_true),
  o->rms_sw_true = model::Rmse(test_sw.y, o->ysw_true);
  o->max_ms = model::MaxAbsError(test_ms.y, o->yms, 1 / kBwSampleRateHz, 0,
                                 (test_ms.y.size() - 1) / kBwSampleRateHz);
  o->max_sw = model::MaxAbsError(test_sw.y, o->ysw, 1 / kBwSampleRateHz, 0,
                                 (test_sw.y.size() - 1) / kBwSampleRateHz);
  const auto& best_cost = o->result.trace.best_cost;
  o->reach = 0;
  while (o->reach + 1 < best_cost.size() && best_cost[o->reach] > o->result.best_cost * 1.01)
    ++o->reach;
}

int RunBoucwen(const BoucwenArgs& a) {
  namespace fs = std::filesystem;
  const fs::path data(a.data_dir), out(a.out_dir);
  CheckBundledData(data, "boucwen-benchmark", "--data-dir DIR");
  const complete::BwTraining fitness =
      MakeTraining(a, LoadBwBenchmark(data, model::CaseRole::kTrain));
  reports::BwOutcome o;
  if (const std::optional<int> code = Search(a, fitness, &o)) return *code;
  ScoreTests(data, &o);
  reports::PrintBoucwenSummary(std::cout, o);
  const reports::BoucwenRun run{.seed = a.seed,
                                .on_service = a.service.enabled(),
                                .substeps = a.substeps,
                                .plots = !a.no_plots};
  for (const auto& w : reports::WriteBoucwenReport(out, run, o))
    std::cerr << "piezoid boucwen: warning: " << w << "\n";
  std::cout << "report: " << (out / "report.md").string() << ", " << (out / "report.json").string()
            << std::endl;
  return 0;
}

}  // namespace

void RegisterBoucwen(CLI::App& app, int& exit_code) {
  auto a = std::make_shared<BoucwenArgs>();
  CLI::App* cmd = app.add_subcommand("boucwen",
                                     "Bouc-Wen benchmark (Noel & Schoukens): identify (m, c, k, "
                                     "alpha, beta*gamma, beta*delta) from the training "
                                     "records by PSO or a GA, then report the simulation RMS error "
                                     "on the official multisine and sine-sweep "
                                     "test sets.");
  cmd->add_option("--algorithm", a->algorithm, "pso, ga-real or ga-binary")
      ->check(CLI::IsMember({"pso", "ga-real", "ga-binary"}))
      ->capture_default_str();
  cmd->add_option("--repetitions", a->repetitions,
                  "runs with seeds seed, seed+1, ...; the best is kept")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--seed", a->seed, "seed of the first repetition")->capture_default_str();
  cmd->add_option("--threads", a->threads, "evaluator threads (0 = all cores)")
      ->check(CLI::Range(0, 256))
      ->capture_default_str();
  cmd->add_option("--iterations", a->iterations,
                  "PSO iterations / GA generations per repetition (default 400)")
      ->check(CLI::Range(0, 100000000));
  cmd->add_option("--population", a->population, "particles / individuals (default 40 PSO, 60 GA)")
      ->check(CLI::Range(2, 1000000));
  cmd->add_option("--stall", a->stall,
                  "stop a repetition after this many iterations without a 1e-4 relative "
                  "improvement (default 60; 0 = never)")
      ->check(CLI::Range(0, 100000000));
  cmd->add_option("--substeps", a->substeps, "RK4 steps per sample during the search")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--train-periods", a->train_periods,
                  "use only the first N 8192-sample periods of each training record (0 = all)")
      ->check(CLI::Range(0, 1000))
      ->capture_default_str();
  cmd->add_option("--data-dir", a->data_dir,
                  std::string("folder with the benchmark CSVs; default under ") + kDataRootHelp)
      ->capture_default_str();
  cmd->add_option("--out", a->out_dir, "output folder (report.json, report.md, CSVs, figures)")
      ->capture_default_str();
  cmd->add_option("--progress", a->progress, "print every N-th iteration to stderr (0 = none)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_flag("--no-plots", a->no_plots, "do not write or render gnuplot figures");
  AddCompleteServiceFlags(cmd, a->service);
  cmd->callback([a, &exit_code] { exit_code = RunBoucwen(*a); });
}

}  // namespace pz::client
