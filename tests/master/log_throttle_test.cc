// Repeated log lines (master/log_throttle.h): one line per key and interval, then the count of
// those left out; keys are independent.
#include <gtest/gtest.h>

#include "master/log_throttle.h"

namespace pz::master {
namespace {

using namespace std::chrono_literals;

TEST(LogThrottle, OneLineAnIntervalPerKeyThenTheCount) {
  LogThrottle t(10s);
  const service::TimePoint t0{};
  uint64_t n = 99;
  EXPECT_TRUE(t.Allow("disk", t0, &n));
  EXPECT_EQ(n, 0u);
  for (int i = 1; i <= 500; ++i) EXPECT_FALSE(t.Allow("disk", t0 + i * 10ms, &n));
  EXPECT_TRUE(t.Allow("frames", t0 + 1s, &n));  // another key is not held back
  EXPECT_EQ(n, 0u);
  EXPECT_FALSE(t.Allow("disk", t0 + 9999ms, &n));
  EXPECT_TRUE(t.Allow("disk", t0 + 10s, &n));
  EXPECT_EQ(n, 501u);
  EXPECT_FALSE(t.Allow("disk", t0 + 15s, &n));
  EXPECT_TRUE(t.Allow("disk", t0 + 31s, &n));
  EXPECT_EQ(n, 1u);
}

}  // namespace
}  // namespace pz::master
