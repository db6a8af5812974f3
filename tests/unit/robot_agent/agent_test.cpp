// The agent's stack against a tiny kinematic world in the test, with a stand-in traffic manager that
// releases the straight way to each goal: it localizes from odometry and compass, drives what is
// released, dwells, reports every task state in order, stops for what is ahead, holds still when
// paused or blind, keeps speed limits, refuses orders it cannot carry out without dropping its task,
// and reports a fault when its estimate is implausible.

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "agent.hpp"
#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/core/angles.hpp"
#include "room_scan.hpp"
#include "straight_releases.hpp"

using namespace fleet;

namespace {

constexpr std::int64_t kTick = 100'000'000;  // ns: 0.1 s cycles

struct World {
  Pose2 truth{1.0, 1.0, 0.0};
  double wheelBase = 0.4;
  std::uint32_t seq = 0;
  std::vector<msg::Detection> detections;
  bool wheelTotals = false;  // send SensorFrame.wheel_*_total too
  double leftTotal = 0.0;
  double rightTotal = 0.0;

  msg::SensorFrame frame(double v, double w, double dt) {
    truth = control::DiffDriveKinematics::integrateExact(truth, {v, w}, dt);
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
    if (room) {
      scan(f);
    }
    return f;
  }

  // With `room`: the walls of a 10 × 8 m room round the origin's corner, scanned as the simulator
  // does (72 rays over 360° from -π, 8 m; a miss reads 8 m) from the true pose.
  bool room = false;
  void scan(msg::SensorFrame& f) const {
    f.angle_min = static_cast<float>(-kPi);
    f.angle_increment = static_cast<float>(test::kRoomRayStep);
    f.ranges = test::roomRanges(truth, 10.0, 8.0);
  }
};

// The room's inner faces, as the site's wall segments.
std::shared_ptr<const std::vector<estimation::MapSegment>> roomWalls() {
  auto w = std::make_shared<std::vector<estimation::MapSegment>>();
  w->push_back({Vec2{0, 0}, Vec2{10, 0}, {0, 1}});
  w->push_back({Vec2{0, 8}, Vec2{10, 8}, {0, -1}});
  w->push_back({Vec2{0, 0}, Vec2{0, 8}, {1, 0}});
  w->push_back({Vec2{10, 0}, Vec2{10, 8}, {-1, 0}});
  return w;
}

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

/// The agent in the world, with the stand-in traffic manager answering its progress reports.
struct AgentRun {
  explicit AgentRun(agent::AgentParams p = params()) : a(p, emptyGrid()) { world.truth = p.start; }

  /// One cycle: the frame for the last command, a step at cycle k, releases for the report.
  agent::AgentOutput step() {
    auto f = world.frame(v, w, 0.1);
    f.stamp_ns = k * kTick;
    a.onFrame(f);
    return stepBlind();
  }
  /// A cycle without a sensor frame.
  agent::AgentOutput stepBlind() {
    auto out = a.step(k++ * kTick, 0.1);
    v = out.command.v;
    w = out.command.w;
    if (out.traffic) {
      if (auto r = releases.onProgress(*out.traffic)) {
        a.onRelease(*r);
      }
    }
    if (out.status) {
      statuses.push_back(*out.status);
    }
    ++activities[static_cast<std::size_t>(out.state.activity)];
    return out;
  }
  /// Steps until `until` holds or `steps` have run.
  template <class Until>
  void until(int steps, Until done) {
    for (int i = 0; i < steps && !done(); ++i) {
      (void)step();
    }
  }
  [[nodiscard]] bool reported(msg::TaskState s) const {
    return std::any_of(statuses.begin(), statuses.end(),
                       [&](const msg::TaskStatus& t) { return t.state == s; });
  }

  agent::Agent a;
  World world;
  test::StraightReleases releases{"r1"};
  std::int64_t k = 0;
  double v = 0.0;
  double w = 0.0;
  std::vector<msg::TaskStatus> statuses;
  std::array<int, kRobotActivities> activities{};  // cycles per RobotState.activity
};

}  // namespace

TEST(Agent, DeliversATransportTaskReportingEveryState) {
  auto p = params();
  p.returnHomeS = -1.0;  // stays at the drop-off
  AgentRun run(p);
  run.a.onAssignment(transport());
  run.until(1500, [&] { return run.reported(msg::TaskState::Done); });
  std::vector<msg::TaskState> states;
  for (const auto& s : run.statuses) {
    EXPECT_EQ(s.task_id, "t1");
    EXPECT_EQ(s.revision, 7u);
    states.push_back(s.state);
  }
  const std::vector<msg::TaskState> expected = {msg::TaskState::EnRoute, msg::TaskState::Loading,
                                                msg::TaskState::Delivering, msg::TaskState::Unloading,
                                                msg::TaskState::Done};
  EXPECT_EQ(states, expected);
  EXPECT_EQ(run.releases.releases(), 2) << "one base to each goal";
  // What it said it did, cycle by cycle, for the robot-time ledger.
  for (const auto a : {RobotActivity::Driving, RobotActivity::TurningDocking, RobotActivity::Dwelling}) {
    EXPECT_GT(run.activities[static_cast<std::size_t>(a)], 0) << toString(a);
  }
  EXPECT_EQ(run.activities[static_cast<std::size_t>(RobotActivity::Unset)], 0);
  EXPECT_LT(distance(run.world.truth, Pose2{5.0, 6.0, 0}), 0.2);
  EXPECT_LT(distance(run.a.pose(), run.world.truth), 0.05) << "odometry + compass keep the estimate close";
  EXPECT_FALSE(run.a.busy());
  const auto out = run.step();
  EXPECT_EQ(out.discs.source_id, "r1");
  EXPECT_FALSE(out.discs.discs.empty());
}

TEST(Agent, CarriesOutAMultiStopOrderStopByStopReportingEachStop) {
  auto p = params();
  p.returnHomeS = -1.0;
  AgentRun run(p);
  auto a = transport();
  a.goals[0].load_id = "L-1";
  a.goals[1].load_id = "L-1";
  a.goals.push_back({{5.0, 6.0, 1.57}, "D-1", msg::GoalAction::None, 2.0});  // a wait where it dropped
  a.goals.push_back({{1.0, 6.0, 3.14}, "X", msg::GoalAction::None, 0.0});
  run.a.onAssignment(a);
  std::int64_t waitBegan = -1;
  run.until(2500, [&] {
    if (waitBegan < 0 && !run.statuses.empty() && run.statuses.back().step == 3) {
      waitBegan = run.statuses.back().stamp_ns;
    }
    return run.reported(msg::TaskState::Done);
  });
  ASSERT_TRUE(run.reported(msg::TaskState::Done));
  std::vector<std::uint32_t> steps;
  for (const auto& s : run.statuses) {
    if (steps.empty() || steps.back() != s.step) {
      steps.push_back(s.step);
    }
  }
  EXPECT_EQ(steps, (std::vector<std::uint32_t>{1, 2, 3, 4})) << "each stop reported, in order";
  const auto& done = run.statuses.back();
  EXPECT_EQ(done.state, msg::TaskState::Done);
  EXPECT_EQ(done.step, 4u);
  ASSERT_GE(waitBegan, 0);
  // The last leg began after the wait's two seconds at the drop-off.
  const auto lastLeg = std::find_if(run.statuses.begin(), run.statuses.end(),
                                    [](const msg::TaskStatus& s) { return s.step == 4; });
  ASSERT_NE(lastLeg, run.statuses.end());
  EXPECT_GE(lastLeg->stamp_ns - waitBegan, 2 * 1'000'000'000LL);
  EXPECT_LT(distance(run.world.truth, Pose2{1.0, 6.0, 0}), 0.2);
}

TEST(Agent, IdleAwayFromHomeItAsksForTheWayHomeAndTheTripIsNoTask) {
  AgentRun run;
  auto order = transport();
  order.goals.pop_back();
  run.a.onAssignment(order);
  run.until(800, [&] { return run.reported(msg::TaskState::Done); });
  ASSERT_TRUE(run.reported(msg::TaskState::Done));
  const std::size_t reports = run.statuses.size();
  std::optional<msg::TrafficProgress> last;
  for (int i = 0; i < 300; ++i) {
    if (auto out = run.step(); out.traffic) {
      last = out.traffic;
    }
  }
  ASSERT_TRUE(last);
  EXPECT_TRUE(last->has_goal) << "its parking place";
  EXPECT_LT(distance(last->goal, params().start), 1e-9);
  EXPECT_LT(distance(run.world.truth.position(), params().start.position()), 0.2) << "drove home";
  EXPECT_EQ(run.statuses.size(), reports) << "the trip home is never reported as a task";
}

TEST(Agent, StopsForSomethingAheadAndReportsWaiting) {
  AgentRun run;
  run.a.onAssignment(transport());
  run.until(20, [] { return false; });
  ASSERT_GT(run.v, 0.1) << "under way towards the pickup (straight ahead, +x)";
  run.world.detections = {{msg::SourceKind::Human, 0.6f, 0.0f, 0.25f}};
  const auto out = run.step();
  EXPECT_LE(out.command.v, 1e-9);
  EXPECT_EQ(out.state.mode, msg::RobotMode::Waiting);
  // Beside the corridor, the same person does not stop the robot.
  run.world.detections = {{msg::SourceKind::Human, 0.6f, 1.2f, 0.25f}};
  run.until(5, [] { return false; });
  EXPECT_GT(run.v, 0.0);
}

TEST(Agent, ACancelledRobotDrivesNoFurtherThanReleasedAndIgnoresOthersOrders) {
  auto p = params();
  p.returnHomeS = -1.0;  // (else an idle robot asks for the way home)
  AgentRun run(p);
  run.a.onAssignment(transport());
  run.until(10, [] { return false; });
  EXPECT_TRUE(run.a.busy());
  auto cancel = transport();
  cancel.task_id.clear();
  cancel.goals.clear();
  cancel.revision = 8;
  run.a.onAssignment(cancel);
  EXPECT_FALSE(run.a.busy());
  // The nodes released to it are its own until the traffic manager says otherwise: it may drive on
  // to the end of them (here the pickup's node), no further, and tells the traffic manager it has
  // no goal any more.
  std::optional<msg::TrafficProgress> last;
  agent::AgentOutput out;
  for (int i = 0; i < 200; ++i) {
    out = run.step();
    if (out.traffic) {
      last = out.traffic;
    }
  }
  ASSERT_TRUE(last);
  EXPECT_FALSE(last->has_goal);
  EXPECT_LT(run.world.truth.x, 5.0 + 0.05);
  EXPECT_EQ(out.command.v, 0.0);
  EXPECT_EQ(out.state.mode, msg::RobotMode::Idle);
  EXPECT_EQ(out.state.activity, RobotActivity::NoTask);
  EXPECT_EQ(run.releases.releases(), 1) << "nothing more asked for";
  EXPECT_TRUE(run.statuses.size() == 1 && run.statuses[0].state == msg::TaskState::EnRoute)
      << "a cancel is the manager's own: nothing reported";
  msg::TaskAssignment other = transport();
  other.robot_id = "r2";
  run.a.onAssignment(other);
  EXPECT_FALSE(run.a.busy()) << "another robot's order is not ours";
}

// A robot whose SensorFrame stream stops holds still, reports RM_FAULT and a TaskStatus naming the
// reason, keeps its task, and drives on to finish it when frames come back.
TEST(Agent, SensorStreamLossStopsReportsAndResumes) {
  auto p = params();
  p.sensorTimeoutS = 0.5;
  AgentRun run(p);
  run.a.onAssignment(transport());
  run.until(20, [] { return false; });
  ASSERT_GT(run.v, 0.1) << "moving before the loss";
  const std::size_t before = run.statuses.size();
  // Frames stop: within the timeout the robot goes on; past it, zero command and a fault.
  std::vector<agent::AgentOutput> blind;
  for (int k = 0; k < 30; ++k) {
    blind.push_back(run.stepBlind());
  }
  EXPECT_NE(blind[3].state.mode, msg::RobotMode::Fault) << "0.4 s without frames is within 0.5 s";
  int faultAt = -1;
  for (int k = 0; k < static_cast<int>(blind.size()); ++k) {
    if (blind[static_cast<std::size_t>(k)].state.mode == msg::RobotMode::Fault && faultAt < 0) {
      faultAt = k;
    }
  }
  ASSERT_EQ(run.statuses.size(), before + 1) << "one report when the stream is lost";
  const auto& lost = run.statuses.back();
  EXPECT_EQ(lost.task_id, "t1");
  EXPECT_NE(lost.error.find("sensor stream lost"), std::string::npos) << lost.error;
  EXPECT_EQ(lost.state, msg::TaskState::EnRoute) << "the task is kept, not failed";
  EXPECT_EQ(faultAt, 5) << "the first step more than 0.5 s after the last frame";
  for (std::size_t k = static_cast<std::size_t>(faultAt); k < blind.size(); ++k) {
    EXPECT_EQ(blind[k].command.v, 0.0);
    EXPECT_EQ(blind[k].command.w, 0.0);
    EXPECT_EQ(blind[k].state.mode, msg::RobotMode::Fault);
  }
  EXPECT_TRUE(run.a.sensorLost());
  EXPECT_TRUE(run.a.busy());
  // Frames come back: the fault clears at once, a status without error says so, and the task ends.
  run.v = 0.0;
  run.w = 0.0;
  const auto back = run.step();
  EXPECT_NE(back.state.mode, msg::RobotMode::Fault);
  ASSERT_TRUE(back.status.has_value());
  EXPECT_TRUE(back.status->error.empty());
  run.until(1500, [&] { return run.reported(msg::TaskState::Done); });
  EXPECT_TRUE(run.reported(msg::TaskState::Done));
  EXPECT_FALSE(run.a.sensorLost());
}

TEST(Agent, InARoomItsLinesMatchTheWallsAndItsPoseIsNeverDoubted) {
  auto p = params();
  p.walls = roomWalls();
  AgentRun run(p);
  run.world.room = true;
  run.a.onAssignment(transport());
  bool fault = false;
  for (int i = 0; i < 1500 && !run.reported(msg::TaskState::Done); ++i)
    fault = run.step().state.mode == msg::RobotMode::Fault || fault;
  EXPECT_TRUE(run.reported(msg::TaskState::Done));
  EXPECT_FALSE(fault);
  EXPECT_EQ(run.a.poseWatch().doubts(), 0u);
  EXPECT_GT(run.a.lineStats().accepted, 300u) << "the lines were fused all the way";
}

TEST(Agent, ARobotWhoseWallsAreNotWhereItThinksStopsFaultedAndSaysWhy) {
  // It believes it is at (1, 1) facing east; it stands at (2.5, 2.2) facing 0.4 rad north of it (a
  // restarted agent without its robots' poses, a robot carried off): every wall it sees is
  // somewhere the map has none.
  auto p = params();
  p.walls = roomWalls();
  AgentRun run(p);
  run.world.room = true;
  run.world.truth = {2.5, 2.2, 0.4};
  run.a.onAssignment(transport());
  int faultAt = -1;
  std::vector<agent::AgentOutput> outs;
  for (int i = 0; i < 200; ++i) {
    outs.push_back(run.step());
    if (faultAt < 0 && outs.back().state.mode == msg::RobotMode::Fault)
      faultAt = i;
  }
  ASSERT_GE(faultAt, 0) << "never doubted";
  EXPECT_LE(faultAt, 110) << "a whole window (10 s) and a cycle";
  EXPECT_TRUE(run.a.poseDoubted());
  for (std::size_t k = static_cast<std::size_t>(faultAt); k < outs.size(); ++k) {
    EXPECT_EQ(outs[k].command.v, 0.0) << k;
    EXPECT_EQ(outs[k].command.w, 0.0) << k;
    EXPECT_EQ(outs[k].state.mode, msg::RobotMode::Fault) << k;
  }
  const auto said = std::find_if(run.statuses.begin(), run.statuses.end(), [](const msg::TaskStatus& t) {
    return t.error.find("localization doubtful") != std::string::npos;
  });
  ASSERT_NE(said, run.statuses.end());
  EXPECT_EQ(said->task_id, "t1");
  EXPECT_NE(said->state, msg::TaskState::Failed) << "the task is kept; the manager's timers decide";
  EXPECT_TRUE(run.a.busy());
  EXPECT_EQ(run.a.poseWatch().doubts(), 1u);
}

TEST(Agent, PausedOrderHoldsStillLongerThanTheFailTimeoutAndResumes) {
  AgentRun run;
  run.a.onAssignment(transport());
  run.until(20, [] { return false; });
  ASSERT_GT(run.world.truth.x, 1.2) << "under way";
  auto hold = transport();
  hold.revision = 8;
  hold.paused = true;
  run.a.onAssignment(hold);
  EXPECT_TRUE(run.a.paused());
  // Longer than the 180 s no-progress limit: no status (no failure), standing still, `waiting`.
  (void)run.step();  // (the command of the cycle before still moves it)
  const std::size_t before = run.statuses.size();
  const Pose2 at = run.world.truth;
  for (int i = 0; i < 2000; ++i) {
    const auto out = run.step();
    EXPECT_EQ(out.state.mode, msg::RobotMode::Waiting);
  }
  EXPECT_EQ(run.statuses.size(), before) << "reported while paused";
  EXPECT_LT(distance(run.world.truth, at), 0.05) << "moved while paused";
  EXPECT_TRUE(run.a.busy());
  auto go = transport();
  go.revision = 9;
  run.a.onAssignment(go);
  EXPECT_FALSE(run.a.paused());
  run.until(1500, [&] { return !run.a.busy(); });
  ASSERT_FALSE(run.statuses.empty());
  EXPECT_EQ(run.statuses.back().state, msg::TaskState::Done);
}

TEST(Agent, SlowsForAPersonWalkingAcrossItsWay) {
  // A person 1 m ahead and 1 m to the right walking across at 1.2 m/s, seen in two frames 0.1 s
  // apart: outside the straight corridor the stop rule watches, on collision course all the same.
  // The same person standing still there is no reason to slow down.
  auto drive = [&](const std::vector<std::vector<msg::Detection>>& seen) {
    AgentRun run;
    run.a.onAssignment(transport());
    run.until(25, [] { return false; });
    EXPECT_GT(run.world.truth.x, 1.3);
    double v = 0.0;
    for (const auto& s : seen) {
      run.world.detections = s;
      v = run.step().command.v;
    }
    return v;
  };
  const double alone = drive({{}, {}});
  EXPECT_GT(alone, 0.3);
  EXPECT_LT(drive({{{msg::SourceKind::Human, 1.0f, -1.12f, 0.25f}},
                   {{msg::SourceKind::Human, 1.0f, -1.0f, 0.25f}}}),
            0.5)
      << "did not slow for the person crossing";
  EXPECT_NEAR(
      drive({{{msg::SourceKind::Human, 1.0f, -1.0f, 0.25f}}, {{msg::SourceKind::Human, 1.0f, -1.0f, 0.25f}}}),
      alone, 0.05);
}

TEST(Agent, AfterASensorGapLandmarksPullTheEstimateToWhereTheRobotRolledUnseen) {
  // Frames carry odometry increments, so motion while none arrive is lost to the estimate. Here
  // the robot rolls 0.7 m during a 3 s gap; the landmark bearings of the next frames must bring the
  // estimate there. Without widening the covariance for the gap, the Mahalanobis gate rejects them
  // as outliers (the estimate had converged to a few millimetres) and it stays 0.7 m off.
  auto grid = emptyGrid();
  auto p = params();
  p.landmarks = {{1, {0.0, 5.0}}, {2, {10.0, 5.0}}, {3, {5.0, 10.0}}, {4, {5.0, 0.0}}};
  agent::Agent a(p, grid);
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
    agent::Agent a(params(), grid);
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

TEST(Agent, KeepsTheSiteSpeedLimitInsideAZoneAndCruisesOutside) {
  // A 0.25 m/s zone across the way from (1, 1) to the pickup at (5, 1), x in [2.5, 3.5].
  auto p = params();
  const double limit = 0.25;
  p.speedLimit = [limit](Vec2 q) {
    return q.x >= 2.5 && q.x <= 3.5 ? limit : std::numeric_limits<double>::infinity();
  };
  AgentRun run(p);
  run.a.onAssignment(transport());
  double fastestInside = 0.0;
  double fastestOutside = 0.0;
  run.until(1500, [&] {
    const bool inside = run.world.truth.x >= 2.5 && run.world.truth.x <= 3.5;
    (inside ? fastestInside : fastestOutside) =
        std::max(inside ? fastestInside : fastestOutside, std::abs(run.v));
    return run.reported(msg::TaskState::Loading);
  });
  EXPECT_TRUE(run.reported(msg::TaskState::Loading));
  EXPECT_LE(fastestInside, limit + 1e-9);
  EXPECT_GT(fastestOutside, 0.5) << "the limit holds in the zone only";
}

// An assignment with a task id and no goals (on a transient-local topic, so it came again after
// every restart) once crashed the agent. The agent refuses the task and keeps working.
TEST(Agent, AssignmentWithATaskAndNoGoalsIsRefusedNotFollowed) {
  AgentRun run;
  msg::TaskAssignment empty;
  empty.robot_id = "r1";
  empty.task_id = "t-empty";
  empty.revision = 3;
  run.a.onAssignment(empty);
  for (int k = 0; k < 50; ++k) {
    EXPECT_EQ(run.step().command.v, 0.0);
  }
  ASSERT_EQ(run.statuses.size(), 1u);
  const auto& report = run.statuses.back();
  EXPECT_EQ(report.task_id, "t-empty");
  EXPECT_EQ(report.revision, 3u);
  EXPECT_EQ(report.state, msg::TaskState::Failed);
  EXPECT_NE(report.error.find("no goals"), std::string::npos) << report.error;
  EXPECT_FALSE(run.a.busy());
  // A proper order afterwards is carried out as usual.
  run.a.onAssignment(transport());
  EXPECT_TRUE(run.a.busy());
}

// A refused order for another task once made the agent drop its current task without a word: the
// robot reported idle with no task while the fleet manager kept the task en route. The refusal is
// reported and the current task goes on to the end.
TEST(Agent, ARefusedOrderForAnotherTaskIsReportedAndTheCurrentTaskGoesOn) {
  auto p = params();
  p.returnHomeS = -1.0;
  AgentRun run(p);
  run.a.onAssignment(transport());
  run.until(30, [] { return false; });
  ASSERT_TRUE(run.a.busy());
  msg::TaskAssignment empty;
  empty.robot_id = "r1";
  empty.task_id = "t-other";
  empty.revision = 8;
  run.a.onAssignment(empty);  // no goals
  msg::TaskAssignment bad = transport();
  bad.task_id = "t-bad";
  bad.revision = 9;
  run.a.refuseAssignment(bad, "goal pose is not finite");  // refused at the process's edge
  EXPECT_TRUE(run.a.busy());
  const auto out = run.step();
  EXPECT_EQ(out.state.task_id, "t1") << "still reported as its task";
  run.until(1500, [&] { return run.reported(msg::TaskState::Done); });
  std::vector<std::string> failed;
  for (const auto& s : run.statuses) {
    if (s.state == msg::TaskState::Failed) {
      failed.push_back(s.task_id);
    }
  }
  EXPECT_EQ(failed, (std::vector<std::string>{"t-other", "t-bad"}));
  ASSERT_FALSE(run.statuses.empty());
  EXPECT_EQ(run.statuses.back().task_id, "t1");
  EXPECT_EQ(run.statuses.back().state, msg::TaskState::Done);
}

// One frame with finite but absurd wheel totals once made the pose NaN for good while the robot
// reported idle. The localizer refuses a wheel increment no robot could drive (more than 10 m in a
// frame): the estimate stays plausible and finite, and the task goes on.
TEST(Agent, AbsurdWheelTotalsAreRefusedAndTheTaskGoesOn) {
  AgentRun run;
  run.world.wheelTotals = true;
  run.a.onAssignment(transport());
  run.until(5, [] { return false; });
  const auto before = run.a.framesRejected();
  auto bad = run.world.frame(0, 0, 0.1);
  bad.wheel_left_total = 1e308;
  bad.wheel_right_total = -1e308;
  run.a.onFrame(bad);
  EXPECT_GT(run.a.framesRejected(), before);
  msg::RobotState last;
  for (int i = 0; i < 15; ++i) {
    last = run.step().state;
  }
  EXPECT_NE(last.mode, msg::RobotMode::Fault);
  EXPECT_TRUE(last.pose.isFinite());
  EXPECT_LT(distance(last.pose, run.world.truth), 0.2);
  EXPECT_TRUE(run.a.busy());
  EXPECT_FALSE(run.reported(msg::TaskState::Failed));
}

TEST(Agent, EachOtherRobotHasOneEntryAsLastHeardHoweverItIsFed) {
  msg::RobotState s;
  s.robot_id = "r2";
  s.pose = {2.0, 1.0, 0.0};
  s.v = 0.5;
  s.stamp_ns = 1;
  // By its state (the agent numbers the ids itself).
  agent::Agent a(params(), emptyGrid());
  a.onOtherRobot(s);
  s.pose = {3.0, 1.0, 0.0};
  s.stamp_ns = 2;
  a.onOtherRobot(s);
  msg::RobotState own = s;
  own.robot_id = "r1";
  a.onOtherRobot(own);
  ASSERT_EQ(a.others().size(), 1U) << "one entry for r2, none for the agent's own robot";
  EXPECT_EQ(a.others()[0].pos.x, 3.0);
  EXPECT_EQ(a.others()[0].stampNs, 2);
  EXPECT_NEAR(a.others()[0].velocity.x, 0.5, 1e-12);
  // Converted once and numbered by the process (AgentNode): the same.
  agent::Agent b(params(), emptyGrid());
  b.onOtherRobot(7, *agent::Agent::otherOf(s));
  s.pose = {4.0, 1.0, 0.0};
  b.onOtherRobot(7, *agent::Agent::otherOf(s));
  b.onOtherRobot(2, *agent::Agent::otherOf(own));
  ASSERT_EQ(b.others().size(), 1U);
  EXPECT_EQ(b.others()[0].pos.x, 4.0);
  s.pose.x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(agent::Agent::otherOf(s).has_value()) << "a pose that is not finite is not a place";
}
