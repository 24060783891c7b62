// Complete models on the service (issue 7): the "complete_model" job kind rebuilds, from its spec
// alone, the fitness the client has (Bouc–Wen oscillator; the records engine's criterion fitness of
// the committee, both stack families, every criterion: costs bit for bit, through the binary and
// the JSON encodings); bad specs are refused field by field; and PSO / GA searches whose
// evaluations run as evaluation sessions on a local master with two workers (one of them killed
// mid-run) give the local thread-pool run's results bit for bit, for the Bouc–Wen searches and the
// committee machine, and so do the commands `piezoid boucwen
// --master` and `piezoid committee --master` on the bundled data.
#include <google/protobuf/struct.pb.h>
#include <google/protobuf/util/json_util.h>
#include <google/protobuf/util/message_differencer.h>
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <random>
#include <thread>

#include "complete/committee.h"
#include "svcclient/complete_service.h"
#include "svcclient/service_evaluator.h"
#include "complete/job_kind.h"
#include "model/stack_models.h"
#include "opt/random.h"
#include "opt/thread_pool_evaluator.h"
#include "records/registry.h"
#include "complete_remote.h"
#include "json_report.h"
#include "service_harness.h"
#include "kinds/kinds.h"

namespace pz::testing {
namespace {

using complete::BwTraining;
using job::CompleteModelProblem;
using records::Criterion;
using records::CriterionFitness;

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

// A periodic multisine force of `periods` × period samples at 750 Hz and the true oscillator's
// response with a little deterministic noise; the first `warmup` samples are not counted.
io::Record OscillatorRecord(const std::string& name, size_t period, int periods, size_t warmup,
                            unsigned seed) {
  model::BwInputOptions input;
  input.sample_rate_hz = 750;
  input.substeps = 4;
  input.interpolation = model::InputInterpolation::kPeriodicFourier;
  input.period_samples = period;
  std::vector<double> u, y;
  std::mt19937 rng(seed);
  std::vector<double> phase(12);
  for (double& p : phase) p = 2 * std::numbers::pi * (rng() / 4294967296.0);
  for (size_t k = 0; k < period * static_cast<size_t>(periods); ++k) {
    double x = 0;
    for (size_t l = 0; l < phase.size(); ++l)
      x += 15 *
           std::sin(2 * std::numbers::pi * static_cast<double>((l + 1) * (k % period)) / period +
                    phase[l]);
    u.push_back(x);
  }
  y.resize(u.size());
  EXPECT_TRUE(model::SimulateBw(model::BwParams{}, model::BwInput(u, input), y).ok());
  for (double& v : y) v += 1e-6 * (rng() / 4294967296.0 - 0.5);
  return complete::MakeBwRecord(name, model::CaseRole::kTrain, std::move(u), std::move(y), warmup);
}

// The benchmark's protocol on two small periodic records (4 RK4 sub-steps, Fourier input).
std::unique_ptr<BwTraining> SmallOscillator() {
  std::vector<io::Record> records;
  records.push_back(OscillatorRecord("A", 256, 2, 0, 1));
  records.push_back(OscillatorRecord("B", 256, 2, 256, 2));
  return std::make_unique<BwTraining>(
      std::move(records), complete::BwProtocol(4, model::InputInterpolation::kPeriodicFourier, 256),
      1.0);
}

io::Record StackRecord(int number, double f, double amp, model::CaseRole role, unsigned seed) {
  io::Record r;
  r.name = "record" + std::to_string(number);
  r.frequency_hz = f;
  r.role = role;
  r.dt = 1 / 5000.0;
  r.offset_mode = io::OffsetMode::kFixed;
  r.rest_samples = 1;
  for (int k = 0; k < 600; ++k) {
    r.t.push_back(k * r.dt);
    r.u.push_back(400 + amp * std::sin(2 * std::numbers::pi * f * k * r.dt));
  }
  r.end_scored = r.t.size();
  r.y.resize(r.u.size());
  model::SimulateStackBoucWen({0.3, 0.004, 0.002, 0.05, 400}, r.u, r.dt, r.y);
  std::mt19937 rng(seed);
  for (double& y : r.y) y += 0.02 * (rng() / 4294967296.0 - 0.5);
  return r;
}

io::RecordSet StackSet() {
  io::RecordSet set;
  set.source = "synthetic";
  set.records.push_back(StackRecord(1, 40, 400, model::CaseRole::kTrain, 1));
  set.records.push_back(StackRecord(2, 40, 300, model::CaseRole::kTest, 2));
  set.records.push_back(StackRecord(3, 60, 350, model::CaseRole::kTrain, 3));
  set.records.push_back(StackRecord(4, 60, 250, model::CaseRole::kTest, 4));
  return set;
}

// A committee fitness of a family on the set's training records (the model kept alive with it).
struct StackFitness {
  std::shared_ptr<records::RecordModel> model;
  std::unique_ptr<CriterionFitness> fitness;
  records::FamilyOptions options;
};
StackFitness MakeStackFitness(const io::RecordSet& set, const std::string& family, Criterion c,
                              double t0, double t1, int substeps = 2) {
  StackFitness f;
  const auto train = set.WithRole(model::CaseRole::kTrain);
  const records::DataScale scale = records::MeasureScale(train);
  f.options.substeps = substeps;
  f.model = std::make_shared<records::RecordModel>(records::MakeFamily(family, scale, f.options),
                                                   std::vector<records::EffectKind>{}, scale);
  f.fitness =
      std::make_unique<CriterionFitness>(*f.model, train, records::CriterionOptions{c, t0, t1});
  return f;
}

void ExpectSameFitness(const opt::FitnessFunction& local, const opt::FitnessFunction& remote,
                       const std::vector<std::vector<double>>& points) {
  for (const auto& p : points) {
    opt::Genome g;
    g.reals = p;
    const opt::FitnessResult a = local.Evaluate(g), b = remote.Evaluate(g);
    EXPECT_TRUE(SameBits(a.cost, b.cost)) << a.cost << " vs " << b.cost;
    EXPECT_EQ(a.status, b.status);
    EXPECT_EQ(a.reason, b.reason);
  }
}

TEST(CompleteModelJobKindTest, TheSpecRebuildsTheOscillatorFitnessBitForBit) {
  const auto small = SmallOscillator();
  const BwTraining& local = *small;
  const job::JobSpec spec =
      complete::CompleteModelJobSpec(complete::CompleteModelProblemOf(local), "bw");
  const std::vector<std::vector<double>> points = {
      model::BwIdentifiable(model::BwParams{}),  // the truth: cost = the noise
      {2.5, 20, 4e4, 6e4, 700, -900},            // elsewhere
      {0.2, -1e4, 5e4, 5e4, 800, -1100},         // negative damping diverges: penalised, cost 1
      {1, 2, 3}};                                // wrong size: an error
  for (bool json : {false, true}) {
    SCOPED_TRACE(json ? "json" : "binary");
    const auto remote = RemoteCompleteFitness(spec, json);
    ASSERT_TRUE(remote);
    ExpectSameFitness(local, *remote, points);
  }
  opt::Genome g;
  g.reals = points[2];
  EXPECT_EQ(local.Evaluate(g).status, opt::FitnessStatus::kPenalized);
  job::JobKindRegistry registry;
  registry.Register(complete::CompleteModelJobKind());
  job::GenomeLayout layout;
  ASSERT_TRUE(registry.Layout(spec, &layout).ok());
  EXPECT_EQ(layout.reals, 6);
  EXPECT_EQ(layout.bits, 0);
  EXPECT_EQ(registry.Find("complete_model")
                ->describe(spec, opt::Genome{{}, {2, 10, 5e4, 5e4, 800, -1100}}),
            "m=2 c=10 k=50000 alpha=50000 beta_gamma=800 beta_delta=-1100");
}

TEST(CompleteModelJobKindTest, TheSpecRebuildsTheCommitteesFitnessBitForBit) {
  const io::RecordSet set = StackSet();
  for (const std::string family : {"stack-bouc-wen", "backlash-like"}) {
    for (Criterion c : {Criterion::kIae, Criterion::kSse, Criterion::kRmse, Criterion::kMax}) {
      SCOPED_TRACE(family + " " + records::CriterionName(c));
      const StackFitness f = MakeStackFitness(set, family, c, 0.01, 0.5, 3);
      const CriterionFitness& local = *f.fitness;
      const auto remote =
          RemoteCompleteFitness(complete::CompleteModelJobSpec(
                                    complete::CompleteModelProblemOf(local, f.options), "stack"),
                                false);
      ASSERT_TRUE(remote);
      if (family == "stack-bouc-wen")
        ExpectSameFitness(local, *remote,
                          {{0.3, 0.004, 0.002, 0.05, 400},
                           {1.5, 0.02, -0.01, 0.03, 5000},
                           {0.3, -0.05, -0.05, 0.05, 400}});
      else
        ExpectSameFitness(local, *remote,
                          {{0.012, 0.052, 0.015}, {0.5, 0.03, -0.02}, {-1, 0.05, 0.01}});
    }
  }
}

TEST(CompleteModelJobKindTest, BadSpecsAreRefusedFieldByField) {
  const io::RecordSet set = StackSet();
  const StackFitness stack = MakeStackFitness(set, "stack-bouc-wen", Criterion::kIae, 0.01, 0.5);
  const job::JobSpec stack_ok = complete::CompleteModelJobSpec(
      complete::CompleteModelProblemOf(*stack.fitness, stack.options), "ok");
  const job::JobSpec bw_ok =
      complete::CompleteModelJobSpec(complete::CompleteModelProblemOf(*SmallOscillator()), "ok");
  job::JobKindRegistry registry;
  registry.Register(complete::CompleteModelJobKind());
  auto violations = [&](job::JobSpec s) {
    s.external = job::ExternalSettings{};
    std::string all;
    for (const auto& v : registry.Validate(s)) all += v.description + "\n";
    return all;
  };
  auto expect = [&](const job::JobSpec& s, const std::string& message) {
    const std::string all = violations(s);
    EXPECT_NE(all.find(message), std::string::npos) << "wanted: " << message << "\ngot: " << all;
  };
  EXPECT_EQ(violations(stack_ok), "");
  EXPECT_EQ(violations(bw_ok), "");
  auto edit = [](job::JobSpec s, auto&& f) {
    f(std::get<CompleteModelProblem>(s.problem));
    return s;
  };
  expect(edit(stack_ok, [](auto& p) { p.records[1].input.resize(1); }),
         "complete_model.records[1].input = 1 samples: needs >= 2");
  expect(edit(stack_ok, [](auto& p) { p.records[0].output.pop_back(); }),
         "complete_model.records[0].output = 599 samples: must have as many as input (600)");
  expect(edit(stack_ok, [](auto& p) { p.records[1].input[7] = NAN; }),
         "complete_model.records[1].input[7] = nan: must be finite");
  expect(edit(stack_ok, [](auto& p) { p.records[0].output[3] = INFINITY; }),
         "complete_model.records[0].output[3] = inf: must be finite");
  expect(edit(stack_ok, [](auto& p) { p.records[0].dt_s = -5; }),
         "complete_model.records[0].dt_s = -5: must be finite and > 0");
  expect(edit(bw_ok, [](auto& p) { p.records[0].sample_rate_hz = -5; }),
         "complete_model.records[0].sample_rate_hz = -5: must be finite and > 0");
  expect(edit(stack_ok, [](auto& p) { p.family = CompleteModelProblem::Family::kUnspecified; }),
         "complete_model.family = COMPLETE_MODEL_FAMILY_UNSPECIFIED: must be");
  expect(edit(stack_ok, [](auto& p) { p.records.clear(); }),
         "complete_model.records = 0 records: at least one");
  expect(edit(stack_ok, [](auto& p) { p.t1_s = 0.005; }),
         "complete_model.t1_s = 0.0050000000000000001: must be finite and > t0_s");
  expect(edit(stack_ok, [](auto& p) { p.t0_s = 0.2; }),
         "complete_model.records[0] = ends at 0.1198");
  expect(edit(stack_ok, [](auto& p) { p.substeps = 2000; }),
         "complete_model.substeps = 2000: must be in [1, 512]");
  expect(edit(stack_ok,
              [](auto& p) {
                p.criterion = CompleteModelProblem::Criterion::kMax;
                p.t0_s = p.t1_s = 0;
              }),
         "complete_model.criterion = max: without a window (t0_s, t1_s) records are scored by the "
         "MSE");
  expect(edit(stack_ok, [](auto& p) { p.family = CompleteModelProblem::Family::kStackBoucWen; }),
         "complete_model.family = STACK_BOUC_WEN: the stack models are records families: family "
         "RECORDS");
  expect(edit(stack_ok, [](auto& p) { p.error_cost = NAN; }),
         "complete_model.error_cost = nan: must be finite and > 0");
  expect(edit(stack_ok, [](auto& p) { p.records[0].end_counted = 601; }),
         "complete_model.records[0].end_counted = 601: must be > first_counted = 0 and <= 600 "
         "samples");
  expect(edit(bw_ok, [](auto& p) { p.records[1].first_counted = 512; }),
         "complete_model.records[1].first_counted = 512: leaves no counted sample of 512");
  expect(edit(bw_ok, [](auto& p) { p.period_samples = 300; }),
         "complete_model.records[0].input = 512 samples: must be a whole number of periods "
         "(period_samples = 300)");
  expect(edit(bw_ok, [](auto& p) { p.records[0].input[300] += 1; }),
         "complete_model.records[0].input[300] = ");
  expect(edit(bw_ok, [](auto& p) { p.records[0].input[300] += 1; }), ": differs from input[44] = ");
  expect(edit(bw_ok,
              [](auto& p) {
                p.period_samples = 0;
                for (auto& r : p.records) {
                  r.input.resize(1009 * 2);
                  r.output.resize(1009 * 2);
                }
              }),
         "complete_model.records[0].input = 2018 samples per period: has the prime factor 1009 > "
         "1000");
  expect(edit(stack_ok,
              [](auto& p) { p.interpolation = CompleteModelProblem::Interpolation::kFourier; }),
         "complete_model.interpolation = fourier: only the oscillator's input is interpolated");
  expect(edit(stack_ok, [](auto& p) { p.period_samples = 10; }),
         "complete_model.period_samples = 10: only the oscillator's FOURIER input has periods");
  expect(edit(bw_ok, [](auto& p) { p.t1_s = 2; }),
         "complete_model.t0_s = 0, t1_s = 2: the oscillator has no window");
  expect(edit(bw_ok, [](auto& p) { p.substeps = 1001; }),
         "complete_model.substeps = 1001: must be in [1, 1000]");
  job::JobSpec with_ga = bw_ok;
  with_ga.ga = job::GaSettings{};
  EXPECT_NE(registry.Validate(with_ga).at(0).description.find(
                "ga: the project GA searches binary genomes"),
            std::string::npos);
  // An unknown enum value on the wire is named too.
  job::JobSpec decoded;
  std::vector<job::FieldViolation> v;
  std::string json = service::JobSpecToJson(bw_ok);
  const std::string family = "\"COMPLETE_MODEL_FAMILY_BW_OSCILLATOR\"";
  ASSERT_NE(json.find(family), std::string::npos);
  json.replace(json.find(family), family.size(), "9");
  EXPECT_TRUE(service::JobSpecFromJson(json, &decoded, &v).ok());
  ASSERT_FALSE(v.empty());
  EXPECT_EQ(v[0].description,
            "complete_model.family = 9: must be BW_OSCILLATOR, STACK_BOUC_WEN, STACK_BACKLASH_LIKE "
            "or RECORDS");
}

svcclient::ServiceEvaluatorOptions Options(const Cluster& c) {
  svcclient::ServiceEvaluatorOptions o;
  o.client.endpoint = c.client_endpoint();
  o.client.timeout_ms = 2000;
  o.client.retries = 3;
  o.batch_timeout_s = 120;
  return o;
}

// Kills `victim` `after_ms` after the `at`-th batch starts, and before the (at + 2)-th batch (a
// worker lost in the middle of a search, maybe in the middle of a batch).
class KillingEvaluator final : public opt::BatchEvaluator {
 public:
  KillingEvaluator(opt::BatchEvaluator& inner, Process* victim, int at, int after_ms)
      : inner_(inner), victim_(victim), at_(at), after_ms_(after_ms) {}
  ~KillingEvaluator() override {
    if (killer_.joinable()) killer_.join();
  }
  void Evaluate(const opt::EvalBatch& batch, std::span<opt::FitnessResult> out) override {
    ++batches_;
    if (victim_ && batches_ == at_)
      killer_ = std::thread([this] {
        std::this_thread::sleep_for(std::chrono::milliseconds(after_ms_));
        victim_->Kill(SIGKILL);
      });
    if (batches_ == at_ + 2 && killer_.joinable()) killer_.join();
    inner_.Evaluate(batch, out);
  }
  int concurrency() const override { return inner_.concurrency(); }

 private:
  opt::BatchEvaluator& inner_;
  Process* victim_;
  int at_, after_ms_, batches_ = 0;
  std::thread killer_;
};

void ExpectSameSearch(const opt::SearchResult& a, const opt::SearchResult& b) {
  ASSERT_EQ(a.best.size(), b.best.size());
  for (size_t i = 0; i < a.best.size(); ++i)
    EXPECT_TRUE(SameBits(a.best[i], b.best[i])) << "best[" << i << "]";
  EXPECT_TRUE(SameBits(a.best_cost, b.best_cost)) << a.best_cost << " vs " << b.best_cost;
  EXPECT_EQ(a.evaluations, b.evaluations);
  EXPECT_EQ(a.iterations, b.iterations);
  EXPECT_EQ(a.stop_reason, b.stop_reason);
  ASSERT_EQ(a.trace.best_cost.size(), b.trace.best_cost.size());
  for (size_t i = 0; i < a.trace.best_cost.size(); ++i)
    EXPECT_TRUE(SameBits(a.trace.best_cost[i], b.trace.best_cost[i]));
}

TEST(CompleteModelServiceTest, BoucwenSearchesOnTheServiceAreTheLocalOnesBitForBit) {
  Cluster cluster("complete-bw");
  cluster.AddWorker(1);
  Process& victim = cluster.AddWorker(1);
  const auto small = SmallOscillator();
  const BwTraining& fitness = *small;
  const job::JobSpec spec =
      complete::CompleteModelJobSpec(complete::CompleteModelProblemOf(fitness), "test");
  for (opt::SearchAlgorithm algorithm :
       {opt::SearchAlgorithm::kPso, opt::SearchAlgorithm::kGaBinary}) {
    SCOPED_TRACE(opt::SearchAlgorithmName(algorithm));
    const bool kill = algorithm == opt::SearchAlgorithm::kGaBinary;
    opt::SearchOptions o;
    o.algorithm = algorithm;
    o.repetitions = 2;
    o.pso.particles = 10;
    o.pso.iterations = 6;
    o.ga_binary.ga.population_size = 10;
    o.ga_binary.ga.max_generations = 8;
    opt::ThreadPoolEvaluator pool(fitness, 2);
    const opt::SearchResult local = opt::Search(fitness.Box(), o, pool);
    svcclient::ServiceEvaluator service(Options(cluster), spec, "test");
    // With the binary GA, one of the two workers is killed during the third batch.
    KillingEvaluator ev(service, kill ? &victim : nullptr, 3, 5);
    const opt::SearchResult remote = opt::Search(fitness.Box(), o, ev);
    if (kill) {
      EXPECT_FALSE(victim.running());  // killed before the fifth of 2 x 9 batches
    }
    ExpectSameSearch(local, remote);
    EXPECT_EQ(service.evaluations(), local.evaluations);
  }
  EXPECT_FALSE(victim.running());
}

TEST(CompleteModelServiceTest, TheCommitteeOnTheServiceIsTheLocalOneBitForBit) {
  Cluster cluster("complete-committee");
  cluster.AddWorker(1);
  cluster.AddWorker(1);
  const io::RecordSet set = StackSet();
  complete::CommitteeOptions o;
  o.bands.edges = {0, 50, 100};
  o.t0_s = 0.01;
  o.t1_s = 0.12;
  o.algorithms = {opt::SearchAlgorithm::kPso, opt::SearchAlgorithm::kGaReal};
  o.search.repetitions = 1;
  o.search.pso.particles = 6;
  o.search.pso.iterations = 3;
  o.search.ga_real.population = 6;
  o.search.ga_real.generations = 3;
  const complete::CommitteeResult local =
      complete::RunCommittee(set, o, complete::LocalEvaluatorFactory(2));
  int sessions = 0;
  const complete::EvaluatorFactory service =
      svcclient::CommitteeServiceFactory(Options(cluster), o.family_options);
  const complete::CommitteeResult remote =
      complete::RunCommittee(set, o, [&](const CriterionFitness& f) {
        ++sessions;
        return service(f);
      });
  EXPECT_EQ(sessions, 12);  // (complete + 2 bands) x 2 families x 2 optimisers
  ASSERT_EQ(remote.complete.size(), local.complete.size());
  for (size_t i = 0; i < local.complete.size(); ++i)
    ExpectSameSearch(local.complete[i].search, remote.complete[i].search);
  ASSERT_EQ(remote.band_models.size(), local.band_models.size());
  for (size_t b = 0; b < local.band_models.size(); ++b)
    for (size_t i = 0; i < local.band_models[b].size(); ++i)
      ExpectSameSearch(local.band_models[b][i].search, remote.band_models[b][i].search);
  EXPECT_EQ(remote.selected, local.selected);
  EXPECT_TRUE(SameBits(remote.committee_test.rmse, local.committee_test.rmse));
  EXPECT_EQ(remote.evaluations, local.evaluations);
  auto client = cluster.Client();
  std::vector<service::JobInfo> jobs;
  ASSERT_TRUE(client.List(&jobs).ok());
  EXPECT_EQ(jobs.size(), 12u);
  for (const auto& j : jobs) EXPECT_EQ(j.kind, "complete_model");
}

// A report without what depends on the machine (wall times, rates, threads, where it ran).
google::protobuf::Struct ReadReport(const fs::path& file) {
  return ReadJsonWithout(
      file, {"wall_time_s", "threads", "evaluations_per_s", "seconds_to_final", "evaluated_on"});
}

// Same keys and values, bit for bit (numbers are printed with 17 digits).
void ExpectSameReport(const google::protobuf::Struct& a, const google::protobuf::Struct& b) {
  ExpectSameJson(a, b);
}

TEST(CompleteModelServiceTest, TheCommandsWithMasterGiveTheLocalRunsReports) {
  Cluster cluster("complete-cli");
  cluster.AddWorker(1);
  cluster.AddWorker(1);
  const fs::path root = cluster.dir() / "cli";
  auto with = [](std::vector<std::string> args, const std::vector<std::string>& more) {
    args.insert(args.end(), more.begin(), more.end());
    return args;
  };
  const std::vector<std::string> bw = {"boucwen",    "--algorithm",
                                       "pso",        "--iterations",
                                       "3",          "--population",
                                       "6",          "--repetitions",
                                       "1",          "--train-periods",
                                       "1",          "--no-plots",
                                       "--progress", "0"};
  std::string out, err;
  ASSERT_EQ(RunCli(with(bw, {"--threads", "2", "--out", (root / "bw-local").string()}), &out, &err),
            0)
      << err;
  ASSERT_EQ(RunCli(with(bw, {"--master", cluster.client_endpoint(), "--out",
                             (root / "bw-service").string()}),
                   &out, &err),
            0)
      << err;
  EXPECT_NE(out.find("worker thread(s) of " + cluster.client_endpoint()), std::string::npos) << out;
  const auto bw_local = ReadReport(root / "bw-local" / "report.json");
  EXPECT_EQ(bw_local.fields().at("evaluations").number_value(), 24);
  ExpectSameReport(ReadReport(root / "bw-service" / "report.json"), bw_local);

  const std::vector<std::string> cm = {"committee", "--bands",       "0,350",  "--optimisers",
                                       "pso",       "--repetitions", "1",      "--particles",
                                       "4",         "--iterations",  "2",      "--stall",
                                       "0",         "--no-figures",  "--quiet"};
  ASSERT_EQ(RunCli(with(cm, {"--threads", "2", "--out", (root / "cm-local").string()}), &out, &err),
            0)
      << err;
  ASSERT_EQ(RunCli(with(cm, {"--master", cluster.client_endpoint(), "--out",
                             (root / "cm-service").string()}),
                   &out, &err),
            0)
      << err;
  const auto cm_local = ReadReport(root / "cm-local" / "committee.json");
  EXPECT_EQ(cm_local.fields().at("evaluations").number_value(), 4 * 12);
  ExpectSameReport(ReadReport(root / "cm-service" / "committee.json"), cm_local);
  auto client = cluster.Client();
  std::vector<service::JobInfo> jobs;
  ASSERT_TRUE(client.List(&jobs).ok());
  EXPECT_EQ(jobs.size(), 1u + 4u);

  // A master that does not answer: exit code 3 and the command named.
  const std::string nobody = "tcp://127.0.0.1:" + std::to_string(FreePort());
  EXPECT_EQ(RunCli(with(bw, {"--master", nobody, "--timeout-ms", "200", "--retries", "1", "--out",
                             (root / "x").string()}),
                   &out, &err),
            3);
  EXPECT_NE(err.find("piezoid boucwen: error: "), std::string::npos) << err;
  EXPECT_EQ(RunCli(with(cm, {"--master", nobody, "--timeout-ms", "200", "--retries", "1", "--out",
                             (root / "y").string()}),
                   &out, &err),
            3);
  EXPECT_NE(err.find("piezoid committee: error: "), std::string::npos) << err;
  // CURVE flags as the other service commands take them: half a pair is bad input.
  EXPECT_EQ(RunCli(with(bw, {"--master", cluster.client_endpoint(), "--curve-secret",
                             (root / "me.key").string(), "--out", (root / "z").string()}),
                   &out, &err),
            2);
  EXPECT_NE(err.find("--curve-secret (or PIEZOID_CURVE_SECRET) needs --master-public"),
            std::string::npos)
      << err;
  // piezoid diagnose takes the same flags.
  EXPECT_EQ(RunCli({"diagnose", "--cases",
                    (fs::path(PIEZOID_DATA_DIR) / "bimorph-fin" / "nominal").string(), "--master",
                    cluster.client_endpoint(), "--curve-secret", (root / "me.key").string(),
                    "--out", (root / "d").string()},
                   &out, &err),
            2);
  EXPECT_NE(err.find("--curve-secret (or PIEZOID_CURVE_SECRET) needs --master-public"),
            std::string::npos)
      << err;
  EXPECT_FALSE(fs::exists(root / "d"));
}

}  // namespace
}  // namespace pz::testing
