// fact::app's simulation clock (follow_sim_clock, wait_for_sim_clock) over memq://, in a binary of
// its own: following the clock switches now_us() for the whole process. Ticks that cannot be used
// are counted and leave the clock where it was (review, session 33: one tick at INT64_MAX − 5 held
// now_us() there for good, and start_clock's error said only "no tick" when foreign messages came).
#include "common/app.h"
#include "fact/sim_clock_t.hpp"

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <limits>

namespace {

void tick(lcm::LCM& lcm, int64_t utime) {
  fact::sim_clock_t t{};
  t.utime = utime;
  t.rate = 1;
  lcm.publish("FACT_SIM_CLOCK", &t);
}

TEST(SimClock, UnusableTicksAreCountedAndLeaveTheClockAlone) {
  lcm::LCM lcm("memq://");
  ASSERT_TRUE(lcm.good());
  fact::app::follow_sim_clock(lcm, "FACT_SIM_CLOCK");
  lcm.publish("FACT_SIM_CLOCK", "not a tick", 10);
  tick(lcm, std::numeric_limits<int64_t>::max() - 5);
  tick(lcm, -1);
  EXPECT_FALSE(fact::app::wait_for_sim_clock(lcm, 300));
  EXPECT_EQ(fact::app::sim_clock_ticks_dropped().undecodable, 1);
  EXPECT_EQ(fact::app::sim_clock_ticks_dropped().refused, 2);
  const int64_t t0 = 1700000000000000;
  tick(lcm, t0);
  ASSERT_TRUE(fact::app::wait_for_sim_clock(lcm, 300));
  EXPECT_EQ(fact::app::now_us(), t0);
  tick(lcm, std::numeric_limits<int64_t>::max() - 5);
  tick(lcm, t0 + 10000);
  while (lcm.handleTimeout(0) > 0) {
  }
  EXPECT_EQ(fact::app::now_us(), t0 + 10000);  // the far-future tick did not hold it
  EXPECT_EQ(fact::app::sim_clock_ticks_dropped().refused, 3);
}

}  // namespace
