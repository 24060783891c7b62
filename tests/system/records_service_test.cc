// Record fits on the service (issue 14): the "complete_model" job kind's RECORDS family rebuilds,
// from its spec alone (binary and JSON encodings), the fitness `piezoid fit` has — every family
// with effects, records cut at their rest, each offset mode — cost for cost, bit for bit; bad
// specs are refused field by field; and a fit whose global search runs on a local master with two
// workers gives the local result bit for bit (a swarm, and the line search of one parameter).
#include <gtest/gtest.h>

#include <cstring>

#include "client/complete_service.h"
#include "complete/job_kind.h"
#include "records/synthetic.h"
#include "complete_remote.h"
#include "service_harness.h"
#include "tests/testing/expect_error.h"

namespace pz::testing {
namespace {

using records::EffectKind;

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

/// Two records of backlash-like + delay: a sine after a rest (offset fit), a multisine (offset rest),
/// plus a withheld one; windows that start after the rest.
io::RecordSet MakeSet() {
  const records::DataScale s = records::SyntheticStackScale();
  auto fam = std::shared_ptr<const records::Family>(records::MakeFamily("backlash-like", s));
  records::RecordModel truth(fam, {EffectKind::Named("delay")}, s);
  const std::vector<double> p = {0.02, 0.1, 0.05, 0.006};
  io::RecordSet set;
  set.source = "synthetic";
  for (int i = 0; i < 3; ++i) {
    records::DriveShape d;
    d.waveform = i == 1 ? records::Waveform::kMultisine : records::Waveform::kSine;
    d.amplitude = 100;
    d.frequency_hz = 1;
    d.frequency_end_hz = 5;
    d.phase_rad = 0.8 + i;
    d.rest_s = 0.3;
    d.duration_s = 3;
    d.fs_hz = 500;
    d.seed = static_cast<uint64_t>(i + 1);
    io::Record r = records::SynthesizeRecord(truth, p, {}, d, {-0.7, 0.02, 0.005, static_cast<uint64_t>(i + 1)},
                                             "r" + std::to_string(i), i == 2 ? model::CaseRole::kValidate : model::CaseRole::kTrain,
                                             0.5, 3.2);
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
    model::InitialState state = model::InitialState::kCentred;  // the family's memory at rest travels too
  };
  for (const Case& c : {Case{"backlash-like", {EffectKind::Named("delay"), EffectKind::Named("drift")}},
                        Case{"prandtl-ishlinskii", {EffectKind::Named("driver-lowpass")}},
                        Case{"prandtl-ishlinskii", {}, 2, 7},
                        Case{"duhem", {EffectKind::Named("friction"), EffectKind::Named("stiffening")}},
                        Case{"stack-bouc-wen", {}},
                        Case{"stack-bouc-wen", {}, 5},
                        Case{"preisach", {EffectKind::Named("delay")}},
                        Case{"preisach", {EffectKind::Named("creep")}, 2, 9},
                        Case{"asymmetric-pi", {EffectKind::Named("quadratic-drive")}},
                        Case{"stack-bouc-wen", {EffectKind::Named("delay")}, 2, 12, model::InitialState::kDescended},
                        Case{"backlash-like", {}, 2, 12, model::InitialState::kAscended},
                        Case{"asymmetric-pi", {EffectKind::Named("delay")}, 2, 12, model::InitialState::kAuto}}) {
    SCOPED_TRACE(c.family + " substeps " + std::to_string(c.substeps) + " plays " + std::to_string(c.pi_operators));
    records::FamilyOptions options;
    options.substeps = c.substeps;
    options.pi_operators = c.pi_operators;
    options.initial_state = c.state;
    auto fam = std::shared_ptr<const records::Family>(records::MakeFamily(c.family, scale, options));
    records::RecordModel model(fam, c.effects, scale);
    records::RecordFitness local(model, train);
    const job::JobSpec spec = complete::CompleteModelJobSpec(complete::CompleteModelProblemOf(local, options), "test");
    // The rest is cut from the records on the wire.
    const auto& problem = std::get<job::CompleteModelProblem>(spec.problem);
    EXPECT_LT(problem.records[0].input.size(), train[0]->end_scored);
    EXPECT_EQ(problem.initial_state, model::InitialStateName(c.state));
    for (bool json : {false, true}) {
      const auto remote = RemoteCompleteFitness(spec, json);
      ASSERT_TRUE(remote);
      for (double x : {0.1, 0.37, 0.8}) {
        opt::Genome g;
        for (const auto& p : model.params()) g.reals.push_back(p.lower + x * (p.upper - p.lower));
        const opt::FitnessResult a = local.Evaluate(g), b = remote->Evaluate(g);
        EXPECT_TRUE(SameBits(a.cost, b.cost)) << a.cost << " vs " << b.cost;
        EXPECT_EQ(a.status, b.status);
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
  PZ_EXPECT_HAS(first_error(q), "complete_model.record_family = 'jiles-atherton': --family 'jiles-atherton' is unknown");
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
  client::ServiceEvaluatorOptions so;
  so.client.endpoint = cluster.client_endpoint();
  so.client.timeout_ms = 2000;
  so.client.retries = 3;
  so.batch_timeout_s = 120;
  o.evaluator_factory = client::RecordsServiceFactory(so, o.family_options, "test");
  records::FitResult remote;
  try {
    remote = records::FitRecords(set, o);
  } catch (const std::exception& e) {
    FAIL() << e.what() << " (see " << cluster.dir() << ")";  // keeps the logs
  }
  ASSERT_EQ(local.params.size(), remote.params.size());
  for (size_t i = 0; i < local.params.size(); ++i) EXPECT_TRUE(SameBits(local.params[i], remote.params[i])) << i;
  EXPECT_TRUE(SameBits(local.train_mse, remote.train_mse));
  EXPECT_EQ(local.search.evaluations, remote.search.evaluations);
  auto client = cluster.Client();
  std::vector<service::JobInfo> jobs;
  ASSERT_TRUE(client.List(&jobs).ok());
  ASSERT_EQ(jobs.size(), 1u);
  EXPECT_EQ(jobs[0].kind, "complete_model");
  // One searched parameter (prandtl-ishlinskii's weights are solved): the line search, its grid and
  // then one point per bracket and step as the batches of the session, the local fit bit for bit.
  records::FitOptions line = o;
  line.family = "prandtl-ishlinskii";
  line.sizing.enabled = true;
  line.evaluator_factory = nullptr;
  const records::FitResult local_line = records::FitRecords(set, line);
  line.evaluator_factory = client::RecordsServiceFactory(so, line.family_options, "test");
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

}  // namespace
}  // namespace pz::testing
