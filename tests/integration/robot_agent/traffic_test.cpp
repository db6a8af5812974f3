// robot_agent as a process over DDS in reserved traffic, with this test playing the traffic manager
// (and the robot's driver): the agent reports TrafficProgress (at least once a second, before any
// release with node -1), takes a TrafficRelease for its robot from the node next to it and reports
// that node and the release's epoch; a release for another robot changes nothing.

#include <gtest/gtest.h>

#include <chrono>
#include <optional>
#include <thread>

#include "fleet/core/clock.hpp"
#include "fleet/transport/dds.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;
using Clk = std::chrono::steady_clock;

namespace {

struct Driver {
  transport::Participant part;
  transport::Writer<msg::SensorFrame> frames{part};
  transport::Writer<msg::TrafficRelease> releases{part};
  transport::Reader<msg::RobotState> states{part};
  transport::Reader<msg::TrafficProgress> progress{part};
  std::optional<msg::RobotState> state;
  std::vector<msg::TrafficProgress> reports;
  std::uint32_t seq = 0;

  /// One frame (the robot stands still), then whatever came back.
  void pump() {
    msg::SensorFrame f;
    f.robot_id = "r1";
    f.seq = seq++;
    f.stamp_ns = WallClock{}.nowNs();
    f.range_max = 8.0f;
    f.battery = 0.9f;
    frames.write(f);
    for (const auto& s : states.take()) {
      if (s.robot_id == "r1") {
        state = s;
      }
    }
    for (const auto& p : progress.take()) {
      reports.push_back(p);
    }
    std::this_thread::sleep_for(50ms);
  }

  template <typename Done>
  bool until(std::chrono::seconds limit, const Done& done) {
    const auto end = Clk::now() + limit;
    while (Clk::now() < end) {
      pump();
      if (done()) {
        return true;
      }
    }
    return false;
  }
};

test::ChildProcess startAgent(const std::string& domain) {
  return test::ChildProcess(FLEET_BINARY_DIR "/services/robot_agent/robot_agent",
                            {"--scenario", FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json", "--robots", "r1",
                             "--clock", "wall", "--log-level", "warn"},
                            {{"FLEET_DDS_DOMAIN", domain}});
}

}  // namespace

TEST(RobotAgentTraffic, ReservedReportsProgressAndTakesItsReleases) {
  const std::string domain = std::to_string(test::uniqueDomain());
  setenv("FLEET_DDS_DOMAIN", domain.c_str(), 1);
  auto agent = startAgent(domain);
  Driver d;
  ASSERT_TRUE(d.until(20s, [&] { return d.state && !d.reports.empty(); })) << "no TrafficProgress";
  const msg::TrafficProgress first = d.reports.back();
  EXPECT_EQ(first.robot_id, "r1");
  EXPECT_EQ(first.node, -1) << "no release yet: the traffic manager places it by its pose";
  EXPECT_EQ(first.epoch, 0u);
  EXPECT_TRUE(first.follows);
  EXPECT_TRUE(first.has_goal) << "idle: its parking place";
  // A heartbeat: more reports while nothing changes.
  d.reports.clear();
  d.until(3s, [] { return false; });
  EXPECT_GE(d.reports.size(), 2u);

  const Pose2 at = d.state->pose;
  msg::TrafficRelease other;
  other.robot_id = "r9";
  other.epoch = 4;
  other.seq = 1;
  other.base = {{55, at.x, at.y}, {56, at.x, at.y + 0.5}};
  d.releases.write(other);
  msg::TrafficRelease mine = other;
  mine.robot_id = "r1";
  mine.base = {{7, at.x + 0.1, at.y}, {8, at.x + 0.1, at.y + 0.5}};
  d.releases.write(mine);
  ASSERT_TRUE(d.until(10s, [&] { return !d.reports.empty() && d.reports.back().node == 7; }))
      << "the release was not taken";
  for (const auto& r : d.reports) {
    EXPECT_NE(r.node, 55) << "took another robot's release";
  }
  EXPECT_EQ(d.reports.back().epoch, 4u);
}
