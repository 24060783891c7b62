// The dashboard's HTTP server against clients that open connections and never finish a request
// (issue 24): raw sockets hold half-open connections while a normal client is answered.
#include <sys/socket.h>
#include <unistd.h>

#include <chrono>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "dashboard/dashboard.h"
#include "tests/testing/raw_socket.h"
// clang-format off
#include "dashboard/http_guard.h"  // last: httplib.h (its macros break Eigen's headers)
// clang-format on

namespace pz::dashboard {
namespace {

using Clock = std::chrono::steady_clock;

int HalfOpen(int port, const std::string& bytes, int from = 1) {
  return testing::RawConnection(port, bytes, from);
}

/// True once the server has closed the connection (recv returns 0 or an error within timeout).
bool ClosedByServer(int fd, int timeout_ms, std::string* got = nullptr) {
  timeval tv{timeout_ms / 1000, (timeout_ms % 1000) * 1000};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
  char buf[512];
  for (;;) {
    const ssize_t n = ::recv(fd, buf, sizeof(buf), 0);
    if (n > 0) {
      if (got) got->append(buf, static_cast<size_t>(n));
      continue;
    }
    if (n == 0) return true;
    return errno != EAGAIN && errno != EWOULDBLOCK;
  }
}

class GuardedServerTest : public ::testing::Test {
 protected:
  void Start(HttpGuardOptions o) {
    server = std::make_unique<GuardedServer>(o);
    server->Get("/ping", [](const httplib::Request&, httplib::Response& res) {
      res.set_content("pong", "text/plain");
    });
    port = server->Bind("127.0.0.1", 0);
    ASSERT_GT(port, 0);
    thread = std::thread([this] { server->listen_after_bind(); });
    while (!server->is_running()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  void TearDown() override {
    for (int fd : fds) ::close(fd);
    if (server) server->Shutdown();
    if (thread.joinable()) thread.join();
  }
  /// GET /ping by a normal client; the seconds it took (−1 if it failed).
  double Ping() {
    httplib::Client c("127.0.0.1", port);
    c.set_connection_timeout(5);
    c.set_read_timeout(5);
    const auto t0 = Clock::now();
    auto res = c.Get("/ping");
    if (!res || res->status != 200 || res->body != "pong") return -1;
    return std::chrono::duration<double>(Clock::now() - t0).count();
  }

  std::unique_ptr<GuardedServer> server;
  std::thread thread;
  int port = 0;
  std::vector<int> fds;
};

TEST_F(GuardedServerTest, SixtyFourHalfOpenConnectionsDoNotDelayANormalClient) {
  Start({});
  for (int i = 0; i < 64; ++i) {
    const int fd = HalfOpen(port, "GET /pi");  // part of a request line, then silence
    ASSERT_GE(fd, 0);
    fds.push_back(fd);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  for (int k = 0; k < 5; ++k) {
    const double s = Ping();
    ASSERT_GE(s, 0) << "request " << k << " failed";
    EXPECT_LT(s, 1.0) << "request " << k;
  }
  const HttpGuardCounters c = server->counters();
  EXPECT_GE(c.accepted, 69u);
  EXPECT_EQ(c.answered, 5u);
  EXPECT_LE(c.pending, 16u) << "one peer holds at most per_peer pending connections";
  EXPECT_GE(c.dropped + c.timed_out, 64u - 16u);
}

TEST_F(GuardedServerTest, AHeadThatDoesNotArriveInTimeIsClosed) {
  HttpGuardOptions o;
  o.head_timeout = std::chrono::milliseconds(300);
  Start(o);
  const int slow = HalfOpen(port, "GET /ping HTTP/1.1\r\nHost: x\r\n");  // never the blank line
  ASSERT_GE(slow, 0);
  fds.push_back(slow);
  const auto t0 = Clock::now();
  EXPECT_TRUE(ClosedByServer(slow, 3000));
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  EXPECT_GT(s, 0.2);
  EXPECT_LT(s, 1.5);
  EXPECT_EQ(server->counters().timed_out, 1u);
  EXPECT_GE(Ping(), 0);
}

TEST_F(GuardedServerTest, ADripFedHeadIsClosedAtItsDeadlineNotPerByte) {
  HttpGuardOptions o;
  o.head_timeout = std::chrono::milliseconds(500);
  Start(o);
  const int fd = HalfOpen(port, "G");
  ASSERT_GE(fd, 0);
  fds.push_back(fd);
  const auto t0 = Clock::now();
  bool closed = false;
  for (int i = 0; i < 20 && !closed; ++i) {  // one byte every 100 ms: each read is quick
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    closed = ::send(fd, "E", 1, MSG_NOSIGNAL) < 0 || ClosedByServer(fd, 1);
  }
  EXPECT_TRUE(closed || ClosedByServer(fd, 1000));
  EXPECT_LT(std::chrono::duration<double>(Clock::now() - t0).count(), 1.5);
  EXPECT_EQ(server->counters().timed_out, 1u);
}

TEST_F(GuardedServerTest, AnOversizedHeadIsRefusedWith431) {
  HttpGuardOptions o;
  o.max_head_bytes = 1024;
  Start(o);
  const int fd = HalfOpen(port, "GET /ping HTTP/1.1\r\nX-Long: " + std::string(4000, 'a'));
  ASSERT_GE(fd, 0);
  fds.push_back(fd);
  std::string reply;
  EXPECT_TRUE(ClosedByServer(fd, 2000, &reply));
  EXPECT_EQ(reply.rfind("HTTP/1.1 431", 0), 0u) << reply;
  EXPECT_EQ(server->counters().oversized, 1u);
}

TEST_F(GuardedServerTest, PendingConnectionsAndMemoryAreBounded) {
  HttpGuardOptions o;
  o.per_peer = 8;
  o.max_pending = 32;
  Start(o);
  const long rss0 = testing::RssKiB();
  // 400 connections from 50 addresses (127.0.0.2 …), each with a large part of a head, never
  // finished.
  for (int i = 0; i < 400; ++i) {
    const int fd = HalfOpen(port, std::string(8000, 'x'), 2 + i % 50);
    ASSERT_GE(fd, 0) << i;
    fds.push_back(fd);
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  const HttpGuardCounters c = server->counters();
  EXPECT_EQ(c.accepted, 400u);
  EXPECT_LE(c.pending, 32u);
  EXPECT_EQ(c.pending + c.dropped + c.timed_out, 400u);
  EXPECT_LT(testing::RssKiB() - rss0, 16 * 1024) << "KiB grown by 400 half-open connections";
  EXPECT_GE(Ping(), 0);
}

TEST_F(GuardedServerTest, ARequestWithABodyIsAnswered) {
  Start({});
  server->Post("/echo", [](const httplib::Request& req, httplib::Response& res) {
    res.set_content(req.body, "text/plain");
  });
  httplib::Client c("127.0.0.1", port);
  auto res = c.Post("/echo", std::string(100000, 'b'), "text/plain");
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_EQ(res->body.size(), 100000u);
}

TEST(DashboardGuard, HalfOpenConnectionsDoNotStallThePage) {
  DashboardOptions o;
  o.client.endpoint = "tcp://127.0.0.1:1";  // no master: the page is served all the same
  o.client.timeout_ms = 300;
  o.client.retries = 1;
  o.plots = false;
  Dashboard d(o);
  ASSERT_TRUE(d.Start().ok());
  const std::string url = d.url();
  const int port = std::stoi(url.substr(url.rfind(':') + 1));
  std::vector<int> fds;
  for (int i = 0; i < 64; ++i) fds.push_back(HalfOpen(port, "GET / HTT"));
  httplib::Client c("127.0.0.1", port);
  c.set_read_timeout(5);
  const auto t0 = Clock::now();
  auto res = c.Get("/");
  const double s = std::chrono::duration<double>(Clock::now() - t0).count();
  ASSERT_TRUE(res);
  EXPECT_EQ(res->status, 200);
  EXPECT_NE(res->body.find("<html"), std::string::npos);
  EXPECT_LT(s, 1.0);
  for (int fd : fds) ::close(fd);
  d.Stop();
}

}  // namespace
}  // namespace pz::dashboard
