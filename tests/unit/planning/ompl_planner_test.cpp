#include <gtest/gtest.h>

#include "fleet/planning/astar.hpp"
#include "fleet/planning/ompl_planner.hpp"
#include "fleet/planning/segment_free.hpp"

using namespace fleet;
using namespace fleet::planning;

namespace {

OccupancyGrid smallWarehouse() {
  WarehouseParams p;
  p.width = 60;
  p.height = 40;
  p.margin = 5;
  p.shelfWidth = 10;
  p.shelfHeight = 2;
  p.aisleX = 3;
  p.aisleY = 3;
  p.resolution = 0.5;
  return makeWarehouseGrid(p);
}

}  // namespace

TEST(OmplPlanner, AllAlgorithmsFindCollisionFreePathsNearTheGridOptimum) {
  const OccupancyGrid g = smallWarehouse();
  const Pose2 from{1.5, 1.5, 0.0}, to{28.0, 18.2, 1.0};
  const auto ref = astar(g, *g.cellAt(from.position()), *g.cellAt(to.position()));
  ASSERT_TRUE(ref.has_value());
  const double gridLength = ref->cost * g.resolution();
  for (OmplAlgorithm alg : {OmplAlgorithm::RRTstar, OmplAlgorithm::PRMstar, OmplAlgorithm::InformedRRTstar}) {
    OmplPlanner planner({.algorithm = alg, .timeBudget = 0.4});
    const auto path = planner.plan(g, from, to);
    ASSERT_TRUE(path.has_value()) << planner.name() << ": " << path.error().message;
    EXPECT_DOUBLE_EQ(path->poses.front().x, from.x);
    EXPECT_DOUBLE_EQ(path->poses.back().y, to.y);
    EXPECT_DOUBLE_EQ(path->poses.back().theta, to.theta);
    for (std::size_t k = 1; k < path->poses.size(); ++k) {
      EXPECT_TRUE(segmentFree(g, path->poses[k - 1].position(), path->poses[k].position())) << planner.name();
    }
    EXPECT_GE(path->length(), distance(from, to) - 1e-9);
    // Any-angle paths beat or approach the 8-connected grid path; 1.25x leaves room for a short budget.
    EXPECT_LE(path->length(), 1.25 * gridLength) << planner.name();
    EXPECT_LE(planner.lastStats().length,
              planner.lastStats().rawLength + 1e-9);  // simplification never lengthens
  }
}

TEST(OmplPlanner, RobotRadiusAndSe2AndErrors) {
  const OccupancyGrid g = smallWarehouse();
  OmplPlanner planner(
      {.algorithm = OmplAlgorithm::RRTstar, .space = OmplSpace::SE2, .timeBudget = 0.3, .robotRadius = 0.5});
  const auto path = planner.plan(g, {1.5, 1.5, 0.0}, {28.0, 18.2, 1.0});
  ASSERT_TRUE(path.has_value()) << path.error().message;
  const OccupancyGrid inflated = g.inflated(0.5);
  for (std::size_t k = 1; k < path->poses.size(); ++k) {
    EXPECT_TRUE(segmentFree(inflated, path->poses[k - 1].position(), path->poses[k].position()));
  }
  // A start next to a wall becomes blocked once inflated.
  EXPECT_EQ(planner.plan(g, {0.6, 5.0, 0.0}, {28.0, 18.2, 0.0}).error().code, "start_blocked");
  // A walled-in goal: no solution within the budget.
  OccupancyGrid walled = g;
  const Cell goal = *g.cellAt({28.0, 18.2});
  for (int dy = -1; dy <= 1; ++dy) {
    for (int dx = -1; dx <= 1; ++dx) {
      if (dx != 0 || dy != 0) {
        walled.setBlocked({goal.x + dx, goal.y + dy});
      }
    }
  }
  OmplPlanner quick({.timeBudget = 0.1});
  const auto none = quick.plan(walled, {1.5, 1.5, 0.0}, {28.0, 18.2, 0.0});
  ASSERT_FALSE(none.has_value());
  EXPECT_EQ(none.error().code, "no_solution");
}

TEST(SegmentFree, AgreesWithDenseSampling) {
  const OccupancyGrid g = smallWarehouse();
  int blocked = 0;
  for (int k = 0; k < 400; ++k) {
    const Vec2 a{1.0 + 0.07 * k, 1.2 + 0.04 * k}, b{29.0 - 0.05 * k, 18.0 - 0.03 * (k % 50)};
    bool sampled = true;
    for (int s = 0; s <= 20000 && sampled; ++s) {
      const auto c = g.cellAt(a + (b - a) * (s / 20000.0));
      sampled = c.has_value() && !g.blocked(*c);
    }
    const bool exact = segmentFree(g, a, b);
    if (sampled != exact) {
      // Dense sampling may step over a corner the exact traversal sees; never the other way round.
      EXPECT_TRUE(sampled && !exact);
    }
    blocked += exact ? 0 : 1;
  }
  EXPECT_GT(blocked, 10);
}
