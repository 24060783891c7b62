// Lease scheduling (master/dispatcher.h), driven by explicit time points (no sleeps): every task
// leased once, duplicates ignored, fair sharing, adaptive batches, deadlines; suspects run alone;
// quarantine only on evidence that the task itself kills or hangs workers, never under churn.
#include <gtest/gtest.h>

#include <map>
#include <random>
#include <set>

#include "master/dispatcher.h"

namespace pz::master {
namespace {

using std::chrono::milliseconds;
using std::chrono::seconds;
const TimePoint t0{};

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
  d.RemoveWorker("w1", /*lost=*/true, t0);
  EXPECT_TRUE(d.ConfirmStrikes(t0 + seconds(60)).empty());  // a batch's death strikes nobody
  d.AddWorker("w2", 2);
  // Suspects come back one per lease, alone on the worker (no second lease meanwhile).
  for (size_t i = 0; i < n; ++i) {
    auto s = d.NextLease(t0);
    ASSERT_TRUE(s);
    EXPECT_EQ(s->positions.size(), 1u);
    EXPECT_TRUE(s->solo);
    EXPECT_FALSE(d.NextLease(t0)) << "a worker running a suspect got another lease";
    d.Complete("w2", s->id, 0);
    d.MarkDone("j", 0, s->positions[0]);
  }
}

TEST(Dispatcher, TaskThatKeepsKillingWorkersIsQuarantined) {
  DispatchOptions o;
  o.quiet_window_s = 5;
  Dispatcher d(o);
  d.StartGeneration("j", 0, 1, 10, 3);
  std::vector<Quarantined> q;
  TimePoint t = t0;
  // The first death is in an ordinary lease: it only makes the task a suspect. Each later death
  // runs it alone, with the cluster otherwise healthy: a strike each, confirmed a window later
  // (the task's own earlier deaths, a second apart, do not count as churn).
  for (int k = 0; k < 4 && q.empty(); ++k) {
    const std::string w = "w" + std::to_string(k);
    d.AddWorker(w, 1);
    auto l = d.NextLease(t);
    ASSERT_TRUE(l) << k;
    EXPECT_EQ(l->solo, k > 0) << k;
    d.RemoveWorker(w, /*lost=*/true, t);
    t += seconds(1);
    q = d.ConfirmStrikes(t + seconds(5));
  }
  ASSERT_EQ(q.size(), 1u);
  EXPECT_EQ(q[0].position, 0);
  EXPECT_EQ(q[0].strikes, 3);
  EXPECT_EQ(d.remaining("j"), 0);
}

TEST(Dispatcher, ChurnNeverQuarantines) {
  // A worker killed every second from outside and replaced — a random one, and every third time
  // the one running a suspect alone when there is one: other workers always left within the quiet
  // window, so nothing is ever struck, even with quarantine after one strike.
  DispatchOptions o;
  o.quiet_window_s = 5;
  Dispatcher d(o);
  d.StartGeneration("j", 0, 3, 10, 1);
  std::map<std::string, Lease> held;  // worker → its last lease
  for (int i = 0; i < 3; ++i) d.AddWorker("w" + std::to_string(i), 1);
  std::mt19937 rng(12);
  TimePoint t = t0;
  int next = 3, solo_kills = 0;
  for (int k = 0; k < 300; ++k) {
    while (auto l = d.NextLease(t)) held[l->worker] = *l;
    std::vector<std::string> alive;
    std::string solo;
    for (const auto& [w, l] : held)
      if (d.HasWorker(w)) {
        alive.push_back(w);
        if (l.solo) solo = w;
      }
    ASSERT_FALSE(alive.empty());
    const std::string victim = (k % 3 == 0 && !solo.empty()) ? solo : alive[rng() % alive.size()];
    solo_kills += held[victim].solo;
    d.RemoveWorker(victim, /*lost=*/true, t);
    held.erase(victim);
    d.AddWorker("w" + std::to_string(next++), 1);
    t += seconds(1);
    EXPECT_TRUE(d.ConfirmStrikes(t).empty()) << "struck under churn at kill " << k;
  }
  EXPECT_GT(solo_kills, 50);  // the kills did land on tasks running alone
  EXPECT_EQ(d.remaining("j"), 3);
}

TEST(Dispatcher, StrikesCountOncePerWorkerAndAHangStrikes) {
  DispatchOptions o;
  o.quiet_window_s = 5;
  Dispatcher d(o);
  d.StartGeneration("j", 0, 1, /*task_timeout_s=*/2, 2);
  d.AddWorker("a", 1);
  auto l = d.NextLease(t0);
  ASSERT_TRUE(l);
  EXPECT_FALSE(l->solo);
  EXPECT_TRUE(d.ExpireLeases(t0 + seconds(2)).empty());  // a batch past its deadline: a suspect
  auto s = d.NextLease(t0 + seconds(2));
  ASSERT_TRUE(s);
  EXPECT_TRUE(s->solo);
  EXPECT_TRUE(d.ExpireLeases(t0 + seconds(4)).empty());  // hung alone on "a": strike 1 of 2
  auto s2 = d.NextLease(t0 + seconds(4));
  ASSERT_TRUE(s2);
  EXPECT_EQ(s2->worker, "a");
  EXPECT_TRUE(d.ExpireLeases(t0 + seconds(6)).empty()) << "the same worker struck twice";
  d.AddWorker("b", 1);
  std::optional<Lease> s3;
  for (TimePoint t = t0 + seconds(6); !s3 || s3->worker != "b"; t += seconds(2)) {
    s3 = d.NextLease(t);
    ASSERT_TRUE(s3);
    if (s3->worker != "b") {
      d.ExpireLeases(t + seconds(2));
      continue;
    }
    auto q = d.ExpireLeases(t + seconds(2));  // hung alone on "b" too: strike 2 of 2
    ASSERT_EQ(q.size(), 1u);
    EXPECT_EQ(q[0].strikes, 2);
  }
}

TEST(Dispatcher, SuspectsDoNotStarveBehindAnotherJob) {
  Dispatcher d;
  d.AddWorker("w", 1);
  d.StartGeneration("big", 0, 100000, 10, 3);
  auto b1 = d.NextLease(t0), b2 = d.NextLease(t0);  // "w" is full with the big job
  ASSERT_TRUE(b1 && b2);
  EXPECT_FALSE(d.NextLease(t0));
  d.AddWorker("x", 1);
  d.StartGeneration("small", 0, 1, 10, 3);
  auto s = d.NextLease(t0);
  ASSERT_TRUE(s);
  ASSERT_EQ(s->job_id, "small");
  ASSERT_EQ(s->worker, "x");
  d.RemoveWorker("x", /*lost=*/true, t0);  // the small job's task is now a suspect
  // "w" is drained: no new lease while the suspect waits, then the suspect alone.
  EXPECT_FALSE(d.NextLease(t0)) << "the drained worker got more of the big job";
  ASSERT_TRUE(d.Complete("w", b1->id, 0.001));
  EXPECT_FALSE(d.NextLease(t0));
  ASSERT_TRUE(d.Complete("w", b2->id, 0.001));
  auto suspect = d.NextLease(t0);
  ASSERT_TRUE(suspect);
  EXPECT_EQ(suspect->job_id, "small");
  EXPECT_TRUE(suspect->solo);
  EXPECT_FALSE(d.NextLease(t0)) << "a worker running a suspect got another lease";
  ASSERT_TRUE(d.Complete("w", suspect->id, 0.001));
  EXPECT_TRUE(d.NextLease(t0));  // the big job goes on
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

// Stragglers: with nothing left to hand out, a lease running 3× longer than the generation's
// median time per task (and at least 0.2 s) gets one copy on an idle worker; the first answer
// counts.
TEST(Dispatcher, AStragglingLeaseGetsOneCopyOnAnIdleWorkerAndTheFirstAnswerCounts) {
  Dispatcher d;
  for (const char* w : {"w1", "w2", "w3"}) d.AddWorker(w, 1);
  d.StartGeneration("j", 0, 3, 60, 3);
  std::vector<Lease> ls;
  while (auto l = d.NextLease(t0)) ls.push_back(*l);
  ASSERT_EQ(ls.size(), 3u);
  for (int i = 0; i < 2; ++i) {
    ASSERT_TRUE(d.Complete(ls[i].worker, ls[i].id, 0.01));
    ASSERT_TRUE(d.MarkDone("j", 0, ls[i].positions[0]));
  }
  const Lease& slow = ls[2];
  EXPECT_LE(d.NextDeadline(), t0 + milliseconds(200))
      << "the broker wakes when the straggler is due";
  EXPECT_FALSE(d.NextLease(t0 + milliseconds(150))) << "not yet a straggler";
  auto copy = d.NextLease(t0 + milliseconds(250));
  ASSERT_TRUE(copy);
  EXPECT_TRUE(copy->speculative);
  EXPECT_NE(copy->worker, slow.worker);
  EXPECT_EQ(copy->positions, slow.positions);
  EXPECT_FALSE(d.NextLease(t0 + seconds(5))) << "one copy per lease, and a copy is never copied";
  EXPECT_EQ(d.speculative_leases(), 1u);
  // The copy answers first: it counts; the straggler's late answer is ignored.
  ASSERT_TRUE(d.Complete(copy->worker, copy->id, 0.01));
  EXPECT_TRUE(d.MarkDone("j", 0, copy->positions[0]));
  EXPECT_EQ(d.remaining("j"), 0);
  ASSERT_TRUE(d.Complete(slow.worker, slow.id, 1.0));
  EXPECT_FALSE(d.MarkDone("j", 0, slow.positions[0]));
}

TEST(Dispatcher, NoCopyWithoutAnIdleWorkerWhenTurnedOffOrForASuspect) {
  {
    DispatchOptions o;
    o.speculate_after = 0;
    Dispatcher d(o);
    d.AddWorker("w1", 1);
    d.AddWorker("w2", 1);
    d.StartGeneration("j", 0, 2, 60, 3);
    auto a = d.NextLease(t0), b = d.NextLease(t0);
    ASSERT_TRUE(a && b);
    ASSERT_TRUE(d.Complete(a->worker, a->id, 0.01));
    EXPECT_FALSE(d.NextLease(t0 + seconds(10)));
  }
  {
    Dispatcher d;  // two workers, both busy: nobody idle to take a copy
    d.AddWorker("w1", 1);
    d.AddWorker("w2", 1);
    d.StartGeneration("j", 0, 3, 60, 3);
    auto a = d.NextLease(t0), b = d.NextLease(t0);
    ASSERT_TRUE(a && b);
    ASSERT_TRUE(d.Complete(a->worker, a->id, 0.01));
    ASSERT_TRUE(d.MarkDone("j", 0, a->positions[0]));
    auto c = d.NextLease(t0 + milliseconds(10));  // the last task, to the worker that answered
    ASSERT_TRUE(c);
    EXPECT_FALSE(c->speculative);
    EXPECT_FALSE(d.NextLease(t0 + seconds(10)));
    EXPECT_EQ(d.speculative_leases(), 0u);
  }
  {
    Dispatcher d;  // a suspect runs alone and is never copied
    d.AddWorker("w1", 1);
    d.AddWorker("w2", 1);
    d.AddWorker("w3", 1);
    d.StartGeneration("j", 0, 2, 60, 3);
    auto a = d.NextLease(t0), b = d.NextLease(t0);
    ASSERT_TRUE(a && b);
    ASSERT_TRUE(d.Complete(a->worker, a->id, 0.01));
    ASSERT_TRUE(d.MarkDone("j", 0, a->positions[0]));
    d.RemoveWorker(b->worker, /*lost=*/true, t0 + milliseconds(20));
    auto solo = d.NextLease(t0 + milliseconds(30));
    ASSERT_TRUE(solo);
    EXPECT_TRUE(solo->solo);
    EXPECT_FALSE(d.NextLease(t0 + seconds(10)));
    EXPECT_EQ(d.speculative_leases(), 0u);
  }
}

}  // namespace
}  // namespace pz::master
