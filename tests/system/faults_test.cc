// The master against bad input over real processes: invalid job specs are rejected with the
// field; garbage, truncated, wrong-version and oversized frames on both endpoints leave it
// serving; an individual that keeps killing workers is quarantined and reported.
#include <gtest/gtest.h>

#include <zmq.hpp>

#include "tests/system/service_harness.h"
#include "wire.pb.h"

namespace pz::testing {
namespace {

using namespace std::chrono_literals;

bool HasField(const std::vector<job::FieldViolation>& v, const std::string& field) {
  for (const auto& x : v)
    if (x.field == field) return true;
  return false;
}

TEST(ServiceFaults, BadJobSpecsAreRejectedWithTheField) {
  Cluster c("badspec");
  auto client = c.Client();
  svcclient::SubmitResult r;
  std::vector<job::FieldViolation> v;

  job::JobSpec s = SyntheticSpec(1, 10, 5);
  s.ga->population = 1;
  Status st = client.Submit(s, &r, &v);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(HasField(v, "ga.population")) << st.message();
  EXPECT_NE(st.message().find("ga.population = 1"), std::string::npos) << st.message();

  s = SyntheticSpec(1, 10, 5);
  s.problem = std::monostate{};
  EXPECT_EQ(client.Submit(s, &r, &v).code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(HasField(v, "problem"));

  s = SyntheticSpec(1, 10, 5);
  std::get<job::SyntheticProblem>(s.problem).genome_bits = 70000;
  s.limits.task_timeout_s = -1;
  EXPECT_EQ(client.Submit(s, &r, &v).code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(HasField(v, "synthetic.genome_bits"));
  EXPECT_TRUE(HasField(v, "limits.task_timeout_s"));

  job::HgannProblem h;  // no cases, an unknown range name
  h.ranges.push_back({"alfa", 0, 1});
  s = SyntheticSpec(1, 10, 5);
  s.problem = h;
  EXPECT_EQ(client.Submit(s, &r, &v).code(), StatusCode::kInvalidArgument);
  EXPECT_TRUE(HasField(v, "hgann.cases"));
  EXPECT_TRUE(HasField(v, "hgann.ranges[0].name"));

  // Unknown JSON fields are refused by the parser, naming the field.
  st = client.SubmitJson(R"({"version": 1, "populaton": 3})", &r, &v);
  EXPECT_EQ(st.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(st.message().find("populaton"), std::string::npos) << st.message();

  // The master still accepts a good one.
  EXPECT_TRUE(client.Submit(SyntheticSpec(1, 10, 2), &r).ok());
}

TEST(ServiceFaults, GarbageFramesOnBothEndpointsLeaveTheMasterServing) {
  Cluster c("garbage", {"--max-message-bytes", "1048576"});
  c.AddWorker(2);
  zmq::context_t ctx;
  pz::wire::ClientRequest wrong_version;
  wrong_version.set_version(99);
  wrong_version.mutable_list();
  const std::string valid_list = [] {
    pz::wire::ClientRequest r;
    r.set_version(1);
    r.set_request_id(5);
    r.mutable_list();
    return r.SerializeAsString();
  }();
  const std::vector<std::string> payloads = {
      "",
      "\xff\xff\xff\xff garbage",
      std::string(100, '\0'),
      valid_list.substr(0, valid_list.size() / 2),
      wrong_version.SerializeAsString(),
      std::string(2 << 20, 'x')};  // oversized: above the 1 MiB cap
  for (const std::string& ep : {c.worker_endpoint(), c.client_endpoint()}) {
    for (const auto& p : payloads) {
      zmq::socket_t s(ctx, zmq::socket_type::dealer);
      s.set(zmq::sockopt::linger, 0);
      s.connect(ep);
      s.send(zmq::buffer(p), zmq::send_flags::dontwait);
      // Multipart garbage too.
      s.send(zmq::buffer(p), zmq::send_flags::sndmore | zmq::send_flags::dontwait);
      s.send(zmq::buffer(std::string("x")), zmq::send_flags::sndmore | zmq::send_flags::dontwait);
      s.send(zmq::buffer(std::string("y")), zmq::send_flags::dontwait);
      std::this_thread::sleep_for(20ms);
    }
  }
  // A wrong-version request is answered with a typed error.
  {
    zmq::socket_t s(ctx, zmq::socket_type::dealer);
    s.set(zmq::sockopt::linger, 0);
    s.connect(c.client_endpoint());
    s.send(zmq::buffer(wrong_version.SerializeAsString()));
    zmq::pollitem_t items[] = {{s.handle(), 0, ZMQ_POLLIN, 0}};
    zmq::poll(items, 1, 5000ms);
    ASSERT_TRUE(items[0].revents & ZMQ_POLLIN);
    zmq::message_t m;
    ASSERT_TRUE(s.recv(m));
    pz::wire::ClientReply reply;
    ASSERT_TRUE(reply.ParseFromArray(m.data(), static_cast<int>(m.size())));
    EXPECT_EQ(reply.code(), pz::wire::CODE_VERSION_MISMATCH);
  }
  auto client = c.Client();
  std::vector<service::JobInfo> jobs;
  ASSERT_TRUE(client.List(&jobs).ok());
  svcclient::SubmitResult r;
  ASSERT_TRUE(client.Submit(SyntheticSpec(5, 20, 5), &r).ok());
  service::JobInfo info;
  ASSERT_TRUE(client.WaitFinal(r.job_id, 30s, &info).ok());
  EXPECT_EQ(info.state, service::JobState::kSucceeded);
}

TEST(ServiceFaults, IndividualThatKeepsKillingWorkersIsQuarantined) {
  job::JobSpec spec = SyntheticSpec(17, 16, 2, 0, 16);
  std::get<job::SyntheticProblem>(spec.problem).crash_prefix = "11";
  spec.limits.quarantine_after = 2;
  spec.limits.penalty_cost = 1e6;
  Cluster c("quarantine");
  c.AddWorker(1);
  c.AddWorker(1);
  auto client = c.Client();
  svcclient::SubmitResult r;
  ASSERT_TRUE(client.Submit(spec, &r).ok());
  service::JobInfo info;
  const auto deadline = std::chrono::steady_clock::now() + 50s;
  while (std::chrono::steady_clock::now() < deadline) {
    ASSERT_TRUE(client.GetStatus(r.job_id, &info).ok());
    if (service::IsFinal(info.state)) break;
    for (auto& w : c.workers())
      if (!w->running()) w = nullptr;
    std::erase(c.workers(), nullptr);
    while (c.workers().size() < 2) c.AddWorker(1);
    std::this_thread::sleep_for(100ms);
  }
  ASSERT_EQ(info.state, service::JobState::kSucceeded) << info.message;
  EXPECT_FALSE(info.quarantined.empty());
  for (const auto& q : info.quarantined) EXPECT_GE(q.strikes, 2u);
}

}  // namespace
}  // namespace pz::testing
