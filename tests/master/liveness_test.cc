// Liveness (service/liveness.h), driven by explicit time points (no sleeps).
#include <gtest/gtest.h>

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

}  // namespace
}  // namespace pz::master
