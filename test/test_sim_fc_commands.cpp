// The simulated flight controller's commands, in process (apps/fact_sim/sim_fc.cpp, no sockets):
// the ground test of a disarm and DO_SET_MODE's base mode. The whole FC over UDP is in
// test_sim_fc.cpp.
#include "sim_fc.h"

#include <gtest/gtest.h>

#include <cmath>

namespace {

namespace mav = fact::mavlink;

struct Fc {
  fact::app::Status status{nullptr, "FACT_STATUS", "test", 2};
  fact::app::Log log{"test", 2};
  fact::sim_fc::SimFc fc{2, fact::sim_fc::FcOptions{}, &status, &log};
  mav::Encoder bridge{{1, 191}};

  void command(uint16_t cmd, float p1, const fact::sim::SimDrone& drone) {
    mav::CommandLong c;
    c.command = cmd;
    c.param = {p1, 0, 0, 0, 0, 0, 0};
    c.target_system = 1;
    c.target_component = 1;
    const std::vector<uint8_t> bytes = bridge.encode(c);
    fc.on_bytes(bytes.data(), bytes.size(), drone, 0);
  }
};

// A drone that took off from a box (start at z = 1.75) and flew off it is in the air: its height
// above the start is 0, but a disarm there is refused (review, session 33: it was accepted and the
// drone froze in mid-air). Back on its start spot, or on the floor, it may disarm.
TEST(SimFcCommands, DisarmOnlyOnTheFloorOrTheSpotItTookOffFrom) {
  Fc f;
  fact::sim::SimDrone d;
  d.origin = {0, 0, 1.75};
  d.landed = false;
  const auto arm = [&] {
    f.command(mav::kCmdComponentArmDisarm, 1, d);
    ASSERT_TRUE(f.fc.armed());
  };
  arm();
  d.p = {1.5, 0, 1.76};  // beside the box, at the box's height
  f.command(mav::kCmdComponentArmDisarm, 0, d);
  EXPECT_TRUE(f.fc.armed()) << "disarmed 1.76 m above the floor, off its start";
  EXPECT_EQ(f.status.value("fc_command_denied"), 1);
  d.p = {0.05, 0, 0.9};  // above the floor, below the start spot (review: that passed as on it)
  f.command(mav::kCmdComponentArmDisarm, 0, d);
  EXPECT_TRUE(f.fc.armed()) << "disarmed 0.9 m above the floor, 0.85 m below its start";
  EXPECT_EQ(f.status.value("fc_command_denied"), 2);
  d.p = {0.05, 0, 1.76};  // back on the box
  f.command(mav::kCmdComponentArmDisarm, 0, d);
  EXPECT_FALSE(f.fc.armed());
  arm();
  d.p = {3, 2, 0.01};  // on the floor
  f.command(mav::kCmdComponentArmDisarm, 0, d);
  EXPECT_FALSE(f.fc.armed());
}

// DO_SET_MODE's param1 is MAV_MODE (a uint8): a value beyond it is refused like one without the
// custom-mode flag, never cast (1e30 to int was undefined behaviour).
TEST(SimFcCommands, SetModeRefusesABaseModeOutsideAByte) {
  Fc f;
  fact::sim::SimDrone d;
  for (float base : {1e30f, -1.0f, 256.0f + 1.0f, std::nanf("")}) f.command(mav::kCmdDoSetMode, base, d);
  EXPECT_EQ(f.status.value("fc_command_denied"), 4);
  EXPECT_EQ((f.fc.custom_mode() >> 16) & 0xff, fact::sim_fc::kMainPosctl);  // the mode it started in
}

}  // namespace
