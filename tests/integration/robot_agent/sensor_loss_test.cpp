// robot_agent as a real process (wall clock) beside a traffic manager (reserved traffic: it
// releases the route), with this test playing the robot's driver over DDS: while frames flow and a
// task is assigned the robot drives; when the SensorFrame stream stops it commands zero, reports
// RM_FAULT in RobotState and a TaskStatus naming the reason; when frames come back it clears the
// fault and drives again.

#include <gtest/gtest.h>

#include <cmath>

#include <chrono>
#include <thread>

#include "fleet/core/clock.hpp"
#include "fleet/transport/dds.hpp"
#include "fleet_stack.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;
using Clk = std::chrono::steady_clock;

namespace {

struct Seen {
  std::optional<msg::VelocityCommand> command;
  std::optional<msg::RobotState> state;
  std::vector<msg::TaskStatus> statuses;
};

}  // namespace

TEST(RobotAgentSensorLoss, StopsReportsFaultAndResumes) {
  const std::string domain = std::to_string(test::uniqueDomain());
  setenv("FLEET_DDS_DOMAIN", domain.c_str(), 1);
  const auto dir = std::filesystem::temp_directory_path() / ("agent_sensor_loss_" + domain);
  std::filesystem::create_directories(dir);
  // On the wall clock: no simulator publishes a Clock here.
  test::ChildProcess traffic(test::kTrafficManagerBinary,
                             test::trafficManagerArgs(dir, FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json",
                                                      false, {{"clock", "wall"}}),
                             {{"FLEET_DDS_DOMAIN", domain}});
  test::ChildProcess agent(
      FLEET_BINARY_DIR "/services/robot_agent/robot_agent",
      {"--scenario", FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json", "--robots", "r1", "--clock", "wall",
       "--sensor-timeout", "0.5", "--threads", "2", "--log-level", "warn"},
      {{"FLEET_DDS_DOMAIN", domain}});
  transport::Participant part;
  transport::Writer<msg::SensorFrame> frames(part);
  transport::Writer<msg::TaskAssignment> assignments(part);
  transport::Reader<msg::VelocityCommand> commands(part);
  transport::Reader<msg::RobotState> states(part);
  transport::Reader<msg::TaskStatus> statuses(part);

  msg::TaskAssignment order;
  order.robot_id = "r1";
  order.task_id = "t-loss";
  order.revision = 1;
  order.goals.push_back({{1.5, 4.0, 0.0}, "CHG-1", msg::GoalAction::Load, 1.0});

  Seen seen;
  std::uint32_t seq = 0;
  auto pump = [&](bool sendFrames) {
    if (sendFrames) {
      msg::SensorFrame f;
      f.robot_id = "r1";
      f.seq = seq++;
      f.stamp_ns = WallClock{}.nowNs();
      f.compass_valid = true;
      f.compass = 1.5708;
      f.range_max = 8.0f;
      f.battery = 0.9f;
      frames.write(f);
    }
    for (const auto& c : commands.take()) {
      if (c.robot_id == "r1") {
        seen.command = c;
      }
    }
    for (const auto& s : states.take()) {
      if (s.robot_id == "r1") {
        seen.state = s;
      }
    }
    for (const auto& s : statuses.take()) {
      seen.statuses.push_back(s);
    }
    std::this_thread::sleep_for(50ms);
  };
  auto until = [&](bool sendFrames, std::chrono::seconds limit, const auto& done) {
    const auto end = Clk::now() + limit;
    while (Clk::now() < end) {
      pump(sendFrames);
      if (done()) {
        return true;
      }
    }
    return false;
  };

  // Live: frames flow, the order arrives, the robot wants to move.
  ASSERT_TRUE(until(true, 20s, [&] { return seen.state.has_value(); })) << "no RobotState from the agent";
  assignments.write(order);
  // Moving means any command: this driver never moves the robot, so a planner that turns towards
  // its path first (the default DWA's rotation shim) keeps turning.
  const auto moving = [&] {
    return seen.command && (seen.command->v > 0.05 || std::abs(seen.command->w) > 0.05);
  };
  ASSERT_TRUE(until(true, 20s, [&] {
    return moving() && seen.state && seen.state->mode != msg::RobotMode::Fault;
  })) << "the robot never drove while frames flowed";
  seen.statuses.clear();

  // Frames stop: zero command, RM_FAULT, a TaskStatus with the reason; the task is kept.
  ASSERT_TRUE(until(false, 10s, [&] { return seen.state && seen.state->mode == msg::RobotMode::Fault; }))
      << "no RM_FAULT after the stream stopped";
  for (int k = 0; k < 6; ++k) {
    pump(false);  // a few more cycles: the fault holds
  }
  ASSERT_TRUE(seen.command);
  EXPECT_EQ(seen.command->v, 0.0);
  EXPECT_EQ(seen.command->w, 0.0);
  EXPECT_EQ(seen.state->mode, msg::RobotMode::Fault);
  EXPECT_EQ(seen.state->task_id, "t-loss");
  bool reported = false;
  for (const auto& s : seen.statuses) {
    if (s.robot_id == "r1" && s.task_id == "t-loss" &&
        s.error.find("sensor stream lost") != std::string::npos) {
      reported = true;
      EXPECT_NE(s.state, msg::TaskState::Failed);
    }
  }
  EXPECT_TRUE(reported) << "no TaskStatus naming the sensor loss";

  // Frames come back: the fault clears and the robot drives on.
  ASSERT_TRUE(until(true, 10s, [&] {
    return seen.state && seen.state->mode != msg::RobotMode::Fault && moving();
  })) << "the robot did not resume";
  std::filesystem::remove_all(dir);
}
