#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <vector>

#include "fleet/avoidance/elastic_strips.hpp"
#include "test_support.hpp"

namespace fleet::avoidance {
namespace {

// Seed 000 §7 worked values (units as in the thesis: mm).
TEST(ElasticStrips, InternalForceWorkedExample) {
  const Vec2 f = elasticInternalForce({0, 0}, {1, 1}, {2, 0}, 0.8);
  EXPECT_NEAR(f.x, 0.0, 1e-12);
  EXPECT_NEAR(f.y, -0.8, 1e-12);
  const Vec2 z = elasticInternalForce({0, 0}, {1, 1}, {2, 2}, 0.8);  // collinear, evenly spaced
  EXPECT_NEAR(z.x, 0.0, 1e-12);
  EXPECT_NEAR(z.y, 0.0, 1e-12);
}

TEST(ElasticStrips, OriginalExternalForceWorkedExample) {
  // dSafe 1000, d_r 350 -> d_o 1350; d_obs,min 1000, K_r 0.6 -> |F| = 210, from obstacle to robot.
  const Vec2 f = elasticExternalForce({0, 1000}, {0, 0}, 1000.0, 1000.0 + 350.0, 0.6);
  EXPECT_NEAR(f.x, 0.0, 1e-9);
  EXPECT_NEAR(f.y, 210.0, 1e-9);
  EXPECT_EQ(elasticExternalForce({0, 1350}, {0, 0}, 1350.0, 1350.0, 0.6), (Vec2{0, 0}));
  EXPECT_EQ(elasticExternalForce({0, 2000}, {0, 0}, 2000.0, 1350.0, 0.6), (Vec2{0, 0}));
}

TEST(ElasticStrips, TwoSidedExternalForceWorkedExample) {
  // d_L 800, threshold dSafe 1000, K_r 0.6 -> 120.
  const Vec2 f = elasticExternalForce({800, 0}, {0, 0}, 800.0, 1000.0, 0.6);
  EXPECT_NEAR(f.x, 120.0, 1e-9);
  EXPECT_EQ(elasticExternalForce({1000, 0}, {0, 0}, 1000.0, 1000.0, 0.6), (Vec2{0, 0}));
}

TEST(ElasticStrips, LeftRightMinimumWorkedExample) {
  const std::vector<double> a{1200, 900, 1500, 700};
  const auto m = leftRightMinimum(a, 1000.0);
  EXPECT_TRUE(m.found);
  EXPECT_EQ(m.minLeft, 900.0);
  EXPECT_EQ(m.minRight, 700.0);
  EXPECT_EQ(m.leftIndex, 1);
  EXPECT_EQ(m.rightIndex, 3);
  const std::vector<double> far{1200, 1000, 1500, 1700};
  EXPECT_FALSE(leftRightMinimum(far, 1000.0).found);
}

// Table 2.3 case 1 in metres: start (0, 0), goal (3.5, 5), K_c 0.8, K_r 0.6, dSafe 1 m, d_r 0.35 m.
// The thesis gives no obstacle; we put a 0.3 m disc centred on the start–goal line (documented).
TEST(ElasticStrips, Table23Case1TwoSidedVariantReachesGoal) {
  const Vec2 goal{3.5, 5.0};
  const auto obstacle = test::ring(goal * 0.5, 0.3, 48);
  ElasticStripsPlanner improved(ElasticVariant::kBvhTwoSided);
  const auto r = test::drive(improved, {0, 0, std::atan2(5.0, 3.5)}, {goal}, obstacle, 1500, {}, 0.35);
  EXPECT_TRUE(r.reached);
  EXPECT_GT(r.minClearance, 0.0);
}

TEST(ElasticStrips, Table23Case1OriginalDoesNotGetPast) {
  // The original's single external force is collinear with the internal one on the line: the
  // robot stalls in front of the obstacle or hits it (thesis Fig. 2.26), never reaching the goal.
  const Vec2 goal{3.5, 5.0};
  const auto obstacle = test::ring(goal * 0.5, 0.3, 48);
  ElasticStripsPlanner original(ElasticVariant::kOriginal);
  const auto r = test::drive(original, {0, 0, std::atan2(5.0, 3.5)}, {goal}, obstacle, 1500, {}, 0.35);
  EXPECT_FALSE(r.reached);
}

// Table 2.3 cases 2-4 (metres). The thesis gives the start, goals, gains and radii but no
// obstacles ("two" in case 2, "three" in cases 3 and 4). We invent 0.3 m discs that exercise what
// the two-sided variant was made for (limitation 3 of the original: obstacles on both sides): a
// gate of two discs across the start-goal line, 0.75 m either side of it (0.9 m between their
// surfaces for a 0.7 m robot), and in cases 3-4 a third disc 0.3 m off the line further on.
struct Table23Case {
  Vec2 goal;
  double kC;
  double kR;
  int obstacles;
};

std::vector<Vec2> table23Obstacles(const Table23Case& c) {
  const Vec2 along = c.goal / c.goal.norm();
  const Vec2 left{-along.y, along.x};
  const double gateAt = c.obstacles == 2 ? 0.5 : 0.35;
  std::vector<Vec2> centres = {c.goal * gateAt + left * 0.7, c.goal * gateAt - left * 0.8};
  if (c.obstacles == 3) {
    centres.push_back(c.goal * 0.7 + left * 0.3);
  }
  std::vector<Vec2> scan;
  for (const Vec2& centre : centres) {
    const auto ring = test::ring(centre, 0.3, 48);
    scan.insert(scan.end(), ring.begin(), ring.end());
  }
  return scan;
}

/// Σ|Δheading| over the run: how much the robot turned in total (a straight run: 0).
double totalTurning(const test::RunResult& r) {
  double sum = 0.0;
  for (std::size_t k = 1; k < r.trace.size(); ++k) {
    sum += std::abs(angleDiff(r.trace[k].theta, r.trace[k - 1].theta));
  }
  return sum;
}

struct Table23Runs {
  test::RunResult original;
  test::RunResult twoSided;
};

Table23Runs runTable23(const Table23Case& c) {
  const auto scan = table23Obstacles(c);
  ElasticStripsParams prm;
  prm.kC = c.kC;
  prm.kR = c.kR;
  const Pose2 start{0, 0, std::atan2(c.goal.y, c.goal.x)};
  ElasticStripsPlanner original(ElasticVariant::kOriginal, prm);
  ElasticStripsPlanner improved(ElasticVariant::kBvhTwoSided, prm);
  Table23Runs r{test::drive(original, start, {c.goal}, scan, 3000, {}, 0.35),
                test::drive(improved, start, {c.goal}, scan, 3000, {}, 0.35)};
  std::cout << "goal (" << c.goal.x << ", " << c.goal.y << "): original reached " << r.original.reached
            << " in " << r.original.steps << " steps, clearance " << r.original.minClearance << " m, turning "
            << totalTurning(r.original) << " rad; two-sided reached " << r.twoSided.reached << " in "
            << r.twoSided.steps << " steps, clearance " << r.twoSided.minClearance << " m, turning "
            << totalTurning(r.twoSided) << " rad\n";
  return r;
}

// Limitation 3 of the original (seed 000 §3): pushed away from the nearest disc of the gate it is
// pushed into the other one. The two-sided variant with the thesis's boxes passes the gate without
// touching either disc and turns a third less (the thesis: both reach, the improved path is
// smoother). Without the boxes (forces from every reading within dSafe) it stopped in front of the
// gate, the two pushes balancing (docs/algorithms.md).
TEST(ElasticStrips, Table23Case2GateOriginalTouchesTwoSidedPassesWithoutContact) {
  const auto r = runTable23({{4.0, 3.5}, 0.8, 0.6, 2});
  EXPECT_TRUE(r.original.reached);
  EXPECT_LT(r.original.minClearance, 0.0);
  EXPECT_TRUE(r.twoSided.reached);
  EXPECT_GT(r.twoSided.minClearance, 0.0);
  EXPECT_LT(totalTurning(r.twoSided), totalTurning(r.original));
}

TEST(ElasticStrips, ObstacleBoxSpansBothReadingsAndDSafeAlongTheMotion) {
  // L and R 1 m ahead, 0.5 m either side; dSafe 1 m along +x: the box covers x in [1, 2], y in [-0.5, 0.5].
  const geometry::Obb2 o = obstacleBox({1.0, 0.5}, {1.0, -0.5}, {1.0, 0.0}, 1.0);
  EXPECT_NEAR(o.center.x, 1.5, 1e-12);
  EXPECT_NEAR(o.center.y, 0.0, 1e-12);
  EXPECT_NEAR(o.half.x, 0.5, 1e-12);  // along L→R
  EXPECT_NEAR(o.half.y, 0.5, 1e-12);  // across it: dSafe / 2
  // The robot's swept footprint: r behind the robot to r past the next control point.
  const geometry::Obb2 far = robotBox({0.0, 0.0}, {0.3, 0.0}, {1.0, 0.0}, 0.35);
  EXPECT_NEAR(far.center.x, 0.15, 1e-12);
  EXPECT_NEAR(far.half.x, 0.5, 1e-12);
  EXPECT_NEAR(far.half.y, 0.35, 1e-12);
  EXPECT_FALSE(geometry::overlaps(far, o));  // reaches x = 0.65 < 1
  EXPECT_TRUE(geometry::overlaps(robotBox({0.5, 0.0}, {0.8, 0.0}, {1.0, 0.0}, 0.35), o));  // x = 1.15
  // A heading oblique to L→R: the box is the rectangle around the parallelogram.
  const geometry::Obb2 skew = obstacleBox({0.0, 0.5}, {0.0, -0.5}, {std::sqrt(0.5), std::sqrt(0.5)}, 1.0);
  EXPECT_NEAR(skew.half.x, 0.5 + 0.5 * std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(skew.half.y, 0.5 * std::sqrt(0.5), 1e-12);
}

TEST(ElasticStrips, TwoSidedPushesOnlyWhenTheBoxesMeetAndOnePointFallsBackToTheOriginal) {
  ElasticStripsParams prm;  // Table 2.3 case 1: K_r 0.6, dSafe 1 m
  const std::vector<Vec2> path{{6.0, 0.0}};
  LocalView v;
  v.robot.radius = 0.35;
  v.path = path;
  // A gate 1.2 m wide, its posts 1.25 m ahead: within dSafe + r of the next point (0.3 m ahead), but
  // the step's footprint (to 0.65 m) does not reach the gate's box: no external force yet.
  std::vector<Vec2> gate{{1.25, 0.6}, {1.25, -0.6}};
  v.scan = gate;
  v.robot.pose = {0.0, 0.0, 0.0};
  ElasticStripsPlanner es(ElasticVariant::kBvhTwoSided, prm);
  (void)es.plan(v);
  EXPECT_EQ(es.lastContact(), ElasticStripsPlanner::Contact::kBoxesApart);
  EXPECT_NEAR(es.lastForce().y, 0.0, 1e-12);
  // 0.7 m closer the footprint (to 1.35 m) meets it: both posts push, symmetric sideways.
  v.robot.pose = {0.7, 0.0, 0.0};
  ElasticStripsPlanner near(ElasticVariant::kBvhTwoSided, prm);
  (void)near.plan(v);
  EXPECT_EQ(near.lastContact(), ElasticStripsPlanner::Contact::kBoxesMeet);
  EXPECT_NEAR(near.lastForce().y, 0.0, 1e-9);
  // One post only: the original's single-reading force (threshold dSafe + r on the centre distance).
  std::vector<Vec2> post{{1.25, 0.6}};
  v.scan = post;
  v.robot.pose = {0.5, 0.0, 0.0};
  ElasticStripsPlanner one(ElasticVariant::kBvhTwoSided, prm);
  (void)one.plan(v);
  EXPECT_EQ(one.lastContact(), ElasticStripsPlanner::Contact::kOnePoint);
  const Vec2 at{0.8, 0.0};
  const Vec2 expected = elasticExternalForce(at, post[0], distance(at, post[0]), 1.0 + 0.35, 0.6);
  ElasticStripsPlanner original(ElasticVariant::kOriginal, prm);
  (void)original.plan(v);
  EXPECT_NEAR(one.lastForce().x, original.lastForce().x, 1e-12);
  EXPECT_NEAR(one.lastForce().y, original.lastForce().y, 1e-12);
  EXPECT_LT(expected.y, 0.0);  // pushed away from the post on the left
}

// With the softer gains of cases 3 and 4 (K_c 0.6, K_r 0.3) the two-sided variant passes the gate
// and the third disc without contact, turning less than half as much as the original, which brushes
// a disc on the way (the thesis: both reach, the improved path is smoother).
TEST(ElasticStrips, Table23Cases3And4TwoSidedReachesWithoutContactAndSmoother) {
  for (const Table23Case& c : {Table23Case{{5.0, 4.0}, 0.6, 0.3, 3}, Table23Case{{6.0, 5.5}, 0.6, 0.3, 3}}) {
    const auto r = runTable23(c);
    EXPECT_TRUE(r.twoSided.reached) << c.goal.x;
    EXPECT_GT(r.twoSided.minClearance, 0.0) << c.goal.x;
    EXPECT_TRUE(r.original.reached) << c.goal.x;
    EXPECT_LT(r.original.minClearance, 0.0) << c.goal.x;
    EXPECT_LT(totalTurning(r.twoSided), 0.5 * totalTurning(r.original)) << c.goal.x;
  }
}

}  // namespace
}  // namespace fleet::avoidance
