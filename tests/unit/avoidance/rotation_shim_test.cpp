#include "fleet/avoidance/rotation_shim.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/core/angles.hpp"
#include "test_support.hpp"

namespace fleet::avoidance {
namespace {

/// Records whether it was asked to plan; drives straight ahead.
class Straight final : public LocalPlanner {
 public:
  Command plan(const LocalView&) override {
    ++calls;
    return {{0.5, 0.0}, PlanStatus::kMoving, false};
  }
  [[nodiscard]] std::string_view name() const override { return "straight"; }
  int calls = 0;
};

TEST(RotationShim, TurnsInPlaceTowardsABendThenHandsOverWithHysteresis) {
  auto inner = std::make_unique<Straight>();
  Straight* straight = inner.get();
  RotationShim shim(std::move(inner));
  // The path turns left by 90° at the robot: the heading error to the point 1 m along is ~80°.
  const std::vector<Vec2> path{{0.0, 0.0}, {0.1, 0.0}, {0.1, 5.0}};
  LocalView v;
  v.path = path;
  v.robot.pose = {0.0, 0.0, 0.0};
  Command c = shim.plan(v);
  EXPECT_TRUE(shim.rotating());
  EXPECT_EQ(c.twist.v, 0.0);
  EXPECT_GT(c.twist.omega, 0.0);  // left, towards the bend
  EXPECT_EQ(straight->calls, 0);
  // Still 0.5 rad off (below the 0.785 start angle, above the 0.2 stop angle): keeps turning.
  v.robot.pose = {0.0, 0.0, std::atan2(1.0, 0.1) - 0.5};
  c = shim.plan(v);
  EXPECT_TRUE(shim.rotating());
  EXPECT_GT(c.twist.omega, 0.0);
  // Aligned within 0.2 rad: the wrapped planner drives.
  v.robot.pose = {0.0, 0.0, std::atan2(1.0, 0.1) - 0.1};
  c = shim.plan(v);
  EXPECT_FALSE(shim.rotating());
  EXPECT_EQ(straight->calls, 1);
  EXPECT_EQ(c.twist.v, 0.5);
  // A right bend turns right; and 0.5 rad off without having rotated does not start a turn.
  v.robot.pose = {0.0, 0.0, kPi / 2 + 1.2};
  EXPECT_LT(shim.plan(v).twist.omega, 0.0);
  RotationShim fresh(std::make_unique<Straight>());
  v.robot.pose = {0.0, 0.0, std::atan2(1.0, 0.1) - 0.5};
  EXPECT_FALSE((fresh.plan(v), fresh.rotating()));
}

TEST(RotationShim, NearTheGoalTheWrappedPlannerDecidesAlone) {
  auto inner = std::make_unique<Straight>();
  Straight* straight = inner.get();
  RotationShim shim(std::move(inner));
  const std::vector<Vec2> path{{0.0, 0.0}, {0.0, 0.8}};  // goal 0.8 m away, straight to the left
  LocalView v;
  v.path = path;
  v.robot.pose = {0.0, 0.0, 0.0};
  (void)shim.plan(v);
  EXPECT_FALSE(shim.rotating());
  EXPECT_EQ(straight->calls, 1);
}

TEST(Dwa, ARobotAlreadyInsideTheMinimumClearanceCanStillTurnAndLeave) {
  // A wall 0.05 m from the robot's surface (inside minClearance 0.10): before, every sample was
  // inadmissible and DWA reported blocked for ever; samples that do not close in stay admissible.
  const auto wall = test::wall({-2.0, 0.35}, {4.0, 0.35});  // robot radius 0.3 at y = 0
  const std::vector<Vec2> path{{3.0, -2.0}};
  LocalView v;
  v.robot.pose = {0.0, 0.0, 0.0};
  v.robot.radius = 0.3;
  v.path = path;
  v.scan = wall;
  DynamicWindowPlanner dwa;
  const Command c = dwa.plan(v);
  EXPECT_EQ(c.status, PlanStatus::kMoving);
  for (const auto& s : dwa.lastSamples()) {
    if (s.twist == c.twist) {
      EXPECT_TRUE(s.admissible);
    }
  }
  EXPECT_LE(c.twist.omega, 0.0);  // away from the wall, towards the goal below
}

}  // namespace
}  // namespace fleet::avoidance
