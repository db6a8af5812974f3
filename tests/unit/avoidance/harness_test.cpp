#include <gtest/gtest.h>

#include <cmath>

#include "fleet/avoidance/harness.hpp"
#include "fleet/avoidance/velocity_obstacle.hpp"

namespace fleet::avoidance {
namespace {

TEST(VelocityObstacle, DiscTimeToCollision) {
  EXPECT_NEAR(discTimeToCollision({10, 0}, {2, 0}, 1.0), 4.5, 1e-12);
  EXPECT_TRUE(std::isinf(discTimeToCollision({10, 0}, {-2, 0}, 1.0)));  // opening
  EXPECT_TRUE(std::isinf(discTimeToCollision({10, 0}, {0, 2}, 1.0)));   // passing wide
  EXPECT_EQ(discTimeToCollision({0.5, 0}, {0, 0}, 1.0), 0.0);           // already overlapping
  // Grazing: offset exactly R → touches at the closest approach.
  EXPECT_NEAR(discTimeToCollision({10, 1}, {1, 0}, 1.0), 10.0, 1e-6);
}

TEST(Harness, CircleSwapWithVelocityObstaclesIsCollisionFree) {
  const auto r = runScenario(circleSwap(8, 4.0), "vo");
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->reached, 8);
  EXPECT_EQ(r->robotCollisions, 0);
  EXPECT_GT(r->minSeparation, 0.0);
  EXPECT_EQ(r->agentSteps > 0, true);
  // Every robot travels at least the diameter.
  EXPECT_GE(r->meanPathLength, 8.0 - 2.0 * 0.15);
}

TEST(Harness, SafetyLayerKeepsDwaSwapFreeOfRobotContacts) {
  const auto r = runScenario(circleSwap(6, 3.0), "dwa");
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->robotCollisions, 0);
  EXPECT_GT(r->overruled, 0);
}

TEST(Harness, AisleCrossingNoShelfOrRobotContacts) {
  for (const char* planner : {"vo", "elastic_strips_bvh"}) {
    const auto r = runScenario(aisleCrossing(2, 2, 3), planner);
    ASSERT_TRUE(r.has_value());
    EXPECT_EQ(r->reached, 4) << planner;
    EXPECT_EQ(r->staticCollisions, 0) << planner;
    EXPECT_EQ(r->robotCollisions, 0) << planner;
    EXPECT_EQ(r->collisions, r->robotCollisions + r->staticCollisions + r->humanCollisions);
  }
}

TEST(Harness, UnknownPlannerIsAnError) {
  EXPECT_FALSE(runScenario(circleSwap(2, 2.0), "nope").has_value());
}

}  // namespace
}  // namespace fleet::avoidance
