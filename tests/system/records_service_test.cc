// Record fits on the service (issue 14): the "complete_model" job kind's RECORDS family rebuilds,
// from its spec alone (binary and JSON encodings), the fitness `piezoid fit` has — every family
// with effects, records cut at their rest, each offset mode — cost for cost, bit for bit; bad
// specs are refused field by field; and a fit whose global search runs on a local master with two
// workers gives the local result bit for bit (a swarm, and the line search of one parameter);
// `piezoid fit --family auto --master` runs the selection's fold fits and the chosen model's refit
// on the workers and writes the local run's fit.json bit for bit but for its wall time (issue 37).
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <sstream>
#include <thread>

#include "complete/job_kind.h"
#include "complete_remote.h"
#include "io/records.h"
#include "json_report.h"
#include "opt/thread_pool_evaluator.h"
#include "records/registry.h"
#include "service_harness.h"
#include "svcclient/complete_service.h"
#include "synth/synthetic.h"
#include "tests/testing/expect_error.h"

namespace pz::testing {
namespace {

using records::EffectKind;

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// Two records of backlash-like + delay: a sine after a rest (offset fit), a multisine (offset
/// rest), plus a withheld one; windows that start after the rest.
io::RecordSet MakeSet() {
  const records::DataScale s = synth::SyntheticStackScale();
  auto fam = std::shared_ptr<const records::Family>(records::MakeFamily("backlash-like", s));
  records::RecordModel truth(fam, {EffectKind::Named("delay")}, s);
  const std::vector<double> p = {0.02, 0.1, 0.05, 0.006};
  io::RecordSet set;
  set.source = "synthetic";
  for (int i = 0; i < 3; ++i) {
    synth::DriveShape d;
    d.waveform = i == 1 ? synth::Waveform::kMultisine : synth::Waveform::kSine;
    d.amplitude = 100;
    d.frequency_hz = 1;
    d.frequency_end_hz = 5;
    d.phase_rad = 0.8 + i;
    d.rest_s = 0.3;
    d.duration_s = 3;
    d.fs_hz = 500;
    d.seed = static_cast<uint64_t>(i + 1);
    io::Record r = synth::SynthesizeRecord(
        truth, p, {}, d, {-0.7, 0.02, 0.005, static_cast<uint64_t>(i + 1)}, "r" + std::to_string(i),
        i == 2 ? model::CaseRole::kValidate : model::CaseRole::kTrain, 0.5, 3.2);
    if (i == 1) {
      r.offset_mode = io::OffsetMode::kRest;
      double m = 0;
      for (size_t k = 0; k < r.rest_samples; ++k) m += r.y[k];
      r.offset = m / static_cast<double>(r.rest_samples);
    }
    set.records.push_back(std::move(r));
  }
  return set;
}

TEST(RecordsJobKindTest, TheSpecRebuildsTheRecordFitnessBitForBit) {
  const io::RecordSet set = MakeSet();
  const auto train = set.WithRole(model::CaseRole::kTrain);
  const records::DataScale scale = records::MeasureScale(train);
  struct Case {
    std::string family;
    std::vector<EffectKind> effects;
    int substeps = 2;  // a family made with other sub-steps is made so on the workers too
    int pi_operators = 12;
    model::InitialState state =
        model::InitialState::kCentred;  // the family's memory at rest travels too
  };
  for (const Case& c :
       {Case{"backlash-like", {EffectKind::Named("delay"), EffectKind::Named("drift")}},
        Case{"prandtl-ishlinskii", {EffectKind::Named("driver-lowpass")}},
        Case{"prandtl-ishlinskii", {}, 2, 7},
        Case{"duhem", {EffectKind::Named("friction"), EffectKind::Named("stiffening")}},
        Case{"stack-bouc-wen", {}}, Case{"stack-bouc-wen", {}, 5},
        Case{"preisach", {EffectKind::Named("delay")}},
        Case{"preisach", {EffectKind::Named("creep")}, 2, 9},
        Case{"asymmetric-pi", {EffectKind::Named("quadratic-drive")}},
        Case{
            "stack-bouc-wen", {EffectKind::Named("delay")}, 2, 12, model::InitialState::kDescended},
        Case{"backlash-like", {}, 2, 12, model::InitialState::kAscended},
        Case{"asymmetric-pi", {EffectKind::Named("delay")}, 2, 12, model::InitialState::kAuto},
        Case{"bw-oscillator", {}}, Case{"bw-oscillator", {EffectKind::Named("delay")}, 3}}) {
    SCOPED_TRACE(c.family + " substeps " + std::to_string(c.substeps) + " plays " +
                 std::to_string(c.pi_operators));
    records::FamilyOptions options;
    options.substeps = c.substeps;
    options.pi_operators = c.pi_operators;
    options.initial_state = c.state;
    auto fam =
        std::shared_ptr<const records::Family>(records::MakeFamily(c.family, scale, options));
    records::RecordModel model(fam, c.effects, scale);
    records::RecordFitness local(model, train);
    const job::JobSpec spec =
        complete::CompleteModelJobSpec(complete::CompleteModelProblemOf(local, options), "test");
    // The rest is cut from the records on the wire.
    const auto& problem = std::get<job::CompleteModelProblem>(spec.problem);
    EXPECT_LT(problem.records[0].input.size(), train[0]->end_scored);
    EXPECT_EQ(problem.initial_state, model::InitialStateName(c.state));
    for (bool json : {false, true}) {
      const auto remote = RemoteCompleteFitness(spec, json);
      ASSERT_TRUE(remote);
      // The workers' compute threads take lanes() genomes at a time (the bw-oscillator's four).
      EXPECT_EQ(remote->lanes(), local.lanes());
      std::vector<opt::Genome> gs;
      for (double x : {0.1, 0.37, 0.8}) {
        opt::Genome& g = gs.emplace_back();
        for (const auto& p : model.params()) g.reals.push_back(p.lower + x * (p.upper - p.lower));
        const opt::FitnessResult a = local.Evaluate(g), b = remote->Evaluate(g);
        EXPECT_TRUE(SameBits(a.cost, b.cost)) << a.cost << " vs " << b.cost;
        EXPECT_EQ(a.status, b.status);
      }
      const std::vector<const opt::Genome*> group = {&gs[0], &gs[1], &gs[2]};
      std::vector<opt::FitnessResult> many(group.size());
      remote->EvaluateMany(group, many);
      for (size_t l = 0; l < group.size(); ++l) {
        const opt::FitnessResult a = local.Evaluate(gs[l]);
        EXPECT_TRUE(SameBits(a.cost, many[l].cost))
            << "lane " << l << ": " << a.cost << " vs " << many[l].cost;
        EXPECT_EQ(a.status, many[l].status);
      }
    }
  }
}

TEST(RecordsJobKindTest, BadSpecsAreRefusedFieldByField) {
  const io::RecordSet set = MakeSet();
  const auto train = set.WithRole(model::CaseRole::kTrain);
  const records::DataScale scale = records::MeasureScale(train);
  auto fam = std::shared_ptr<const records::Family>(records::MakeFamily("backlash-like", scale));
  records::RecordModel model(fam, {}, scale);
  records::RecordFitness local(model, train);
  job::CompleteModelProblem p = complete::CompleteModelProblemOf(local, records::FamilyOptions{});
  job::JobKindRegistry registry;
  registry.Register(complete::CompleteModelJobKind());
  auto first_error = [&](job::CompleteModelProblem q) {
    job::JobSpec spec = complete::CompleteModelJobSpec(std::move(q), "bad");
    spec.external = job::ExternalSettings{};
    const auto v = registry.Validate(spec);
    return v.empty() ? std::string("<none>") : v.front().description;
  };
  EXPECT_EQ(first_error(p), "<none>");
  auto q = p;
  q.record_family = "jiles-atherton";
  PZ_EXPECT_HAS(
      first_error(q),
      "complete_model.record_family = 'jiles-atherton': --family 'jiles-atherton' is unknown");
  q = p;
  q.scale.pop_back();
  PZ_EXPECT_HAS(first_error(q), "complete_model.scale = 8 values: must hold 9");
  q = p;
  q.records[0].end_counted = q.records[0].input.size() + 1;
  PZ_EXPECT_HAS(first_error(q), "complete_model.records[0].end_counted");
  q = p;
  q.effects = {"hum"};
  PZ_EXPECT_HAS(first_error(q), "effect 'hum' is unknown");
  q = p;
  q.records[1].offset_mode = 7;
  PZ_EXPECT_HAS(first_error(q), "complete_model.records[1].offset_mode = 7: must be 0, 1 or 2");
}

TEST(RecordsServiceTest, AFitOnTheServiceIsTheLocalOneBitForBit) {
  Cluster cluster("records-fit");
  cluster.AddWorker(1);
  cluster.AddWorker(1);
  const io::RecordSet set = MakeSet();
  records::FitOptions o;
  o.family = "backlash-like";
  o.effects = {EffectKind::Named("delay")};
  o.search.repetitions = 1;
  o.search.pso.particles = 8;
  o.search.pso.iterations = 6;
  o.lm.max_iterations = 5;
  const records::FitResult local = records::FitRecords(set, o);
  svcclient::ServiceEvaluatorOptions so;
  so.client.endpoint = cluster.client_endpoint();
  so.client.timeout_ms = 2000;
  so.client.retries = 3;
  so.batch_timeout_s = 120;
  o.evaluator_factory = svcclient::RecordsServiceFactory(so, o.family_options, "test");
  records::FitResult remote;
  try {
    remote = records::FitRecords(set, o);
  } catch (const std::exception& e) {
    FAIL() << e.what() << " (see " << cluster.dir() << ")";  // keeps the logs
  }
  ASSERT_EQ(local.params.size(), remote.params.size());
  for (size_t i = 0; i < local.params.size(); ++i)
    EXPECT_TRUE(SameBits(local.params[i], remote.params[i])) << i;
  EXPECT_TRUE(SameBits(local.train_mse, remote.train_mse));
  EXPECT_EQ(local.search.evaluations, remote.search.evaluations);
  auto client = cluster.Client();
  std::vector<service::JobInfo> jobs;
  ASSERT_TRUE(client.List(&jobs).ok());
  // The search's session and the polish's (its residual vectors, "… (polish)").
  ASSERT_EQ(jobs.size(), 2u);
  int polishes = 0;
  for (const auto& j : jobs) {
    EXPECT_EQ(j.kind, "complete_model");
    EXPECT_GT(j.evaluations, 0u) << j.name;
    polishes += j.name.ends_with(" (polish)") ? 1 : 0;
  }
  EXPECT_EQ(polishes, 1);
  // One searched parameter (prandtl-ishlinskii's weights are solved): the line search, its grid and
  // then one point per bracket and step as the batches of the session, the local fit bit for bit.
  records::FitOptions line = o;
  line.family = "prandtl-ishlinskii";
  line.sizing.enabled = true;
  line.evaluator_factory = nullptr;
  const records::FitResult local_line = records::FitRecords(set, line);
  line.evaluator_factory = svcclient::RecordsServiceFactory(so, line.family_options, "test");
  records::FitResult remote_line;
  try {
    remote_line = records::FitRecords(set, line);
  } catch (const std::exception& e) {
    FAIL() << e.what() << " (see " << cluster.dir() << ")";
  }
  EXPECT_EQ(local_line.algorithm, opt::SearchAlgorithm::kLine);
  EXPECT_EQ(remote_line.algorithm, opt::SearchAlgorithm::kLine);
  ASSERT_EQ(local_line.params.size(), 1u);
  ASSERT_EQ(remote_line.params.size(), 1u);
  EXPECT_TRUE(SameBits(local_line.params[0], remote_line.params[0]));
  EXPECT_TRUE(SameBits(local_line.train_mse, remote_line.train_mse));
  EXPECT_EQ(local_line.search.evaluations, remote_line.search.evaluations);
  EXPECT_EQ(local_line.search.trace.best_cost, remote_line.search.trace.best_cost);
}

// `piezoid fit --family auto --master ENDPOINT` (issue 37): the screening's and the finalists'
// fold fits and the chosen model's refit search on the workers (one evaluation session each), and
// the choice, every CV figure, the parameters and weights — the whole fit.json but its wall time —
// are the local run's bit for bit (the local run's folds side by side on 2 threads, the service
// run's one after another). A small grid: backlash-like and prandtl-ishlinskii of 8 plays, each
// with the default effect sets (none, delay, creep, creep + delay): swarms, the line search of one
// parameter (prandtl-ishlinskii + delay) and nothing searched (prandtl-ishlinskii alone); 3 folds,
// 2 finalists.
TEST(RecordsServiceTest, AnAutoFamilyFitWithMasterWritesTheLocalFitJsonBitForBit) {
  Cluster cluster("records-auto");
  cluster.AddWorker(1);
  cluster.AddWorker(1);
  const fs::path root = cluster.dir() / "auto";
  io::WriteRecordSet(MakeSet(), root / "records");
  auto run = [&](const std::string& out, std::vector<std::string> more, std::string* stdout_text) {
    std::vector<std::string> args = {"fit", "--records", (root / "records").string(), "--out",
                                     (root / out).string()};
    const std::string grid =
        "--family auto --auto-families backlash-like,prandtl-ishlinskii --pi-operators 8 "
        "--folds 3 --finalists 2 --lm-iterations 10 --no-figures --quiet";
    std::istringstream words(grid);
    for (std::string w; words >> w;) args.push_back(w);
    args.insert(args.end(), more.begin(), more.end());
    std::string err;
    EXPECT_EQ(RunCli(args, stdout_text, &err), 0) << err << " (see " << cluster.dir() << ")";
    // Its wall times: the one figure the service may change.
    return ReadJsonWithout(root / out / "fit.json", {"wall_time_s"});
  };
  std::string local_out, service_out;
  const google::protobuf::Struct local = run("local", {"--threads", "2"}, &local_out);
  const google::protobuf::Struct service = run(
      "service", {"--master", cluster.client_endpoint(), "--timeout-ms", "2000", "--retries", "3"},
      &service_out);
  EXPECT_EQ(local_out.find("on the workers of"), std::string::npos) << local_out;
  EXPECT_NE(service_out.find("(search and polish on the workers of " + cluster.client_endpoint()),
            std::string::npos)
      << service_out;
  // The choice and the CV figures, then the chosen model (its parameters and weights), then the
  // rest.
  ASSERT_TRUE(local.fields().contains("selection"));
  ASSERT_TRUE(service.fields().contains("selection"));
  const auto& ls = local.fields().at("selection").struct_value().fields();
  const auto& ss = service.fields().at("selection").struct_value().fields();
  for (const char* key : {"chosen", "best_cv_rmse", "ranking", "initial_states", "fold_fits"}) {
    ASSERT_TRUE(ls.contains(key)) << key;
    ASSERT_TRUE(ss.contains(key)) << key;
    ExpectSameJson(ls.at(key), ss.at(key), std::string("selection.") + key);
  }
  const auto& ranking = ls.at("ranking").list_value().values();
  ASSERT_GE(ranking.size(), 4u);
  size_t finite = 0;
  for (const auto& r : ranking) {
    const auto& f = r.struct_value().fields();
    if (f.contains("cv_rmse") && f.at("cv_rmse").has_number_value() &&
        std::isfinite(f.at("cv_rmse").number_value()) && f.at("cv_rmse").number_value() > 0)
      ++finite;
  }
  EXPECT_GE(finite, 4u);  // the figures compared are the CV's, not missing ones
  for (const char* key : {"model", "train_mse", "records", "search"}) {
    ASSERT_TRUE(local.fields().contains(key)) << key;
    ASSERT_TRUE(service.fields().contains(key)) << key;
    ExpectSameJson(local.fields().at(key), service.fields().at(key), key);
  }
  EXPECT_GT(
      local.fields().at("model").struct_value().fields().at("params").list_value().values_size(),
      0);
  ExpectSameJson(local, service, "fit.json");
  // The searches ran on the workers: one session per fit that searches (the folds' and the
  // refit's), each named for the selection; the chosen model's refit among them.
  auto client = cluster.Client();
  std::vector<service::JobInfo> jobs;
  ASSERT_TRUE(client.List(&jobs).ok());
  std::map<std::string, int> per_model;
  size_t searches = 0, polishes = 0;  // the polishes' sessions: their residual vectors
  for (const auto& j : jobs) {
    EXPECT_EQ(j.kind, "complete_model");
    EXPECT_EQ(j.name.rfind("piezoid fit --family auto: ", 0), 0u) << j.name;
    EXPECT_GT(j.evaluations, 0u) << j.name;
    if (j.name.ends_with(" (polish)")) {
      ++polishes;
      continue;
    }
    ++searches;
    ++per_model[j.name.substr(0, j.name.rfind(" on "))];
  }
  std::printf("%zu search session(s), %zu polish session(s)\n", searches, polishes);
  EXPECT_GT(polishes, 0u);
  for (const auto& [name, n] : per_model) std::printf("%d session(s): %s\n", n, name.c_str());
  // 8 of the grid's candidates search (prandtl-ishlinskii, alone or with the creep spectrum,
  // solves its weights; with a delay it searches): 8 × 3 screening folds, 2 finalists × 3 folds,
  // and the 2 finalists' refits on every training record.
  EXPECT_EQ(searches, 8u * 3 + 2 * 3 + 2);
  // The chosen model: its 3 screening folds, its 3 final folds and its refit, whose session
  // evaluated the whole global search of fit.json.
  const auto& model = local.fields().at("model").struct_value().fields();
  std::string chosen = "piezoid fit --family auto: " + model.at("family").string_value();
  for (const auto& e : model.at("effects").list_value().values())
    chosen += " + " + e.string_value();
  EXPECT_EQ(per_model[chosen], 7) << chosen;
  const double searched =
      local.fields().at("search").struct_value().fields().at("search_evaluations").number_value();
  EXPECT_GT(searched, 0);
  bool refit = false;
  for (const auto& j : jobs)
    refit = refit || (j.name == chosen + " on 2 record(s)" &&
                      static_cast<double>(j.evaluations) == searched);
  EXPECT_TRUE(refit) << chosen << ": no session of " << searched
                     << " evaluations on the 2 training records";
}

/// A records fit's evaluator that takes the genomes one at a time on two threads: the fitness's
/// lanes hidden (how the workers evaluated before they took lanes() genomes at a time).
class OneAtATimeEvaluator final : public opt::BatchEvaluator {
 public:
  OneAtATimeEvaluator(const records::RecordFitness& f, records::RecordEvaluation e)
      : residuals_(f),
        single_(e == records::RecordEvaluation::kResiduals
                    ? static_cast<const opt::FitnessFunction&>(residuals_)
                    : f),
        pool_(single_, 2) {}
  void Evaluate(const opt::EvalBatch& batch, std::span<opt::FitnessResult> out) override {
    pool_.Evaluate(batch, out);
  }

 private:
  records::RecordResidualFitness residuals_;
  struct Single final : opt::FitnessFunction {
    explicit Single(const opt::FitnessFunction& f) : f(f) {}
    opt::FitnessResult Evaluate(const opt::Genome& g) const override { return f.Evaluate(g); }
    const opt::FitnessFunction& f;
  } single_;
  opt::ThreadPoolEvaluator pool_;
};

// The bw-oscillator runs four genomes side by side (RecordFitness::lanes): a fit whose search runs
// on workers of two threads and of one, which take four genomes of a lease at a time, is the local
// fit (a thread pool taking four at a time) bit for bit, and the fit whose evaluations are taken
// one at a time (the workers before they took lanes). 10 particles: groups of 4, 4 and 2 where a
// lease holds them all, shorter ones where the master splits them.
/// A bw-oscillator + delay fit's options (10 particles: groups of 4, 4 and 2 where a lease holds
/// a whole swarm, shorter ones where the master splits it).
records::FitOptions BwFitOptions(int iterations) {
  records::FitOptions o;
  o.family = "bw-oscillator";
  o.effects = {EffectKind::Named("delay")};
  o.search.repetitions = 2;
  o.search.pso.particles = 10;
  o.search.pso.iterations = iterations;
  o.lm.max_iterations = 5;
  return o;
}

records::RecordEvaluatorFactory ServiceFactory(const Cluster& cluster,
                                               const records::FitOptions& o) {
  svcclient::ServiceEvaluatorOptions so;
  so.client.endpoint = cluster.client_endpoint();
  so.client.timeout_ms = 2000;
  so.client.retries = 3;
  so.batch_timeout_s = 120;
  return svcclient::RecordsServiceFactory(so, o.family_options, "test");
}

void ExpectSameFit(const records::FitResult& want, const records::FitResult& got) {
  ASSERT_EQ(want.params.size(), got.params.size());
  for (size_t i = 0; i < want.params.size(); ++i)
    EXPECT_TRUE(SameBits(want.params[i], got.params[i])) << i;
  EXPECT_TRUE(SameBits(want.train_mse, got.train_mse)) << want.train_mse << " vs " << got.train_mse;
  EXPECT_EQ(want.search.evaluations, got.search.evaluations);
}

// The bw-oscillator runs four genomes side by side (RecordFitness::lanes): a fit whose search runs
// on workers of two threads and of one, which take four genomes of a lease at a time, is the local
// fit (a thread pool taking four at a time) bit for bit, and the fit whose evaluations are taken
// one at a time (the workers before they took lanes).
TEST(RecordsServiceTest, ABwOscillatorFitOnWorkersTakingFourGenomesAtATimeIsTheLocalOneBitForBit) {
  Cluster cluster("records-bw-fit");
  cluster.AddWorker(2);
  cluster.AddWorker(1);
  const io::RecordSet set = MakeSet();
  records::FitOptions o = BwFitOptions(8);
  const records::FitResult local = records::FitRecords(set, o);
  ASSERT_EQ(local.params.size(), 7u);
  o.evaluator_factory = [](const records::RecordFitness& f,
                           records::RecordEvaluation e) -> std::unique_ptr<opt::BatchEvaluator> {
    EXPECT_EQ(f.lanes(), 4);
    return std::make_unique<OneAtATimeEvaluator>(f, e);
  };
  {
    SCOPED_TRACE("one at a time");
    ExpectSameFit(local, records::FitRecords(set, o));
  }
  o.evaluator_factory = ServiceFactory(cluster, o);
  try {
    SCOPED_TRACE("on the service");
    const records::FitResult remote = records::FitRecords(set, o);
    ExpectSameFit(local, remote);
    EXPECT_EQ(local.evaluations, remote.evaluations);
    EXPECT_EQ(local.lm_iterations, remote.lm_iterations);
  } catch (const std::exception& e) {
    FAIL() << e.what() << " (see " << cluster.dir() << ")";  // keeps the logs
  }
  // The search was one session, the polish another (its residual vectors, "… (polish)"): every
  // evaluation of both on the workers.
  auto client = cluster.Client();
  std::vector<service::JobInfo> jobs;
  ASSERT_TRUE(client.List(&jobs).ok());
  uint64_t search = 0, polish = 0;
  for (const auto& j : jobs) (j.name.ends_with(" (polish)") ? polish : search) += j.evaluations;
  EXPECT_EQ(search, static_cast<uint64_t>(local.search.evaluations));
  EXPECT_GT(local.lm_iterations, 0);
  EXPECT_EQ(polish, static_cast<uint64_t>(local.evaluations - local.search.evaluations));
}

/// A service evaluator that kills one of the cluster's workers (SIGKILL, at random) 1 ms into
/// every third batch, while its leases are out, and starts a replacement of `threads` threads.
class ChurningEvaluator final : public opt::BatchEvaluator {
 public:
  ChurningEvaluator(std::unique_ptr<opt::BatchEvaluator> inner, Cluster& cluster, int threads,
                    int* kills)
      : inner_(std::move(inner)), cluster_(cluster), threads_(threads), kills_(kills) {}
  void Evaluate(const opt::EvalBatch& batch, std::span<opt::FitnessResult> out) override {
    std::thread killer;
    if (batches_++ % 3 == 1) {
      killer = std::thread([this] {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
        auto& ws = cluster_.workers();
        const size_t victim = rng_() % ws.size();
        ws[victim]->Kill(SIGKILL);
        ws.erase(ws.begin() + static_cast<long>(victim));
        cluster_.AddWorker(threads_);
        ++*kills_;
      });
    }
    try {
      inner_->Evaluate(batch, out);
    } catch (...) {
      if (killer.joinable()) killer.join();
      throw;
    }
    if (killer.joinable()) killer.join();
  }
  int concurrency() const override { return inner_->concurrency(); }

 private:
  std::unique_ptr<opt::BatchEvaluator> inner_;
  Cluster& cluster_;
  int threads_;
  int* kills_;
  int batches_ = 0;
  std::mt19937 rng_{5};
};

// Workers that die holding groups of a lease change nothing: the same fit, while one of three
// 2-thread workers is killed 1 ms into every third batch of the search and replaced. (50 RK4
// steps per sample: evaluations of milliseconds, so the kill lands while the leases are out.)
TEST(RecordsServiceTest, ABwOscillatorFitIsBitIdenticalUnderWorkerChurn) {
  Cluster cluster("records-bw-churn");
  for (int i = 0; i < 3; ++i) cluster.AddWorker(2);
  const io::RecordSet set = MakeSet();
  records::FitOptions o = BwFitOptions(12);
  o.family_options.substeps = 50;
  const records::FitResult local = records::FitRecords(set, o);
  int kills = 0;
  const records::RecordEvaluatorFactory service = ServiceFactory(cluster, o);
  o.evaluator_factory = [&](const records::RecordFitness& f,
                            records::RecordEvaluation e) -> std::unique_ptr<opt::BatchEvaluator> {
    return std::make_unique<ChurningEvaluator>(service(f, e), cluster, 2, &kills);
  };
  records::FitResult remote;
  try {
    remote = records::FitRecords(set, o);
  } catch (const std::exception& e) {
    FAIL() << e.what() << " (see " << cluster.dir() << ")";  // keeps the logs
  }
  std::printf("%d workers killed during the fit\n", kills);
  EXPECT_GE(kills, 8);
  ExpectSameFit(local, remote);
}

}  // namespace
}  // namespace pz::testing
