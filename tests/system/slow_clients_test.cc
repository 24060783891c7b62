// The master's client endpoint against clients that never read and connections that never speak
// (issue 24): 64 watchers of a fast job that read nothing, 64 TCP connections without a ZeroMQ
// greeting and 64 with half of one. A normal client is answered within 1 s throughout, a 65th
// watcher still gets its events, and the
// master's memory stays bounded (the client socket queues at most --client-queue messages per peer;
// a stalled watcher loses events, never the master its memory).
#include <gtest/gtest.h>

#include <unistd.h>

#include <zmq.hpp>

#include "tests/system/service_harness.h"
#include "tests/testing/raw_socket.h"
#include "wire.pb.h"

namespace pz::testing {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

int RawConnection(const std::string& endpoint, const std::string& bytes) {
  return testing::RawConnection(std::stoi(endpoint.substr(endpoint.rfind(':') + 1)), bytes);
}

TEST(SlowClients, WatchersThatNeverReadAndSilentConnectionsDoNotStallTheMaster) {
  Cluster c("slowclients");
  c.AddWorker(1);
  auto client = c.Client(2000, 1);
  svcclient::SubmitResult r;
  // Many short generations: a stream of events for the watchers.
  ASSERT_TRUE(client.Submit(SyntheticSpec(11, 16, 4000), &r).ok());
  const long rss0 = RssKiB(c.master_pid());
  ASSERT_GT(rss0, 0);

  zmq::context_t ctx;
  std::vector<std::unique_ptr<zmq::socket_t>> watchers;
  for (int i = 0; i < 64; ++i) {
    auto s = std::make_unique<zmq::socket_t>(ctx, zmq::socket_type::dealer);
    s->set(zmq::sockopt::linger, 0);
    s->set(zmq::sockopt::rcvhwm, 1);     // queue almost nothing here …
    s->set(zmq::sockopt::rcvbuf, 4096);  // … and little in the kernel: the master's side fills up
    s->connect(c.client_endpoint());
    pz::wire::ClientRequest w;
    w.set_version(1);
    w.set_request_id(1000 + i);
    w.mutable_watch()->set_job_id(r.job_id);
    s->send(zmq::buffer(w.SerializeAsString()));
    watchers.push_back(std::move(s));  // never read
  }
  std::vector<int> raw;
  const std::string greeting_half("\xff\0\0\0\0\0\0\0\x01\x7f\x03",
                                  11);  // ZMTP 3 signature, cut short
  for (int i = 0; i < 64; ++i) raw.push_back(RawConnection(c.client_endpoint(), ""));
  for (int i = 0; i < 64; ++i) raw.push_back(RawConnection(c.client_endpoint(), greeting_half));
  for (int fd : raw) ASSERT_GE(fd, 0);

  // Until the job has published well past the per-client queue (1000 messages by default).
  double worst = 0;
  long rss_max = rss0;
  service::JobInfo info;
  const auto until = Clock::now() + 40s;
  int requests = 0;
  do {
    const auto t0 = Clock::now();
    ASSERT_TRUE(client.GetStatus(r.job_id, &info).ok()) << "request " << requests;
    worst = std::max(worst, std::chrono::duration<double>(Clock::now() - t0).count());
    rss_max = std::max(rss_max, RssKiB(c.master_pid()));
    ++requests;
    std::this_thread::sleep_for(100ms);
  } while (info.generation < 2500 && service::JobState::kRunning == info.state &&
           Clock::now() < until);
  EXPECT_LT(worst, 1.0) << "slowest Status answer [s]";
  // A 65th watcher (the maximum is 64) takes the oldest one's place and gets events.
  int events = 0;
  ASSERT_TRUE(client
                  .Watch(
                      r.job_id, [&](const service::JobEvent&) { return ++events < 5; }, 10s)
                  .ok());
  EXPECT_EQ(events, 5);
  EXPECT_GE(info.generation, 2500u) << "the job went on";
  // 64 stalled watchers of a job publishing hundreds of events a second: bounded by the per-peer
  // queue.
  EXPECT_LT(rss_max - rss0, 32 * 1024) << "KiB the master grew by (from " << rss0 << ")";
  std::printf(
      "slow clients: slowest Status %.3f s over %d requests; master RSS %ld -> max %ld KiB; "
      "generation %ld\n",
      worst, requests, rss0, rss_max, static_cast<long>(info.generation));
  for (int fd : raw) ::close(fd);
  ASSERT_TRUE(client.Cancel(r.job_id).ok());
}

}  // namespace
}  // namespace pz::testing
