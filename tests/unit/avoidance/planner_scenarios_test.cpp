// Every local planner on the harness scenarios it is built for: one robot past static boxes, and
// one robot along an aisle that people cross. Each goes through the safety layer, as in the agent.
// The multi-robot scenarios (circle swap, the aisle with robots both ways) are the comparison of
// docs/benchmarks.md; only the reciprocal planners are expected to solve those (orca_test.cpp).

#include <gtest/gtest.h>

#include <iostream>
#include <string>

#include "fleet/avoidance/harness.hpp"

namespace fleet::avoidance {
namespace {

const char* const kPlanners[] = {
    "dwa", "potential_field", "bug1", "bug2", "risk_stepping", "elastic_strips", "elastic_strips_bvh",
    "vo",  "vo_keep_right",   "orca"};

void print(const ScenarioResult& r) {
  std::cout << r.scenario << " " << r.planner << ": reached " << r.reached << "/" << r.robots << " in "
            << r.makespan << " s, path " << r.meanPathLength << " m, contacts static " << r.staticCollisions
            << " robot " << r.robotCollisions << " human " << r.humanCollisions << " (while moving "
            << r.humanHitsWhileMoving << ", driven into " << r.humanHitsByRobot << "), min gap "
            << r.minSeparation << " m, overruled " << r.overruled << "\n";
}

TEST(PlannerScenarios, EveryPlannerDrivesPastStaticBoxesWithoutContact) {
  const Scenario sc = obstacleCourse();
  for (const char* name : kPlanners) {
    const auto r = runScenario(sc, name);
    ASSERT_TRUE(r.has_value()) << name;
    print(*r);
    EXPECT_EQ(r->reached, 1) << name;
    EXPECT_EQ(r->collisions, 0) << name;
    // Past three boxes a detour is needed, but not a wander: at most twice the straight 16 m, except
    // for Bug1, which tours every obstacle it meets once and a half by design. Its bound (Lumelsky)
    // is D + 1.5·Σ perimeters, the perimeters followed at r + followGap = 0.65 m from the boxes
    // (1 × 2 m and twice 1.2 × 2.4 m): 2(w + h) + 2π·0.65 each.
    const double followed = (6.0 + 7.2 + 7.2) + 3.0 * 2.0 * 3.14159265 * 0.65;
    EXPECT_LT(r->meanPathLength, std::string(name) == "bug1" ? 16.0 + 1.5 * followed : 32.0) << name;
  }
}

TEST(PlannerScenarios, EveryPlannerCrossesTheAisleWhilePeopleWalkThrough) {
  const Scenario sc = aisleCrossingAlone();
  for (const char* name : kPlanners) {
    const auto r = runScenario(sc, name);
    ASSERT_TRUE(r.has_value()) << name;
    print(*r);
    EXPECT_EQ(r->reached, 1) << name;
    EXPECT_EQ(r->staticCollisions, 0) << name;
    // People here do not avoid: they walk into robots that stand or creep. No robot may drive into
    // a person (contact beginning while it moves towards them).
    EXPECT_EQ(r->humanHitsByRobot, 0) << name;
  }
}

}  // namespace
}  // namespace fleet::avoidance
