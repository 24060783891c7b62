// Liveness and lease scheduling, driven by explicit time points (no sleeps).
#include <gtest/gtest.h>

#include <set>

#include "master/dispatcher.h"
#include "service/liveness.h"

namespace pz::master {

using service::Backoff;
using service::PeerLiveness;
using service::ServerLiveness;
using service::TimePoint;
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
const TimePoint t0{};

TEST(PeerLiveness, PeerExpiresAfterLivenessSilentIntervals) {
  PeerLiveness l(milliseconds(100), 3);
  l.Seen("a", t0);
  l.Seen("b", t0 + milliseconds(200));
  EXPECT_TRUE(l.TakeExpired(t0 + milliseconds(300)).empty());
  EXPECT_EQ(l.TakeExpired(t0 + milliseconds(301)), std::vector<std::string>{"a"});
  EXPECT_FALSE(l.Contains("a"));
  EXPECT_EQ(l.NextExpiry(), t0 + milliseconds(500));
}

TEST(PeerLiveness, AnyMessageRefreshes) {
  PeerLiveness l(milliseconds(100), 3);
  l.Seen("a", t0);
  l.Seen("a", t0 + milliseconds(250));
  EXPECT_TRUE(l.TakeExpired(t0 + milliseconds(500)).empty());
}

TEST(PeerLiveness, HeartbeatsAreDueOncePerInterval) {
  PeerLiveness l(milliseconds(100), 3);
  EXPECT_TRUE(l.HeartbeatDue(t0));
  EXPECT_FALSE(l.HeartbeatDue(t0 + milliseconds(99)));
  EXPECT_TRUE(l.HeartbeatDue(t0 + milliseconds(100)));
}

TEST(ServerLiveness, ExpiresWithoutTraffic) {
  ServerLiveness s(milliseconds(100), 3);
  s.Reset(t0);
  EXPECT_FALSE(s.Expired(t0 + milliseconds(300)));
  EXPECT_TRUE(s.Expired(t0 + milliseconds(301)));
  s.Seen(t0 + milliseconds(301));
  EXPECT_FALSE(s.Expired(t0 + milliseconds(400)));
}

TEST(Backoff, DoublesUpToTheCapAndResets) {
  Backoff b(milliseconds(100), milliseconds(350));
  EXPECT_EQ(b.Next(), milliseconds(100));
  EXPECT_EQ(b.Next(), milliseconds(200));
  EXPECT_EQ(b.Next(), milliseconds(350));
  EXPECT_EQ(b.Next(), milliseconds(350));
  b.Reset();
  EXPECT_EQ(b.Next(), milliseconds(100));
}

TEST(Dispatcher, LeasesCoverEveryTaskExactlyOnce) {
  Dispatcher d;
  d.AddWorker("w1", 4);
  d.AddWorker("w2", 2);
  d.StartGeneration("j", 0, 100, 10, 3);
  std::multiset<int> seen;
  for (int round = 0; round < 200 && d.remaining("j") > 0; ++round) {
    while (auto l = d.NextLease(t0)) {
      auto done = d.Complete(l->worker, l->id, 0.001 * l->positions.size());
      ASSERT_TRUE(done);
      for (int p : done->positions) {
        seen.insert(p);
        EXPECT_TRUE(d.MarkDone("j", 0, p));
      }
    }
  }
  EXPECT_EQ(d.remaining("j"), 0);
  EXPECT_EQ(seen.size(), 100u);
  EXPECT_EQ(std::set<int>(seen.begin(), seen.end()).size(), 100u);
}

TEST(Dispatcher, DuplicateAndForeignResultsAreIgnored) {
  Dispatcher d;
  d.AddWorker("w1", 1);
  d.AddWorker("w2", 1);
  d.StartGeneration("j", 5, 2, 10, 3);
  auto l = d.NextLease(t0);
  ASSERT_TRUE(l);
  EXPECT_FALSE(d.Complete(l->worker == "w1" ? "w2" : "w1", l->id, 0));  // not the holder
  EXPECT_TRUE(d.Complete(l->worker, l->id, 0));
  EXPECT_FALSE(d.Complete(l->worker, l->id, 0));  // the same lease twice
  EXPECT_TRUE(d.MarkDone("j", 5, l->positions[0]));
  EXPECT_FALSE(d.MarkDone("j", 5, l->positions[0]));  // the same key twice
  EXPECT_FALSE(d.MarkDone("j", 4, 1));                // an old generation
}

TEST(Dispatcher, DeadWorkerLeasesAreRequeuedAndIsolated) {
  Dispatcher d;
  d.AddWorker("w1", 2);
  d.StartGeneration("j", 0, 6, 10, 3);
  auto l = d.NextLease(t0);
  ASSERT_TRUE(l);
  const size_t n = l->positions.size();
  EXPECT_TRUE(d.RemoveWorker("w1", /*strike=*/true).empty());
  d.AddWorker("w2", 2);
  // Struck tasks come back one per lease.
  for (size_t i = 0; i < n; ++i) {
    auto s = d.NextLease(t0);
    ASSERT_TRUE(s);
    EXPECT_EQ(s->positions.size(), 1u);
    d.Complete("w2", s->id, 0);
    d.MarkDone("j", 0, s->positions[0]);
  }
}

TEST(Dispatcher, TaskThatKeepsKillingWorkersIsQuarantined) {
  Dispatcher d;
  d.StartGeneration("j", 0, 1, 10, 3);
  std::vector<Quarantined> q;
  for (int k = 0; k < 3; ++k) {
    const std::string w = "w" + std::to_string(k);
    d.AddWorker(w, 1);
    ASSERT_TRUE(d.NextLease(t0));
    q = d.RemoveWorker(w, true);
  }
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q[0].position, 0);
  EXPECT_EQ(q[0].strikes, 3);
  EXPECT_EQ(d.remaining("j"), 0);
}

TEST(Dispatcher, ExpiredLeaseIsRequeuedAndLateResultIgnored) {
  Dispatcher d;
  d.AddWorker("w", 1);
  d.StartGeneration("j", 0, 1, /*task_timeout_s=*/2, 3);
  auto l = d.NextLease(t0);
  ASSERT_TRUE(l);
  EXPECT_EQ(l->deadline, t0 + seconds(2));
  EXPECT_TRUE(d.ExpireLeases(t0 + milliseconds(1999)).empty());
  EXPECT_EQ(d.leases_outstanding(), 1u);
  d.ExpireLeases(t0 + seconds(2));
  EXPECT_EQ(d.leases_outstanding(), 0u);
  EXPECT_FALSE(d.Complete("w", l->id, 0));  // late
  auto again = d.NextLease(t0 + seconds(2));
  ASSERT_TRUE(again);
  EXPECT_EQ(again->positions, l->positions);
}

TEST(Dispatcher, JobsShareWorkersFairly) {
  Dispatcher d;
  d.AddWorker("w", 4);
  d.StartGeneration("a", 0, 1000, 10, 3);
  d.StartGeneration("b", 0, 1000, 10, 3);
  std::map<std::string, int> leased;
  for (int i = 0; i < 10; ++i) {
    auto l = d.NextLease(t0);
    ASSERT_TRUE(l);
    leased[l->job_id] += static_cast<int>(l->positions.size());
    d.Complete("w", l->id, 0.01 * l->positions.size());
  }
  EXPECT_NEAR(leased["a"], leased["b"], 0.2 * (leased["a"] + leased["b"]));
}

TEST(Dispatcher, BatchSizeAdaptsToWorkerSpeed) {
  DispatchOptions o;
  o.target_batch_s = 1.0;
  Dispatcher d(o);
  d.AddWorker("w", 2);
  d.StartGeneration("j", 0, 100000, 10, 3);
  auto first = d.NextLease(t0);
  ASSERT_TRUE(first);
  EXPECT_EQ(first->positions.size(), 2u);  // unknown speed: one round of threads
  d.Complete("w", first->id, 2 * 0.01);    // 10 ms per evaluation
  auto second = d.NextLease(t0);
  ASSERT_TRUE(second);
  EXPECT_EQ(second->positions.size(), 200u);  // 100 rounds of 2 threads ≈ 1 s
}

}  // namespace
}  // namespace pz::master
