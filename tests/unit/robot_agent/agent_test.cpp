// The agent's stack against a tiny kinematic world in the test: it localizes from odometry and
// compass, plans, follows, dwells, reports every task state in order, and stops for what is ahead.

#include <gtest/gtest.h>

#include <limits>

#include <algorithm>
#include <cmath>
#include <optional>

#include "agent.hpp"
#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/core/angles.hpp"
#include "fleet/geometry/grid_raycast.hpp"

using namespace fleet;

namespace {

struct World {
  Pose2 truth{1.0, 1.0, 0.0};
  double wheelBase = 0.4;
  std::uint32_t seq = 0;
  std::vector<msg::Detection> detections;
  bool wheelTotals = false;  // send SensorFrame.wheel_*_total too
  double leftTotal = 0.0;
  double rightTotal = 0.0;

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
    leftTotal += f.ds_left;
    rightTotal += f.ds_right;
    f.wheel_totals_valid = wheelTotals;
    f.wheel_left_total = leftTotal;
    f.wheel_right_total = rightTotal;
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

class GlobalPlannerChoice : public ::testing::TestWithParam<const char*> {};

TEST_P(GlobalPlannerChoice, DeliversAroundAWallWithoutEnteringIt) {
  // A wall from y = 0 to y = 4.5 at x = 3 stands between the start (1, 1) and the pickup (5, 1):
  // only a plan around its top end gets there (the test world has no scan, so the stop rule
  // cannot save a path through it). The follower drives, so the path is what is tested: with the
  // DWA, OMPL's paths, which cut the wall's corner at the margin, left the robot at the corner in
  // about 4 runs of 10, every move onward closing in on it (docs/algorithms.md, fifth round).
  auto raw = std::make_shared<planning::OccupancyGrid>(40, 40, 0.25, Vec2{0, 0});
  for (int y = 0; y < 18; ++y) {
    raw->setBlocked({12, y});
  }
  auto grid = agent::inflate(*raw, 0.5);
  auto p = params();
  p.globalPlanner = GetParam();
  p.localPlanner = "follow";
  agent::Agent a(p, grid, raw);
  World world;
  a.onAssignment(transport());
  int k = 0;
  bool done = false;
  double minWall = 1e9;
  double v = 0;
  double w = 0;
  for (; k < 3000 && !done; ++k) {
    a.onFrame(world.frame(v, w, 0.1));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    v = out.command.v;
    w = out.command.w;
    done = out.status && out.status->state == msg::TaskState::Done;
    ASSERT_FALSE(out.status && out.status->state == msg::TaskState::Failed)
        << GetParam() << ": " << out.status->error << " at " << world.truth.x << ", " << world.truth.y;
    // Distance from the robot's centre to the wall's rectangle [3, 3.25] x [0, 4.5].
    const double dx = std::max({3.0 - world.truth.x, 0.0, world.truth.x - 3.25});
    const double dy = std::max(0.0, world.truth.y - 4.5);
    minWall = std::min(minWall, std::hypot(dx, dy));
  }
  EXPECT_TRUE(done) << GetParam();
  EXPECT_GT(minWall, 0.3) << GetParam() << ": the robot's body touched the wall";
  EXPECT_LT(distance(world.truth, Pose2{5.0, 6.0, 0}), 0.3);
}

INSTANTIATE_TEST_SUITE_P(Agent, GlobalPlannerChoice, ::testing::Values("astar", "wavefront", "ompl"));

TEST(Agent, UnknownGlobalPlannerIsRefusedByName) {
  auto p = params();
  p.globalPlanner = "dijkstra";
  try {
    agent::Agent a(p, emptyGrid(), emptyGrid());
    FAIL() << "accepted";
  } catch (const std::invalid_argument& e) {
    EXPECT_NE(std::string(e.what()).find("dijkstra"), std::string::npos) << e.what();
  }
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

namespace {
// Steps the agent in the test world until `until` holds or `steps` run out; returns the statuses.
template <class Until>
std::vector<msg::TaskStatus> run(agent::Agent& a, World& world, int& k, int steps, Until until,
                                 double* minDistTo = nullptr, Vec2 to = {}) {
  std::vector<msg::TaskStatus> statuses;
  double v = 0;
  double w = 0;
  for (int i = 0; i < steps && !until(); ++i, ++k) {
    a.onFrame(world.frame(v, w, 0.1));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    v = out.command.v;
    w = out.command.w;
    if (out.status) {
      statuses.push_back(*out.status);
    }
    if (minDistTo != nullptr) {
      *minDistTo = std::min(*minDistTo, distance(world.truth.position(), to));
    }
  }
  return statuses;
}

msg::RobotState parked(const std::string& id, Vec2 at) {
  msg::RobotState s;
  s.robot_id = id;
  s.pose = {at.x, at.y, 0.0};
  s.mode = msg::RobotMode::Idle;
  return s;
}
}  // namespace

TEST(Agent, PausedOrderHoldsStillLongerThanTheFailTimeoutAndResumes) {
  auto grid = emptyGrid();
  agent::Agent a(params(), grid, grid);
  World world;
  a.onAssignment(transport());
  int k = 0;
  (void)run(a, world, k, 20, [] { return false; });
  ASSERT_GT(world.truth.x, 1.2) << "under way";
  auto hold = transport();
  hold.revision = 8;
  hold.paused = true;
  a.onAssignment(hold);
  EXPECT_TRUE(a.paused());
  // Twice the 60 s fail timeout: no status (no failure), standing still, reporting `waiting`.
  const Pose2 at = world.truth;
  double v = 0;
  double w = 0;
  for (int i = 0; i < 1200; ++i, ++k) {
    a.onFrame(world.frame(v, w, 0.1));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    v = out.command.v;
    w = out.command.w;
    ASSERT_FALSE(out.status) << "reported " << msg::toString(out.status->state) << " while paused";
    EXPECT_EQ(out.state.mode, msg::RobotMode::Waiting);
  }
  EXPECT_LT(distance(world.truth, at), 0.05) << "moved while paused";
  EXPECT_TRUE(a.busy());
  auto go = transport();
  go.revision = 9;
  a.onAssignment(go);
  EXPECT_FALSE(a.paused());
  const auto statuses = run(a, world, k, 1500, [&] { return !a.busy(); });
  ASSERT_FALSE(statuses.empty());
  EXPECT_EQ(statuses.back().state, msg::TaskState::Done);
}

TEST(Agent, QueueForAStationBacksAwayWhenTheRobotOnItWantsOut) {
  auto grid = emptyGrid();
  agent::Agent a(params(), grid, grid);
  World world;
  a.onAssignment(transport());  // pickup P-1 at (5, 1)
  msg::RobotState onStation = parked("r2", {5.0, 1.0});
  onStation.mode = msg::RobotMode::Loading;
  onStation.task_id = "t9";
  int k = 0;
  double closest = 1e9;
  auto stepWith = [&](int n) {
    double v = 0;
    double w = 0;
    for (int i = 0; i < n; ++i, ++k) {
      a.onOtherRobot(onStation);
      a.onFrame(world.frame(v, w, 0.1));
      const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
      v = out.command.v;
      w = out.command.w;
      closest = std::min(closest, distance(world.truth.position(), Vec2{5.0, 1.0}));
    }
  };
  stepWith(150);
  const double queued = distance(world.truth.position(), Vec2{5.0, 1.0});
  EXPECT_GE(queued, 1.4);
  EXPECT_LE(queued, 2.1) << "queues 1.5-2 m off the occupied station";
  // Loading done, it wants out (held up: waiting). The queue makes room: about 1 m further back.
  onStation.mode = msg::RobotMode::Waiting;
  stepWith(150);
  const double room = distance(world.truth.position(), Vec2{5.0, 1.0});
  EXPECT_GT(room, queued + 0.6) << "did not make room";
  EXPECT_LE(room, 3.4) << "backed away too far";
  // Gone: the station is free and the robot drives on to it.
  onStation.pose = {9.0, 9.0, 0.0};
  onStation.mode = msg::RobotMode::Moving;
  closest = 1e9;
  stepWith(150);
  EXPECT_LT(closest, 0.2) << "did not go on to the station once it was free";
}

TEST(Agent, ReturnsHomeWhenIdleWithoutReportingTheTrip) {
  auto grid = emptyGrid();
  auto p = params();
  p.returnHomeS = 2.0;
  agent::Agent a(p, grid, grid);
  World world;
  a.onAssignment(transport());
  int k = 0;
  auto statuses = run(a, world, k, 1500, [&] { return !a.busy() && k > 10; });
  ASSERT_FALSE(statuses.empty());
  ASSERT_EQ(statuses.back().state, msg::TaskState::Done);
  ASSERT_GT(distance(world.truth.position(), p.start.position()), 3.0);
  // Idle at the drop-off: after 2 s it drives home, reporting nothing (no order of the manager's).
  const auto during = run(a, world, k, 1500, [&] {
    return distance(world.truth.position(), p.start.position()) < 0.2 && !a.homing();
  });
  EXPECT_TRUE(during.empty());
  EXPECT_LT(distance(world.truth.position(), p.start.position()), 0.2);
  EXPECT_FALSE(a.busy());
  EXPECT_FALSE(a.homing());
}

TEST(Agent, NewOrderPreemptsTheTripHome) {
  auto grid = emptyGrid();
  auto p = params();
  p.returnHomeS = 0.5;
  agent::Agent a(p, grid, grid);
  World world;
  a.onAssignment(transport());
  int k = 0;
  (void)run(a, world, k, 1500, [&] { return !a.busy() && k > 10; });
  (void)run(a, world, k, 20, [] { return false; });
  ASSERT_TRUE(a.homing());
  auto order = transport();
  order.task_id = "t2";
  order.revision = 8;
  a.onAssignment(order);
  EXPECT_FALSE(a.homing());
  const auto statuses = run(a, world, k, 1500, [&] { return !a.busy(); });
  ASSERT_FALSE(statuses.empty());
  EXPECT_EQ(statuses.front().task_id, "t2");
  EXPECT_EQ(statuses.front().state, msg::TaskState::EnRoute);
  EXPECT_EQ(statuses.back().state, msg::TaskState::Done);
}

TEST(Agent, AHeldIdleRobotStandsStillInsteadOfDrivingHomeUntilReleased) {
  auto grid = emptyGrid();
  auto p = params();
  p.returnHomeS = 0.5;
  agent::Agent a(p, grid, grid);
  World world;
  a.onAssignment(transport());
  int k = 0;
  (void)run(a, world, k, 1500, [&] { return !a.busy() && k > 10; });
  (void)run(a, world, k, 20, [] { return false; });
  ASSERT_TRUE(a.homing()) << "idle away from home: on its way back";
  msg::TaskAssignment hold;
  hold.robot_id = p.id;
  hold.revision = 20;
  hold.paused = true;  // the manager's answer to TC_HOLD_ROBOT for an idle robot
  a.onAssignment(hold);
  const Vec2 heldAt = world.truth.position();
  (void)run(a, world, k, 100, [] { return false; });  // 10 s, far beyond returnHomeS
  EXPECT_FALSE(a.homing());
  EXPECT_TRUE(a.paused());
  EXPECT_LT(distance(world.truth.position(), heldAt), 0.05) << "a held robot drove on";
  hold.revision = 21;
  hold.paused = false;
  a.onAssignment(hold);
  (void)run(a, world, k, 1500, [&] { return distance(world.truth.position(), p.start.position()) < 0.2; });
  EXPECT_LT(distance(world.truth.position(), p.start.position()), 0.2) << "released, it goes home";
}

TEST(Agent, PlansAroundARobotParkedOnItsWay) {
  auto grid = emptyGrid();
  agent::Agent a(params(), grid, grid);
  World world;
  // Parked (idle, no task) right on the straight line to the pickup at (5, 1). The test world has
  // no sensor model of it: only the plan can keep the robot away.
  a.onOtherRobot(parked("r2", {3.0, 1.0}));
  a.onAssignment(transport());
  int k = 0;
  double minDist = 1e9;
  const auto statuses = run(a, world, k, 1500, [&] { return !a.busy() && k > 10; }, &minDist, {3.0, 1.0});
  ASSERT_FALSE(statuses.empty());
  EXPECT_EQ(statuses.back().state, msg::TaskState::Done);
  EXPECT_GE(minDist, 2 * params().radius) << "drove through the parked robot";
}

TEST(Agent, StopsForARobotCrossingFromTheSide) {
  auto grid = emptyGrid();
  agent::Agent a(params(), grid, grid);
  World world;
  a.onAssignment(transport());
  int k = 0;
  (void)run(a, world, k, 25, [] { return false; });
  ASSERT_GT(world.truth.x, 1.3);
  // Another robot 1 m ahead and 1 m to the right, driving across the path at 0.8 m/s: on
  // collision course, but outside the straight corridor ahead that the stop rule watches.
  msg::RobotState other;
  other.robot_id = "r2";
  other.pose = {world.truth.x + 0.9, world.truth.y - 0.9, M_PI / 2};
  other.v = 0.8;
  other.mode = msg::RobotMode::Moving;
  other.task_id = "t9";
  a.onOtherRobot(other);
  a.onFrame(world.frame(0.8, 0.0, 0.1));
  const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
  EXPECT_LT(out.command.v, 0.5) << "did not slow for the crossing robot";
}

TEST(Agent, BacksOutOfANarrowPassageAlongItsTrailAndTakesTheOtherWay) {
  // 10 m x 10 m: two rooms joined by a 1.25 m passage (one robot wide) and, further round, by a
  // 2 m corridor. A robot with a smaller id stands in the passage facing this one, waiting on it.
  auto raw = std::make_shared<planning::OccupancyGrid>(40, 40, 0.25, Vec2{0, 0});
  for (int y = 0; y < 40; ++y) {
    for (int x = 10; x < 30; ++x) {
      const double cy = raw->cellCenter({x, y}).y;
      const bool passage = cy > 4.25 && cy < 5.5;
      const bool corridor = cy > 8.0;
      if (!passage && !corridor) {
        raw->setBlocked({x, y});
      }
    }
  }
  auto grid = agent::inflate(*raw, 0.3);
  auto p = params();
  p.id = "r2";
  p.start = {1.0, 4.875, 0.0};
  agent::Agent a(p, grid, raw);
  World world;
  world.truth = p.start;
  msg::TaskAssignment order;
  order.robot_id = "r2";
  order.task_id = "t1";
  order.revision = 1;
  order.goals.push_back({{9.0, 4.875, 0.0}, "D-1", msg::GoalAction::Unload, 0.5});
  a.onAssignment(order);
  const Vec2 blocker{5.5, 4.875};
  msg::RobotState other;
  other.robot_id = "r1";
  other.pose = {blocker.x, blocker.y, M_PI};
  other.mode = msg::RobotMode::Waiting;
  other.task_id = "t9";
  double v = 0;
  double w = 0;
  double minDist = 1e9;
  bool done = false;
  double maxX = 0.0;
  for (int k = 0; k < 2000 && !done; ++k) {
    // The blocker as the robot's sensors see it, in the robot's frame.
    const Vec2 rel = blocker - world.truth.position();
    const double c = std::cos(world.truth.theta);
    const double s = std::sin(world.truth.theta);
    world.detections = {{msg::SourceKind::Robot, static_cast<float>(c * rel.x + s * rel.y),
                         static_cast<float>(-s * rel.x + c * rel.y), 0.3f}};
    a.onOtherRobot(other);
    a.onFrame(world.frame(v, w, 0.1));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    v = out.command.v;
    w = out.command.w;
    done = out.status && out.status->state == msg::TaskState::Done;
    minDist = std::min(minDist, distance(world.truth.position(), blocker));
    if (world.truth.y < 6.0 && world.truth.x < 7.5) {  // in the passage
      maxX = std::max(maxX, world.truth.x);
    }
    ASSERT_FALSE(out.status && out.status->state == msg::TaskState::Failed) << out.status->error;
  }
  EXPECT_TRUE(done);
  EXPECT_GE(a.conduct().returns, 1u) << "backed out along its trail";
  // Where the passage meets the corridor the DWA (the default planner) turns in place for good, a
  // local minimum nothing else notices; the follower takes over for a while and the robot gets on.
  EXPECT_GE(a.conduct().plannerRecoveries, 1u) << "the local planner never handed over";
  EXPECT_GE(a.conduct().mutualBlocks, 1u) << "the blocker waits on it: a wait cycle";
  EXPECT_GE(minDist, 0.6 + 0.2) << "kept clear of the robot it yielded to";
  EXPECT_LT(maxX, blocker.x) << "never went past the blocker in the passage";
  EXPECT_LT(distance(world.truth, Pose2{9.0, 4.875, 0.0}), 0.3);
}

TEST(Agent, ReachesAStationInsideThePlanningMarginWithoutHuggingTheWall) {
  // 10 m x 5 m at the warehouse's 0.5 m cells: a wall along the bottom and a shelf above a 2 m
  // corridor (as the parking band). The station at y = 0.9 is 0.4 m from the wall, so its cell is
  // blocked on the planning grid (map inflated by radius + 0.2). Planning there fell back to the
  // raw map, whose shortest path runs along the wall 0.25 m off it, where the stop rule (which sees
  // the wall ahead in its corridor) never lets the robot drive.
  auto raw = std::make_shared<planning::OccupancyGrid>(20, 10, 0.5, Vec2{0, 0});
  for (int x = 0; x < 20; ++x) {
    raw->setBlocked({x, 0});
    for (int y = 5; y < 10 && x >= 6 && x < 16; ++y) {
      raw->setBlocked({x, y});
    }
  }
  auto grid = agent::inflate(*raw, 0.5);
  ASSERT_TRUE(grid->blocked(*grid->cellAt({1.5, 0.9})));
  auto p = params();
  p.start = {9.0, 1.5, M_PI};
  agent::Agent a(p, grid, raw);
  World world;
  world.truth = p.start;
  msg::TaskAssignment order;
  order.robot_id = "r1";
  order.task_id = "t1";
  order.revision = 1;
  order.goals.push_back({{1.5, 0.9, M_PI / 2}, "PARK-1", msg::GoalAction::Unload, 0.5});
  a.onAssignment(order);
  double v = 0;
  double w = 0;
  bool done = false;
  double minWall = 1e9;
  const auto view = raw->view();
  for (int k = 0; k < 600 && !done; ++k) {
    auto f = world.frame(v, w, 0.1);
    f.angle_min = static_cast<float>(-M_PI);
    f.angle_increment = static_cast<float>(2.0 * M_PI / 72.0);
    for (int i = 0; i < 72; ++i) {
      const double ang = world.truth.theta - M_PI + i * 2.0 * M_PI / 72.0;
      f.ranges.push_back(
          static_cast<float>(geometry::raycastGrid(view, world.truth.position(), ang, 8.0).range));
    }
    a.onFrame(f);
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    v = out.command.v;
    w = out.command.w;
    done = out.status && out.status->state == msg::TaskState::Done;
    ASSERT_FALSE(out.status && out.status->state == msg::TaskState::Failed) << out.status->error;
    if (world.truth.x > 3.5) {  // along the corridor, before the final approach
      minWall = std::min(minWall, world.truth.y - 0.5);
    }
  }
  EXPECT_TRUE(done) << "stalled at " << world.truth.x << ", " << world.truth.y;
  EXPECT_GT(minWall, 0.5) << "drove along the wall";
  EXPECT_LT(distance(world.truth.position(), Vec2{1.5, 0.9}), 0.2);
}

TEST(Agent, PassesRobotsParkedBesideItsWayInsteadOfWaitingOnThem) {
  // The parking band of the warehouse: a wall along the bottom, robots parked every metre at
  // y = 0.9, a shelf above a 2 m corridor. A robot driving home stopped 0.8 m above the row,
  // facing down-left across its path west: its first arc toward the path swept within a body of
  // a parked robot, the safety layer held it, the standoff rule re-planned around the "standing
  // blocker" every 3 s (the same path) and restarted its clock each time, so it stood there for
  // three minutes until the progress watch failed the trip.
  auto raw = std::make_shared<planning::OccupancyGrid>(40, 10, 0.5, Vec2{0, 0});
  for (int x = 0; x < 40; ++x) {
    raw->setBlocked({x, 0});
    for (int y = 5; y < 10 && x >= 6 && x < 36; ++y) {
      raw->setBlocked({x, y});
    }
  }
  auto grid = agent::inflate(*raw, 0.5);
  auto p = params();
  p.id = "r7";
  p.start = {17.43, 1.68, -2.78};
  agent::Agent a(p, grid, raw);
  World world;
  world.truth = p.start;
  msg::TaskAssignment order;
  order.robot_id = "r7";
  order.task_id = "t1";
  order.revision = 1;
  order.goals.push_back({{9.0, 0.9, M_PI / 2}, "PARK-7", msg::GoalAction::Park, 0.0});
  a.onAssignment(order);
  std::vector<msg::RobotState> parkedRow;
  for (int x = 10; x <= 19; ++x) {
    parkedRow.push_back(parked("p" + std::to_string(x), {static_cast<double>(x), 0.9}));
  }
  double v = 0;
  double w = 0;
  bool done = false;
  double closest = 1e9;
  for (int k = 0; k < 900 && !done; ++k) {
    for (const auto& s : parkedRow) {
      a.onOtherRobot(s);
      closest = std::min(closest, distance(world.truth.position(), s.pose.position()));
    }
    a.onFrame(world.frame(v, w, 0.1));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    v = out.command.v;
    w = out.command.w;
    done = out.status && out.status->state == msg::TaskState::Done;
    ASSERT_FALSE(out.status && out.status->state == msg::TaskState::Failed) << out.status->error;
  }
  EXPECT_TRUE(done) << "stood at " << world.truth.x << ", " << world.truth.y;
  EXPECT_GE(closest, 0.6) << "touched a parked robot";
}

TEST(Agent, ARobotParkedInAPassageFailsTheTaskAfterTheBlockedTimeout) {
  // A 1 m passage (one robot wide) with a robot parked in it and no other way: re-planning around
  // the parked robot finds nothing, and the task must fail after blockedFailS (60 s) with the
  // blocker named — not stand for three minutes because each re-plan restarted the clock.
  auto raw = std::make_shared<planning::OccupancyGrid>(40, 40, 0.25, Vec2{0, 0});
  for (int y = 0; y < 40; ++y) {
    for (int x = 8; x < 32; ++x) {
      const double cy = raw->cellCenter({x, y}).y;
      if (cy < 4.5 || cy > 5.5) {
        raw->setBlocked({x, y});
      }
    }
  }
  auto grid = agent::inflate(*raw, 0.3);
  auto p = params();
  p.start = {1.0, 5.0, 0.0};
  agent::Agent a(p, grid, raw);
  World world;
  world.truth = p.start;
  msg::TaskAssignment order;
  order.robot_id = "r1";
  order.task_id = "t1";
  order.revision = 1;
  order.goals.push_back({{9.5, 5.0, 0.0}, "D-1", msg::GoalAction::Unload, 0.5});
  a.onAssignment(order);
  const Vec2 blocker{5.0, 5.0};
  double v = 0;
  double w = 0;
  std::optional<msg::TaskStatus> failed;
  int k = 0;
  for (; k < 1200 && !failed; ++k) {
    const Vec2 rel = blocker - world.truth.position();
    const double c = std::cos(world.truth.theta);
    const double s = std::sin(world.truth.theta);
    world.detections = {{msg::SourceKind::Robot, static_cast<float>(c * rel.x + s * rel.y),
                         static_cast<float>(-s * rel.x + c * rel.y), 0.3f}};
    a.onOtherRobot(parked("r9", blocker));
    a.onFrame(world.frame(v, w, 0.1));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    v = out.command.v;
    w = out.command.w;
    if (out.status && out.status->state == msg::TaskState::Failed) {
      failed = out.status;
    }
  }
  ASSERT_TRUE(failed) << "still waiting after " << k / 10 << " s";
  EXPECT_NE(failed->error.find("blocked by r9"), std::string::npos) << failed->error;
  EXPECT_LT(k, 900) << "failed only after " << k / 10 << " s";
}

TEST(Agent, BackingOntoAStationStopsForAPersonBehind) {
  // The goal lies 0.4 m behind the robot, facing the robot's heading: the pose law backs onto it.
  // A person stands behind, on the way: reversing is held by the rear check.
  auto grid = emptyGrid();
  auto p = params();
  p.start = {5.0, 2.3, M_PI / 2};
  agent::Agent a(p, grid, grid);
  World world;
  world.truth = p.start;
  msg::TaskAssignment order;
  order.robot_id = "r1";
  order.task_id = "t1";
  order.revision = 1;
  order.goals.push_back({{5.0, 1.9, M_PI / 2}, "PARK-1", msg::GoalAction::Park, 0.0});
  a.onAssignment(order);
  const Vec2 person{5.0, 1.5};
  double v = 0;
  double w = 0;
  double closest = 1e9;
  bool reversed = false;
  for (int k = 0; k < 100; ++k) {
    const Vec2 rel = person - world.truth.position();
    const double c = std::cos(world.truth.theta);
    const double s = std::sin(world.truth.theta);
    world.detections = {{msg::SourceKind::Human, static_cast<float>(c * rel.x + s * rel.y),
                         static_cast<float>(-s * rel.x + c * rel.y), 0.25f}};
    a.onFrame(world.frame(v, w, 0.1));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    v = out.command.v;
    w = out.command.w;
    reversed = reversed || v < -0.01;
    closest = std::min(closest, distance(world.truth.position(), person) - 0.3 - 0.25);
  }
  EXPECT_TRUE(reversed) << "the scene did not make the robot back up";
  EXPECT_GT(closest, 0.15) << "backed into the person";
}

TEST(Agent, SlowsForAPersonWalkingAcrossItsWay) {
  auto grid = emptyGrid();
  agent::Agent a(params(), grid, grid);
  World world;
  a.onAssignment(transport());
  int k = 0;
  (void)run(a, world, k, 25, [] { return false; });
  ASSERT_GT(world.truth.x, 1.3);
  // A person 1 m ahead and 1 m to the right walking across at 1.2 m/s, seen in two frames 0.1 s
  // apart: outside the straight corridor the stop rule watches, on collision course all the same.
  auto step = [&](double side, std::int64_t stampNs) {
    world.detections = {{msg::SourceKind::Human, 1.0f, static_cast<float>(side), 0.25f}};
    auto f = world.frame(0.8, 0.0, 0.1);
    f.stamp_ns = stampNs;
    a.onFrame(f);
    return a.step(stampNs, 0.1);
  };
  (void)step(-1.12, static_cast<std::int64_t>(k) * 100'000'000);
  const auto out = step(-1.0, static_cast<std::int64_t>(k + 1) * 100'000'000);
  EXPECT_LT(out.command.v, 0.5) << "did not slow for the person crossing";
  // The same person standing still there is no reason to slow down: the robot drives as it does
  // with nobody in view.
  auto drive = [&](const std::vector<msg::Detection>& seen) {
    agent::Agent b(params(), grid, grid);
    World still;
    b.onAssignment(transport());
    int j = 0;
    (void)run(b, still, j, 25, [] { return false; });
    still.detections = seen;
    double v = 0.0;
    for (int i = 0; i < 2; ++i) {
      auto f = still.frame(0.8, 0.0, 0.1);
      f.stamp_ns = static_cast<std::int64_t>(j + i) * 100'000'000;
      b.onFrame(f);
      v = b.step(f.stamp_ns, 0.1).command.v;
    }
    return v;
  };
  const double alone = drive({});
  EXPECT_GT(alone, 0.3);
  EXPECT_NEAR(drive({{msg::SourceKind::Human, 1.0f, -1.0f, 0.25f}}), alone, 0.05);
}

TEST(Agent, AGoalInsideAWalledOffRoomFailsTheTaskNamingIt) {
  // The pickup P-1 at (7, 7) lies inside a closed room (walls one cell thick around
  // [6, 8] x [6, 8], no door): no plan reaches it on the inflated map, on the plain map nor on the
  // raw map. The task must fail at once with the station named, and the robot must not drive off.
  auto raw = std::make_shared<planning::OccupancyGrid>(40, 40, 0.25, Vec2{0, 0});
  for (int i = 23; i <= 33; ++i) {
    raw->setBlocked({i, 23});
    raw->setBlocked({i, 33});
    raw->setBlocked({23, i});
    raw->setBlocked({33, i});
  }
  ASSERT_FALSE(raw->blocked(*raw->cellAt({7.0, 7.0}))) << "the goal itself is free, only walled off";
  auto grid = agent::inflate(*raw, 0.3);
  agent::Agent a(params(), grid, raw);
  World world;
  msg::TaskAssignment order = transport();
  order.goals.front().pose = {7.0, 7.0, 0.0};
  a.onAssignment(order);
  ASSERT_TRUE(a.busy());
  std::optional<msg::TaskStatus> failed;
  std::vector<msg::TaskStatus> statuses;
  agent::AgentOutput last;
  double v = 0;
  double w = 0;
  int k = 0;
  for (; k < 50 && !failed; ++k) {
    a.onFrame(world.frame(v, w, 0.1));
    last = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    v = last.command.v;
    w = last.command.w;
    if (last.status) {
      statuses.push_back(*last.status);
      if (last.status->state == msg::TaskState::Failed) {
        failed = last.status;
      }
    }
  }
  ASSERT_TRUE(failed) << "still busy after " << k << " steps at " << world.truth.x << ", " << world.truth.y;
  EXPECT_EQ(k, 1) << "failed on the first step, when the goal is planned";
  EXPECT_EQ(statuses.size(), 1u) << "no en-route report before the failure";
  EXPECT_EQ(failed->task_id, "t1");
  EXPECT_EQ(failed->revision, 7u);
  EXPECT_NE(failed->error.find("no path to P-1"), std::string::npos) << failed->error;
  EXPECT_FALSE(a.busy());
  EXPECT_EQ(last.command.v, 0.0);
  EXPECT_EQ(last.command.w, 0.0);
  // Afterwards it stays put: no further reports, no motion.
  for (int i = 0; i < 30; ++i, ++k) {
    a.onFrame(world.frame(v, w, 0.1));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    v = out.command.v;
    w = out.command.w;
    EXPECT_FALSE(out.status) << msg::toString(out.status->state);
    EXPECT_EQ(out.command.v, 0.0);
    EXPECT_EQ(out.command.w, 0.0);
  }
  EXPECT_LT(distance(world.truth, params().start), 1e-6) << "drove off";
}

TEST(Agent, AfterASensorGapLandmarksPullTheEstimateToWhereTheRobotRolledUnseen) {
  // Frames carry odometry increments, so motion while none arrive is lost to the estimate. Here
  // the robot rolls 0.7 m during a 3 s gap; the landmark bearings of the next frames must bring the
  // estimate there. Without widening the covariance for the gap, the Mahalanobis gate rejects them
  // as outliers (the estimate had converged to a few millimetres) and it stays 0.7 m off.
  auto grid = emptyGrid();
  auto p = params();
  p.landmarks = {{1, {0.0, 5.0}}, {2, {10.0, 5.0}}, {3, {5.0, 10.0}}, {4, {5.0, 0.0}}};
  agent::Agent a(p, grid, grid);
  World world;
  std::int64_t now = 0;
  agent::AgentOutput out;
  auto feed = [&] {
    msg::SensorFrame f = world.frame(0.0, 0.0, 0.1);
    f.stamp_ns = now;
    for (const auto& [id, at] : p.landmarks) {
      const Vec2 rel = at - world.truth.position();
      f.landmarks.push_back({id, static_cast<float>(angleDiff(std::atan2(rel.y, rel.x), world.truth.theta))});
    }
    a.onFrame(f);
    out = a.step(now, 0.1);
    now += 100'000'000;
  };
  for (int k = 0; k < 30; ++k) {
    feed();
  }
  ASSERT_LT(distance(out.state.pose, world.truth), 0.02);
  world.truth = {1.7, 1.0, 0.0};  // rolled on while its driver was silent
  now += 3'000'000'000;
  for (int k = 0; k < 30; ++k) {
    feed();
  }
  EXPECT_LT(distance(out.state.pose, world.truth), 0.05);
}

TEST(Agent, WithWheelTotalsTheMotionDuringASensorGapIsKeptWithoutAnyLandmark) {
  // The same blind roll, but the driver sends its wheel totals: the motion between the last frame
  // before the gap and the first after it is known, so the estimate is right at once, without a
  // single landmark (most of a warehouse's aisles have none in view). Without totals the same gap
  // loses the roll (what the test above widens P for). Returns {estimated x, true x}.
  auto blindRoll = [](bool totals) {
    auto grid = emptyGrid();
    agent::Agent a(params(), grid, grid);
    World world;
    world.wheelTotals = totals;
    std::int64_t now = 0;
    agent::AgentOutput out;
    auto feed = [&] {
      msg::SensorFrame f = world.frame(0.0, 0.0, 0.1);
      f.stamp_ns = now;
      a.onFrame(f);
      out = a.step(now, 0.1);
      now += 100'000'000;
    };
    for (int k = 0; k < 10; ++k) {
      feed();
    }
    for (int k = 0; k < 30; ++k) {
      (void)world.frame(0.7 / 3.0, 0.0, 0.1);  // 3 s of frames that never arrive: it rolls 0.7 m
      now += 100'000'000;
    }
    feed();
    return std::pair{out.state.pose.x, world.truth.x};
  };
  const auto [withTotals, truth] = blindRoll(true);
  EXPECT_NEAR(truth, params().start.x + 0.7, 1e-9);
  EXPECT_NEAR(withTotals, truth, 0.01);
  EXPECT_NEAR(blindRoll(false).first, params().start.x, 0.01)
      << "without totals the increments are all it has";
}

TEST(Agent, MovingBackAndForthWithoutGettingCloserFailsTheTaskNamingTheGoal) {
  // A livelock as one robot lives it: whatever it commands, it is moved 0.3 m forth and back (two
  // robots yielding to each other by turns; a robot backing out and trying again). Moving is not
  // progress: after 3 x blockedFailS without getting 0.25 m closer to its goal the task fails.
  auto grid = emptyGrid();
  agent::Agent a(params(), grid, grid);
  World world;
  a.onAssignment(transport());
  std::optional<msg::TaskStatus> failed;
  int k = 0;
  for (; k < 2500 && !failed; ++k) {
    const double v = (k / 10) % 2 == 0 ? 0.3 : -0.3;  // 1 s forth, 1 s back
    a.onFrame(world.frame(v, 0.0, 0.1));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    if (out.status && out.status->state == msg::TaskState::Failed) {
      failed = out.status;
    }
  }
  ASSERT_TRUE(failed) << "still going after " << k / 10 << " s";
  EXPECT_EQ(failed->error, "no progress towards P-1 for 180 s");
  EXPECT_GE(k, 1800);  // not before the limit
  EXPECT_LT(k, 1900);
}

TEST(Agent, KeepsTheSiteSpeedLimitInsideAZoneAndCruisesOutside) {
  // A 0.25 m/s zone across the way from (1, 1) to the pickup at (5, 1), x in [2.5, 3.5].
  auto grid = emptyGrid();
  auto p = params();
  const double limit = 0.25;
  p.speedLimit = [limit](Vec2 q) {
    return q.x >= 2.5 && q.x <= 3.5 ? limit : std::numeric_limits<double>::infinity();
  };
  agent::Agent a(p, grid, grid);
  World world;
  a.onAssignment(transport());
  double v = 0;
  double w = 0;
  double fastestInside = 0.0;
  double fastestOutside = 0.0;
  bool loaded = false;
  for (int k = 0; k < 1500 && !loaded; ++k) {
    a.onFrame(world.frame(v, w, 0.1));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    v = out.command.v;
    w = out.command.w;
    loaded = out.status && out.status->state == msg::TaskState::Loading;
    const bool inside = world.truth.x >= 2.5 && world.truth.x <= 3.5;
    (inside ? fastestInside : fastestOutside) =
        std::max(inside ? fastestInside : fastestOutside, std::abs(v));
  }
  EXPECT_TRUE(loaded);
  EXPECT_LE(fastestInside, limit + 1e-9);
  EXPECT_GT(fastestOutside, 0.5) << "the limit holds in the zone only";
}

// Issue 19: an assignment with a task id and no goals (on a transient-local topic, so it came again
// after every restart) crashed the agent. The agent now refuses the task and keeps working.
TEST(Agent, AssignmentWithATaskAndNoGoalsIsRefusedNotFollowed) {
  auto grid = emptyGrid();
  agent::Agent a(params(), grid, grid);
  World world;
  msg::TaskAssignment empty;
  empty.robot_id = "r1";
  empty.task_id = "t-empty";
  empty.revision = 3;
  a.onAssignment(empty);
  std::optional<msg::TaskStatus> report;
  for (int k = 0; k < 50; ++k) {
    a.onFrame(world.frame(0, 0, 0.1));
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    if (out.status) {
      report = out.status;
    }
    EXPECT_EQ(out.command.v, 0.0);
  }
  ASSERT_TRUE(report);
  EXPECT_EQ(report->task_id, "t-empty");
  EXPECT_EQ(report->revision, 3u);
  EXPECT_EQ(report->state, msg::TaskState::Failed);
  EXPECT_NE(report->error.find("no goals"), std::string::npos) << report->error;
  EXPECT_FALSE(a.busy());
  // A proper order afterwards is carried out as usual.
  a.onAssignment(transport());
  EXPECT_TRUE(a.busy());
}

// Issue 19: one frame with finite but absurd wheel totals made the pose NaN for good while the robot
// reported idle. The edge refuses such a frame; an Agent that is fed one anyway reports a fault and
// gives its task back.
TEST(Agent, ImplausibleEstimateReportsAFaultAndFailsTheTask) {
  auto grid = emptyGrid();
  agent::Agent a(params(), grid, grid);
  World world;
  world.wheelTotals = true;
  a.onAssignment(transport());
  for (int k = 0; k < 5; ++k) {
    a.onFrame(world.frame(0, 0, 0.1));
    (void)a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
  }
  auto bad = world.frame(0, 0, 0.1);
  bad.wheel_left_total = 1e308;
  bad.wheel_right_total = -1e308;
  a.onFrame(bad);
  std::optional<msg::TaskStatus> report;
  msg::RobotState last;
  for (int k = 5; k < 20; ++k) {
    const auto out = a.step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
    if (out.status) {
      report = out.status;
    }
    last = out.state;
    EXPECT_EQ(out.command.v, 0.0);
    a.onFrame(world.frame(0, 0, 0.1));
  }
  EXPECT_EQ(last.mode, msg::RobotMode::Fault);
  EXPECT_TRUE(last.pose.isFinite()) << "the last plausible pose is reported, so the fault stays visible";
  ASSERT_TRUE(report);
  EXPECT_EQ(report->state, msg::TaskState::Failed);
  EXPECT_FALSE(a.busy());
}
