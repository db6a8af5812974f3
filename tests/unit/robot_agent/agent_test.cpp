// The agent's stack against a tiny kinematic world in the test: it localizes from odometry and
// compass, plans, follows, dwells, reports every task state in order, and stops for what is ahead.

#include <gtest/gtest.h>

#include <cmath>

#include "agent.hpp"
#include "fleet/control/diff_drive_kinematics.hpp"

using namespace fleet;

namespace {

struct World {
  Pose2 truth{1.0, 1.0, 0.0};
  double wheelBase = 0.4;
  std::uint32_t seq = 0;
  std::vector<msg::Detection> detections;

  msg::SensorFrame frame(double v, double w, double dt) {
    const Pose2 before = truth;
    truth = control::DiffDriveKinematics::integrateExact(truth, {v, w}, dt);
    (void)before;
    msg::SensorFrame f;
    f.robot_id = "r1";
    f.seq = seq++;
    // Wheel travel for the executed twist (exact arc).
    f.ds_left = (v - w * wheelBase / 2) * dt;
    f.ds_right = (v + w * wheelBase / 2) * dt;
    f.compass_valid = true;
    f.compass = truth.theta;
    f.range_max = 8.0f;
    f.detections = detections;
    f.battery = 0.9f;
    return f;
  }
};

std::shared_ptr<const planning::OccupancyGrid> emptyGrid() {
  return std::make_shared<const planning::OccupancyGrid>(40, 40, 0.25, Vec2{0, 0});
}

agent::AgentParams params() {
  agent::AgentParams p;
  p.id = "r1";
  p.start = {1.0, 1.0, 0.0};
  p.wheelBase = 0.4;
  return p;
}

msg::TaskAssignment transport() {
  msg::TaskAssignment a;
  a.robot_id = "r1";
  a.task_id = "t1";
  a.revision = 7;
  a.goals.push_back({{5.0, 1.0, 0.0}, "P-1", msg::GoalAction::Load, 1.0});
  a.goals.push_back({{5.0, 6.0, 1.57}, "D-1", msg::GoalAction::Unload, 1.0});
  return a;
}

}  // namespace

TEST(Agent, DeliversATransportTaskReportingEveryState) {
  auto grid = emptyGrid();
  agent::Agent a(params(), grid, grid);
  World world;
  a.onAssignment(transport());
  std::vector<msg::TaskState> states;
  const double dt = 0.1;
  double v = 0;
  double w = 0;
  for (int k = 0; k < 1200 && (states.empty() || states.back() != msg::TaskState::Done); ++k) {
    a.onFrame(world.frame(v, w, dt));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, dt);
    v = out.command.v;
    w = out.command.w;
    if (out.status) {
      EXPECT_EQ(out.status->task_id, "t1");
      EXPECT_EQ(out.status->revision, 7u);
      states.push_back(out.status->state);
    }
    EXPECT_EQ(out.discs.source_id, "r1");
    EXPECT_FALSE(out.discs.discs.empty());
  }
  const std::vector<msg::TaskState> expected = {msg::TaskState::EnRoute, msg::TaskState::Loading,
                                                msg::TaskState::Delivering, msg::TaskState::Unloading,
                                                msg::TaskState::Done};
  EXPECT_EQ(states, expected);
  EXPECT_LT(distance(world.truth, Pose2{5.0, 6.0, 0}), 0.3);
  EXPECT_LT(distance(a.pose(), world.truth), 0.05) << "odometry + compass keep the estimate close";
  EXPECT_FALSE(a.busy());
}

TEST(Agent, StopsForSomethingAheadAndReportsWaiting) {
  auto grid = emptyGrid();
  agent::Agent a(params(), grid, grid);
  World world;
  a.onAssignment(transport());
  double v = 0;
  double w = 0;
  // Let it start moving toward the pickup (straight ahead, +x).
  for (int k = 0; k < 20; ++k) {
    a.onFrame(world.frame(v, w, 0.1));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    v = out.command.v;
    w = out.command.w;
  }
  ASSERT_GT(v, 0.1);
  world.detections = {{msg::SourceKind::Human, 0.6f, 0.0f, 0.25f}};
  a.onFrame(world.frame(v, w, 0.1));
  const auto out = a.step(2'000'000'000, 0.1);
  EXPECT_LE(out.command.v, 1e-9);
  EXPECT_EQ(out.state.mode, msg::RobotMode::Waiting);
  // Beside the corridor, the same person does not stop the robot.
  world.detections = {{msg::SourceKind::Human, 0.6f, 1.2f, 0.25f}};
  a.onFrame(world.frame(0, 0, 0.1));
  EXPECT_GT(a.step(2'100'000'000, 0.1).command.v, 0.0);
}

TEST(Agent, CancelStopsAndIgnoresRepeatedOrders) {
  auto grid = emptyGrid();
  agent::Agent a(params(), grid, grid);
  World world;
  a.onAssignment(transport());
  a.onFrame(world.frame(0, 0, 0.1));
  (void)a.step(0, 0.1);
  EXPECT_TRUE(a.busy());
  auto cancel = transport();
  cancel.task_id.clear();
  cancel.goals.clear();
  cancel.revision = 8;
  a.onAssignment(cancel);
  EXPECT_FALSE(a.busy());
  const auto out = a.step(100'000'000, 0.1);
  EXPECT_EQ(out.command.v, 0.0);
  EXPECT_EQ(out.state.mode, msg::RobotMode::Idle);
  msg::TaskAssignment other = transport();
  other.robot_id = "r2";
  a.onAssignment(other);
  EXPECT_FALSE(a.busy()) << "another robot's order is not ours";
}

// A robot whose SensorFrame stream stops holds still, reports RM_FAULT and a TaskStatus naming the
// reason, keeps its task, and drives on to finish it when frames come back.
TEST(Agent, SensorStreamLossStopsReportsAndResumes) {
  auto grid = emptyGrid();
  auto p = params();
  p.sensorTimeoutS = 0.5;
  agent::Agent a(p, grid, grid);
  World world;
  a.onAssignment(transport());
  double v = 0;
  double w = 0;
  std::int64_t now = 0;
  const std::int64_t tick = 100'000'000;
  for (int k = 0; k < 20; ++k, now += tick) {
    a.onFrame(world.frame(v, w, 0.1));
    const auto out = a.step(now, 0.1);
    v = out.command.v;
    w = out.command.w;
  }
  ASSERT_GT(v, 0.1) << "moving before the loss";
  // Frames stop: within the timeout the robot goes on; past it, zero command and a fault.
  std::vector<agent::AgentOutput> blind;
  for (int k = 0; k < 30; ++k, now += tick) {
    blind.push_back(a.step(now, 0.1));
  }
  EXPECT_NE(blind[3].state.mode, msg::RobotMode::Fault) << "0.4 s without frames is within 0.5 s";
  int faultAt = -1;
  int statuses = 0;
  for (int k = 0; k < static_cast<int>(blind.size()); ++k) {
    if (blind[static_cast<std::size_t>(k)].state.mode == msg::RobotMode::Fault && faultAt < 0) {
      faultAt = k;
    }
    if (const auto& s = blind[static_cast<std::size_t>(k)].status) {
      ++statuses;
      EXPECT_EQ(s->task_id, "t1");
      EXPECT_NE(s->error.find("sensor stream lost"), std::string::npos) << s->error;
      EXPECT_EQ(s->state, msg::TaskState::EnRoute) << "the task is kept, not failed";
    }
  }
  EXPECT_EQ(faultAt, 5) << "the first step more than 0.5 s after the last frame";
  EXPECT_EQ(statuses, 1) << "one report when the stream is lost";
  for (std::size_t k = static_cast<std::size_t>(faultAt); k < blind.size(); ++k) {
    EXPECT_EQ(blind[k].command.v, 0.0);
    EXPECT_EQ(blind[k].command.w, 0.0);
    EXPECT_EQ(blind[k].state.mode, msg::RobotMode::Fault);
    EXPECT_EQ(blind[k].state.v, 0.0);
  }
  EXPECT_TRUE(a.sensorLost());
  EXPECT_TRUE(a.busy());
  // The robot really stood still from the fault on (the world executes the last command once).
  v = 0;
  w = 0;
  // Frames come back: the fault clears at once, a status without error says so, and the task ends.
  std::vector<msg::TaskState> after;
  bool clearedReported = false;
  for (int k = 0; k < 1500 && (after.empty() || after.back() != msg::TaskState::Done); ++k, now += tick) {
    a.onFrame(world.frame(v, w, 0.1));
    const auto out = a.step(now, 0.1);
    if (k == 0) {
      EXPECT_NE(out.state.mode, msg::RobotMode::Fault);
      ASSERT_TRUE(out.status.has_value());
      EXPECT_TRUE(out.status->error.empty());
      clearedReported = true;
    }
    v = out.command.v;
    w = out.command.w;
    if (out.status && k > 0) {
      after.push_back(out.status->state);
    }
  }
  EXPECT_TRUE(clearedReported);
  ASSERT_FALSE(after.empty());
  EXPECT_EQ(after.back(), msg::TaskState::Done);
  EXPECT_FALSE(a.sensorLost());
}
