// The diagnosis on the service: `piezoid diagnose --cases --master` (the records engine,
// DiagnoseBench, every fit's evaluations as complete_model sessions) equals the local run bit for
// bit; a master given a spec of the removed "diagnose" kind (the fin engine's fits, proto tag 13
// now reserved) refuses it, naming the kind.
#include <gtest/gtest.h>

#include <cstring>
#include <zmq.hpp>

#include "diagnose/fin_diagnose.h"
#include "io/fin_records.h"
#include "service/wire_codec.h"
#include "svcclient/complete_service.h"
#include "synth/synthetic.h"
#include "tests/system/service_harness.h"
#include "wire.pb.h"

namespace pz::diagnose {
namespace {

using model::EffectKind;

io::RecordSet SmallBench(bool with_delay) {
  const model::BimorphPlant plant;
  synth::FinTrialOptions so;
  model::BimorphParams p;
  std::vector<std::pair<double, double>> sat;
  for (double v : {375.0, 500.0, 750.0})
    for (double f : {0.25, 0.5, 1.0})
      sat.push_back({0.0065 * v - 0.85 * f - 0.63, -0.0062 * v + 0.68 * f + 0.71});
  opt::Rng rng(3);
  std::vector<records::Effect> effects;
  if (with_delay) effects = {{EffectKind::Named("delay"), {0.02}}};
  return io::RecordsFromCaseSet(synth::SimulateBench(plant, p, effects, sat, so, rng));
}

bool SameBits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void ExpectSameVector(const std::vector<double>& a, const std::vector<double>& b,
                      const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i)
    EXPECT_TRUE(SameBits(a[i], b[i])) << what << "[" << i << "]: " << a[i] << " vs " << b[i];
}

// A small diagnosis: two candidates (a drive effect, a beam effect on CVODE), small searches.
DiagnoseOptions SmallOptions() {
  DiagnoseOptions o;
  o.candidates = {EffectKind::Named("delay"), EffectKind::Named("cubic-stiffening")};
  o.de_base.population = 12;
  o.de_base.generations = 8;
  o.de_candidate.population = 12;
  o.de_candidate.generations = 5;
  o.lm.max_iterations = 6;
  o.cvode_lm_iterations = 2;
  o.cvode_start_fractions = {0.05};
  o.second_effect = false;
  o.trends = false;
  return o;
}

svcclient::ServiceEvaluatorOptions ServiceOptions(testing::Cluster& cluster) {
  svcclient::ServiceEvaluatorOptions so;
  so.client.endpoint = cluster.client_endpoint();
  so.client.timeout_ms = 2000;
  so.client.retries = 3;
  so.batch_timeout_s = 300;
  return so;
}

// piezoid diagnose --cases --master: the records engine (DiagnoseBench) with every fit's search as
// a complete_model session (bimorph-fin's bench form on the workers) gives the local diagnosis
// bit for bit.
TEST(DiagnoseServiceTest, TheRecordsEngineOnTheServiceIsTheLocalOneBitForBit) {
  testing::Cluster cluster("diagnose-records-service");
  cluster.AddWorker(1);
  cluster.AddWorker(1);
  const io::RecordSet m = SmallBench(true);
  DiagnoseOptions o = SmallOptions();
  const diagnose::RecordDiagnosis local = DiagnoseBench(m, o).records;

  const svcclient::ServiceEvaluatorOptions so = ServiceOptions(cluster);
  int factories = 0;
  o.records_service = [&](const records::FamilyOptions& f) {
    ++factories;
    EXPECT_TRUE(f.bench_form);
    return svcclient::RecordsServiceFactory(so, f, "test");
  };
  const diagnose::RecordDiagnosis remote = DiagnoseBench(m, o).records;
  EXPECT_GE(factories, 1);
  ExpectSameVector(remote.base.params, local.base.params, "base.params");
  EXPECT_TRUE(SameBits(remote.base.train_sse, local.base.train_sse));
  ASSERT_EQ(remote.base.metrics.size(), local.base.metrics.size());
  for (size_t c = 0; c < local.base.metrics.size(); ++c)
    EXPECT_TRUE(SameBits(remote.base.metrics[c].sse, local.base.metrics[c].sse)) << c;
  // The first round's candidates, the naming and the verdict, bit for bit.
  ASSERT_EQ(remote.candidates.size(), local.candidates.size());
  for (size_t i = 0; i < local.candidates.size(); ++i) {
    const auto& a = remote.candidates[i];
    const auto& b = local.candidates[i];
    EXPECT_EQ(a.kind, b.kind);
    ExpectSameVector(a.fit.params, b.fit.params, std::string(model::EffectName(b.kind)) + ".x");
    EXPECT_TRUE(SameBits(a.s_withheld, b.s_withheld));
    EXPECT_TRUE(SameBits(a.score, b.score));
  }
  EXPECT_EQ(remote.named_effects, local.named_effects);
  EXPECT_EQ(remote.verdict, local.verdict);
  // The searches ran on the workers: complete_model sessions, each with evaluations.
  auto client = cluster.Client();
  std::vector<service::JobInfo> jobs;
  ASSERT_TRUE(client.List(&jobs).ok());
  EXPECT_GE(jobs.size(), 2u);
  for (const auto& j : jobs) {
    EXPECT_EQ(j.kind, "complete_model");
    EXPECT_GT(j.evaluations, 0u);
  }
}

// A spec of the removed "diagnose" kind, as an old client sends it: the problem's field (tag 13)
// reaches the master as an unknown field; the submission is refused with the kind named, not run
// as a spec without a problem.
TEST(DiagnoseServiceTest, AnOldDiagnoseSpecIsRefusedNamingTheKind) {
  testing::Cluster cluster("diagnose-removed-kind");
  job::JobSpec spec;
  spec.name = "old diagnose session";
  spec.external = job::ExternalSettings{};
  service::ClientRequestMsg submit;
  submit.type = service::ClientRequestMsg::Type::kSubmit;
  submit.request_id = 7;
  submit.spec = spec;
  submit.client_token = "old";
  wire::ClientRequest request;
  ASSERT_TRUE(request.ParseFromString(service::EncodeClientRequest(submit)));
  // DiagnoseProblem{structure: ["creep"], residuals: true} as the old encoder wrote it.
  wire::JobSpec* old = request.mutable_submit()->mutable_spec();
  old->GetReflection()->MutableUnknownFields(old)->AddLengthDelimited(
      13, std::string("\x1a\x05creep\x28\x01", 9));
  std::string bytes;
  ASSERT_TRUE(request.SerializeToString(&bytes));

  zmq::context_t ctx;
  zmq::socket_t s(ctx, zmq::socket_type::dealer);
  s.set(zmq::sockopt::linger, 0);
  s.connect(cluster.client_endpoint());
  s.send(zmq::buffer(bytes));
  zmq::pollitem_t items[] = {{s.handle(), 0, ZMQ_POLLIN, 0}};
  zmq::poll(items, 1, std::chrono::milliseconds(10000));
  ASSERT_TRUE(items[0].revents & ZMQ_POLLIN) << "no reply";
  zmq::message_t msg;
  ASSERT_TRUE(s.recv(msg));
  service::ClientReplyMsg reply;
  ASSERT_TRUE(service::DecodeClientReply(msg.to_string_view(), &reply).ok());
  EXPECT_EQ(reply.request_id, 7u);
  EXPECT_EQ(reply.code, service::WireCode::kInvalidArgument);
  EXPECT_NE(reply.error.find("the job kind \"diagnose\" (the fin engine's fits) was removed"),
            std::string::npos)
      << reply.error;
  ASSERT_FALSE(reply.violations.empty());
  EXPECT_EQ(reply.violations[0].field, "problem");
  // Nothing was started.
  std::vector<service::JobInfo> jobs;
  ASSERT_TRUE(cluster.Client().List(&jobs).ok());
  EXPECT_TRUE(jobs.empty());
}

}  // namespace
}  // namespace pz::diagnose
