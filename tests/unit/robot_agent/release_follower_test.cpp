// The release follower alone, with a stand-in for the robot's stack (no local planner: the path
// follower drives; a gate the test holds shut or opens) and ideal kinematics: it stands when
// nothing is released, drives a release to its end and stops there, says when it stands on its
// goal, tells a hold by a person (reported blocked after 3 s) from a wait on a robot the plan
// knows (never blocked), and forgets a hold once at work.

#include "release_follower.hpp"

#include <gtest/gtest.h>

#include <optional>
#include <string>

#include "fleet/control/diff_drive_kinematics.hpp"

using namespace fleet;
using agent::Blocker;
using agent::DriveStack;
using agent::FollowCommand;
using agent::FollowCycle;
using agent::ReleaseFollower;
using fleet::RobotActivity;

namespace {

constexpr std::int64_t kTick = 100'000'000;

/// The stack as the follower sees it: no local planner; the gate holds the robot while `holder` is
/// set (naming it), and otherwise passes the command through.
struct Stack : DriveStack {
  std::optional<Blocker> holder;
  std::string knownRobot = "r2";
  [[nodiscard]] bool hasPlanner() const override { return false; }
  control::Twist planLocal(const std::vector<Vec2>&, bool& blocked) override {
    blocked = false;
    return {};
  }
  bool heldUp(const std::vector<Vec2>&, bool, double& v, double& w, Blocker& blocker) override {
    if (!holder) {
      return false;
    }
    blocker = *holder;
    v = 0.0;
    w = 0.0;
    return true;
  }
  double clearSpeed(const std::vector<Vec2>&, bool, double v, Blocker& blocker) override {
    if (holder) {
      blocker = *holder;
      return 0.0;
    }
    return v;
  }
  [[nodiscard]] bool knowsRobot(const std::string& id) const override { return id == knownRobot; }
};

/// One robot at (1, 5) facing +x, following releases along y = 5 (a node every 0.5 m).
struct Drive {
  Drive() : follow(agent::FollowerParams{}, nullptr, watch) {}

  agent::ProgressWatch watch{agent::ProgressParams{}};
  ReleaseFollower follow;
  Stack stack;
  Pose2 pose{1.0, 5.0, 0.0};
  std::int64_t k = 0;
  double lastV = 0.0;
  std::optional<agent::TaskGoal> goal = agent::TaskGoal{{4.0, 5.0, 0.0}, "P-1", agent::GoalAction::Load, 1.0};

  void release(int first, int last, bool atGoal, std::uint32_t seq = 1) {
    agent::Release r;
    r.epoch = 1;
    r.seq = seq;
    r.endsAtGoal = atGoal;
    for (int i = first; i <= last; ++i) {
      r.base.push_back({i, {1.0 + 0.5 * i, 5.0}});
    }
    ASSERT_EQ(follow.offer(r, pose.position()), agent::ReleaseVerdict::kAccepted);
  }

  FollowCommand step() {
    FollowCycle c;
    c.nowNs = k++ * kTick;
    c.dt = 0.1;
    c.pose = pose;
    c.lastV = lastV;
    c.goal = goal;
    c.busy = true;
    const FollowCommand cmd = follow.drive(c, stack);
    follow.noteStanding(c, cmd);
    pose = control::DiffDriveKinematics::integrateExact(pose, {cmd.v, cmd.w}, 0.1);
    lastV = cmd.v;
    return cmd;
  }
};

}  // namespace

TEST(ReleaseFollower, WithNothingReleasedItStandsAndSaysWhy) {
  Drive d;
  for (int i = 0; i < 20; ++i) {
    const auto cmd = d.step();
    EXPECT_EQ(cmd.v, 0.0);
    EXPECT_EQ(cmd.mode, msg::RobotMode::Waiting) << "with a task, waiting on the traffic manager";
    EXPECT_FALSE(cmd.held);
    EXPECT_EQ(cmd.doing, RobotActivity::WaitingOnRobot);
  }
  EXPECT_EQ(d.follow.standing().why, "nothing released beyond its node");
  EXPECT_EQ(d.follow.standing().sinceNs, 0);
  EXPECT_FALSE(d.follow.blocked());
}

TEST(ReleaseFollower, DrivesAReleaseToItsEndAndStopsThere) {
  Drive d;
  d.release(0, 3, false);  // to x = 2.5, short of the goal at x = 4
  bool moved = false;
  FollowCommand cmd;
  for (int i = 0; i < 150; ++i) {
    cmd = d.step();
    if (cmd.v > 0.3) {
      moved = true;
      EXPECT_EQ(cmd.doing, RobotActivity::Driving);
    }
    EXPECT_FALSE(cmd.onGoal);
  }
  EXPECT_TRUE(moved);
  EXPECT_EQ(cmd.doing, RobotActivity::WaitingOnRobot) << "held at its base's end for the others";
  EXPECT_NEAR(d.pose.x, 2.5, 0.06) << "stopped at the base's end";
  EXPECT_NEAR(d.pose.y, 5.0, 0.05);
  EXPECT_EQ(d.follow.releases().node(), 3) << "every node reached, the last one last";
  EXPECT_EQ(d.follow.standing().why, "at the end of its base");
}

TEST(ReleaseFollower, SaysWhenItStandsOnItsGoal) {
  Drive d;
  d.release(0, 6, true);  // x = 4: the goal
  bool onGoal = false;
  for (int i = 0; i < 200 && !onGoal; ++i) {
    onGoal = d.step().onGoal;
  }
  ASSERT_TRUE(onGoal);
  EXPECT_LT(distance(d.pose.position(), Vec2{4.0, 5.0}), 0.15);
  EXPECT_TRUE(d.follow.releases().endsAtGoal());
}

TEST(ReleaseFollower, HeldByAPersonItIsReportedBlockedAfterThreeSecondsButNeverByAKnownRobot) {
  Drive d;
  d.release(0, 6, true);
  for (int i = 0; i < 10; ++i) {
    (void)d.step();
  }
  d.stack.holder = Blocker{false, "human"};
  FollowCommand cmd;
  for (int i = 0; i < 25; ++i) {
    cmd = d.step();
  }
  EXPECT_TRUE(cmd.held);
  EXPECT_TRUE(cmd.waiting) << "on a person: no progress clock runs";
  EXPECT_EQ(cmd.doing, RobotActivity::HeldByPerson);
  EXPECT_FALSE(d.follow.blocked()) << "2.5 s: not yet";
  for (int i = 0; i < 10; ++i) {
    cmd = d.step();
  }
  EXPECT_TRUE(d.follow.blocked()) << "3.5 s held by a person";
  EXPECT_EQ(d.follow.standing().why, "held by human");

  Drive e;
  e.release(0, 6, true);
  for (int i = 0; i < 10; ++i) {
    (void)e.step();
  }
  e.stack.holder = Blocker{true, "r2"};
  for (int i = 0; i < 100; ++i) {
    cmd = e.step();
  }
  EXPECT_TRUE(cmd.waiting) << "a dependency the plan knows";
  EXPECT_EQ(cmd.doing, RobotActivity::WaitingOnRobot);
  EXPECT_FALSE(e.follow.blocked()) << "a robot the traffic manager plans is no block";
  EXPECT_EQ(e.follow.standing().why, "held by robot r2");
  e.stack.knownRobot.clear();
  for (int i = 0; i < 40; ++i) {
    cmd = e.step();
  }
  EXPECT_FALSE(cmd.waiting);
  EXPECT_TRUE(e.follow.blocked()) << "a robot nobody reports is something the plan does not know";
  EXPECT_EQ(cmd.doing, RobotActivity::HeldBySafety);
}

TEST(ReleaseFollower, AtWorkItIsNeitherStandingNorBlocked) {
  Drive d;
  d.release(0, 6, true);
  for (int i = 0; i < 5; ++i) {
    (void)d.step();
  }
  d.stack.holder = Blocker{false, "human"};
  for (int i = 0; i < 50; ++i) {
    (void)d.step();
  }
  ASSERT_TRUE(d.follow.blocked());
  d.follow.atWork();
  EXPECT_FALSE(d.follow.blocked());
  EXPECT_EQ(d.follow.standing().sinceNs, -1);
  EXPECT_FALSE(d.follow.dockingLeg());
}
