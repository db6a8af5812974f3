#include "fleet/control/path_follower.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/control/velocity_limits.hpp"
#include "fleet/core/angles.hpp"

using namespace fleet;
using namespace fleet::control;

namespace {

struct FollowResult {
  Pose2 end;
  bool reached = false;
  int steps = 0;
  double max_cross_track = 0.0;
  bool progress_monotone = true;
};

/// Closed loop with the speed/acceleration limits in between, as the robot agent runs it.
FollowResult follow(PathFollower& f, Pose2 pose, int maxSteps) {
  const VelocityLimits limits;
  FollowResult res;
  Twist prev{};
  double last_progress = 0.0;
  for (int k = 0; k < maxSteps; ++k) {
    auto out = f.step(pose);
    EXPECT_TRUE(out.has_value());
    res.steps = k;
    if (out->progress < last_progress) {
      res.progress_monotone = false;
    }
    last_progress = out->progress;
    if (!out->finalApproach) {
      res.max_cross_track = std::max(res.max_cross_track, out->crossTrack);
    }
    if (out->goalReached) {
      res.reached = true;
      break;
    }
    prev = applyLimits(limits, out->cmd, prev, 0.1).twist;
    pose = DiffDriveKinematics::integrateExact(pose, prev, 0.1);
  }
  res.end = pose;
  return res;
}

}  // namespace

TEST(PathFollower, FollowsLShapedAisleToFinalPose) {
  PathFollower f;
  ASSERT_TRUE(f.setPath(std::vector<Vec2>{{0, 0}, {4, 0}, {4, 3}}, kPi / 2).has_value());
  EXPECT_NEAR(f.pathLength(), 7.0, 1e-12);
  const FollowResult r = follow(f, Pose2{0, 0, 0}, 2000);
  ASSERT_TRUE(r.reached);
  EXPECT_LT(std::hypot(r.end.x - 4.0, r.end.y - 3.0), 0.02);
  EXPECT_LT(std::abs(angleDiff(r.end.theta, kPi / 2)), 0.0087);
  EXPECT_LT(r.max_cross_track, 0.35);  // corner cutting bounded by the lookahead
  EXPECT_TRUE(r.progress_monotone);
  // At 0.45 m/s the 7 m path needs ≥ 15.6 s; the follower should not dawdle either.
  EXPECT_GT(r.steps, 155);
  EXPECT_LT(r.steps, 600);
}

TEST(PathFollower, StartsOffThePathAndRejoins) {
  PathFollower f;
  std::vector<Pose2> path;
  for (int i = 0; i <= 20; ++i) {
    path.push_back(Pose2{0.25 * i, std::sin(0.25 * i), 0.0});
  }
  path.back().theta = -0.5;
  ASSERT_TRUE(f.setPath(path).has_value());
  const FollowResult r = follow(f, Pose2{0.0, -0.8, kPi / 2}, 3000);
  ASSERT_TRUE(r.reached);
  EXPECT_LT(std::hypot(r.end.x - 5.0, r.end.y - std::sin(5.0)), 0.02);
  EXPECT_LT(std::abs(angleDiff(r.end.theta, -0.5)), 0.0087);
  EXPECT_TRUE(r.progress_monotone);
}

TEST(PathFollower, SinglePointPathIsAPoseGoal) {
  PathFollower f;
  ASSERT_TRUE(f.setPath(std::vector<Pose2>{Pose2{1.0, -1.0, 1.0}}).has_value());
  const FollowResult r = follow(f, Pose2{0, 0, 0}, 2000);
  ASSERT_TRUE(r.reached);
  EXPECT_LT(std::hypot(r.end.x - 1.0, r.end.y + 1.0), 0.02);
}

TEST(PathFollower, Errors) {
  PathFollower f;
  EXPECT_EQ(f.step(Pose2{}).error().code, "no_path");
  EXPECT_EQ(f.setPath(std::vector<Vec2>{}, 0.0).error().code, "empty_path");
  EXPECT_EQ(f.setPath(std::vector<Vec2>{{0, 0}, {std::nan(""), 1}}, 0.0).error().code, "non_finite_path");
  ASSERT_TRUE(f.setPath(std::vector<Vec2>{{0, 0}, {0, 0}, {1, 0}}, 0.0).has_value());  // duplicate dropped
  EXPECT_NEAR(f.pathLength(), 1.0, 1e-12);
  EXPECT_EQ(f.step(Pose2{std::nan(""), 0, 0}).error().code, "non_finite_pose");
  PathFollowerParams p;
  p.lookahead = 0.0;
  EXPECT_FALSE(p.validate().has_value());
  EXPECT_TRUE(PathFollowerParams{}.validate().has_value());
}
