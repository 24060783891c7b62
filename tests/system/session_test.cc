// Evaluation sessions (JobSpec.external, master/session.h, svcclient/service_evaluator.h): an
// optimiser in the client process evaluates its batches on the service's workers. The results equal
// an InlineEvaluator's bit for bit with one or two workers and when a worker is killed mid-batch;
// the session shows in status (batches, evaluations) and succeeds when closed; bad requests get
// clear errors; a session whose client falls silent is cancelled.
#include <gtest/gtest.h>

#include <cstring>

#include "svcclient/service_evaluator.h"
#include "opt/inline_evaluator.h"
#include "opt/random.h"
#include "service_harness.h"
#include "kinds/kinds.h"

namespace pz::testing {
namespace {

using opt::FitnessResult;
using opt::Genome;

job::JobSpec SessionSpec(double sleep_ms = 0, int bits = 48) {
  job::JobSpec s;
  s.name = "session test";
  job::SyntheticProblem p;
  p.cost = job::SyntheticProblem::Cost::kFunction;
  p.genome_bits = bits;
  p.sleep_ms = sleep_ms;
  s.problem = p;
  return s;
}

std::vector<Genome> RandomGenomes(int n, int bits, uint64_t seed) {
  opt::Rng rng(seed);
  std::vector<Genome> g(n);
  for (auto& x : g) {
    x.bits.resize(bits);
    for (auto& b : x.bits) b = rng.Uniform01() < 0.5;
  }
  return g;
}

std::vector<FitnessResult> Inline(const job::JobSpec& spec, const std::vector<Genome>& genomes) {
  std::unique_ptr<opt::FitnessFunction> f;
  EXPECT_TRUE(kinds::All().MakeFitness(spec, &f).ok());
  opt::InlineEvaluator ev(*f, spec.limits.penalty_cost);
  std::vector<FitnessResult> out(genomes.size());
  std::vector<int> idx(genomes.size());
  ev.Evaluate({0, genomes, idx}, out);
  return out;
}

std::vector<FitnessResult> Evaluate(opt::BatchEvaluator& ev, const std::vector<Genome>& genomes) {
  std::vector<FitnessResult> out(genomes.size());
  std::vector<int> idx(genomes.size());
  for (size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<int>(i);
  ev.Evaluate({0, genomes, idx}, out);
  return out;
}

void ExpectSame(const std::vector<FitnessResult>& a, const std::vector<FitnessResult>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(std::memcmp(&a[i].cost, &b[i].cost, sizeof(double)), 0)
        << i << ": " << a[i].cost << " vs " << b[i].cost;
    EXPECT_EQ(a[i].status, b[i].status) << i;
    EXPECT_EQ(a[i].reason, b[i].reason) << i;
    EXPECT_EQ(a[i].residuals, b[i].residuals) << i;
  }
}

svcclient::ServiceEvaluatorOptions Options(const Cluster& c) {
  svcclient::ServiceEvaluatorOptions o;
  o.client.endpoint = c.client_endpoint();
  o.client.timeout_ms = 2000;
  o.client.retries = 3;
  o.batch_timeout_s = 120;
  return o;
}

service::JobInfo WaitFor(svcclient::ServiceClient& c, const std::string& id,
                         service::JobState state) {
  service::JobInfo info;
  for (int i = 0; i < 400; ++i) {
    EXPECT_TRUE(c.GetStatus(id, &info).ok());
    if (info.state == state) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  return info;
}

TEST(SessionTest, BitIdenticalToInlineWithOneAndTwoWorkers) {
  for (int workers : {1, 2}) {
    SCOPED_TRACE(std::to_string(workers) + " workers");
    Cluster cluster("session" + std::to_string(workers));
    for (int w = 0; w < workers; ++w) cluster.AddWorker(2);
    const job::JobSpec spec = SessionSpec();
    std::string id;
    {
      svcclient::ServiceEvaluator ev(Options(cluster), spec, "session test");
      id = ev.job_id();
      for (uint64_t b = 0; b < 4; ++b) {
        const auto genomes = RandomGenomes(17 + static_cast<int>(b) * 30, 48, 100 + b);
        ExpectSame(Evaluate(ev, genomes), Inline(spec, genomes));
      }
      EXPECT_GE(ev.concurrency(), 1);
      auto client = cluster.Client();
      service::JobInfo info;
      ASSERT_TRUE(client.GetStatus(id, &info).ok());
      EXPECT_EQ(info.state, service::JobState::kRunning);
      EXPECT_EQ(info.algorithm, "external");
      EXPECT_EQ(info.kind, "synthetic");
      EXPECT_EQ(info.generation, 4u);  // batches
      EXPECT_EQ(info.evaluations, 17u + 47u + 77u + 107u);
    }  // closes the session
    auto client = cluster.Client();
    const service::JobInfo info = WaitFor(client, id, service::JobState::kSucceeded);
    EXPECT_EQ(info.state, service::JobState::kSucceeded) << info.message;
    std::vector<service::GenerationRecord> log;
    ASSERT_TRUE(client.Fetch(id, 1, nullptr, &log).ok());
    ASSERT_EQ(log.size(), 4u);
    EXPECT_EQ(log[3].evaluations_total, static_cast<int64_t>(info.evaluations));
  }
}

TEST(SessionTest, AWorkerKilledMidBatchGivesTheSameResults) {
  Cluster cluster("session-kill");
  cluster.AddWorker(1);
  Process& victim = cluster.AddWorker(1);
  const job::JobSpec spec = SessionSpec(/*sleep_ms=*/30);
  const auto genomes = RandomGenomes(60, 48, 7);
  svcclient::ServiceEvaluator ev(Options(cluster), spec, "kill test");
  std::thread killer([&] {
    std::this_thread::sleep_for(std::chrono::milliseconds(500));
    victim.Kill(SIGKILL);
  });
  const auto got = Evaluate(ev, genomes);
  killer.join();
  ExpectSame(got, Inline(spec, genomes));
  // The session goes on with the survivor.
  const auto more = RandomGenomes(5, 48, 8);
  ExpectSame(Evaluate(ev, more), Inline(spec, more));
}

TEST(SessionTest, BadRequestsGetClearErrors) {
  Cluster cluster("session-bad");
  cluster.AddWorker(1);
  auto client = cluster.Client();
  bool done = false;
  std::vector<FitnessResult> results;
  // Unknown job.
  Status s = client.Evaluate("jnosuchjob", 1, RandomGenomes(1, 48, 1), &done, &results);
  EXPECT_EQ(s.code(), StatusCode::kNotFound) << s.message();
  EXPECT_NE(s.message().find("jnosuchjob"), std::string::npos) << s.message();
  // A GA job is not a session.
  svcclient::SubmitResult ga;
  ASSERT_TRUE(client.Submit(SyntheticSpec(1, 8, 1000, 5), &ga).ok());
  s = client.Evaluate(ga.job_id, 1, RandomGenomes(1, 64, 1), &done, &results);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition) << s.message();
  EXPECT_NE(s.message().find("algorithm external"), std::string::npos) << s.message();
  EXPECT_EQ(client.Close(ga.job_id).code(), StatusCode::kFailedPrecondition);
  ASSERT_TRUE(client.Cancel(ga.job_id).ok());
  // A session spec without a problem, or with both algorithms, is refused field by field.
  job::JobSpec none = SessionSpec();
  none.problem = std::monostate{};
  none.external = job::ExternalSettings{};
  std::vector<job::FieldViolation> v;
  svcclient::SubmitResult r;
  EXPECT_EQ(client.Submit(none, &r, &v).code(), StatusCode::kInvalidArgument);
  ASSERT_FALSE(v.empty());
  EXPECT_EQ(v.front().field, "problem");
  // (On the wire the algorithm is a oneof: both set is a client-side mistake, caught by
  // validation.)
  job::JobSpec both = SessionSpec();
  both.external = job::ExternalSettings{};
  both.ga = job::GaSettings{};
  v = kinds::All().Validate(both);
  ASSERT_FALSE(v.empty());
  EXPECT_EQ(v.front().field, "algorithm");
  EXPECT_EQ(v.front().description, "algorithm: only one of ga, external may be set");
  // The same through the evaluator: InputError naming the field.
  try {
    svcclient::ServiceEvaluator bad(Options(cluster), none);
    ADD_FAILURE() << "a session without a problem was opened";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("problem"), std::string::npos) << e.what();
  }
  // Wrong genome length, batch_seq 0, a poll of a batch never sent.
  svcclient::ServiceEvaluator ev(Options(cluster), SessionSpec());
  s = client.Evaluate(ev.job_id(), 1, RandomGenomes(2, 47, 1), &done, &results);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("genomes[0] has 47 bits"), std::string::npos) << s.message();
  EXPECT_NE(s.message().find("48 bits"), std::string::npos) << s.message();
  s = client.Evaluate(ev.job_id(), 0, RandomGenomes(1, 48, 1), &done, &results);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find("batch_seq = 0"), std::string::npos) << s.message();
  s = client.Evaluate(ev.job_id(), 9, {}, &done, &results);
  EXPECT_EQ(s.code(), StatusCode::kNotFound);
  EXPECT_NE(s.message().find("send it with its genomes"), std::string::npos) << s.message();
  // After closing: refused; a second close is fine.
  ASSERT_TRUE(ev.Close().ok());
  WaitFor(client, ev.job_id(), service::JobState::kSucceeded);
  s = client.Evaluate(ev.job_id(), 1, RandomGenomes(1, 48, 1), &done, &results);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(s.message().find("succeeded"), std::string::npos) << s.message();
  EXPECT_TRUE(client.Close(ev.job_id()).ok());
  EXPECT_THROW(Evaluate(ev, RandomGenomes(1, 48, 1)), svcclient::ServiceError);
}

TEST(SessionTest, ASilentClientsSessionIsCancelled) {
  Cluster cluster("session-idle");
  auto o = [&] {
    svcclient::ServiceEvaluatorOptions x = Options(cluster);
    x.idle_timeout_s = 0.5;
    return x;
  }();
  svcclient::ServiceEvaluator ev(o, SessionSpec());
  auto client = cluster.Client();
  const service::JobInfo info = WaitFor(client, ev.job_id(), service::JobState::kCancelled);
  EXPECT_EQ(info.state, service::JobState::kCancelled);
  EXPECT_NE(info.message.find("idle_timeout_s"), std::string::npos) << info.message;
  EXPECT_THROW(Evaluate(ev, RandomGenomes(1, 48, 1)), svcclient::ServiceError);
}

}  // namespace
}  // namespace pz::testing
