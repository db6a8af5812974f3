#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "fleet/avoidance/bug.hpp"
#include "fleet/avoidance/potential_field.hpp"
#include "fleet/avoidance/risk_stepping.hpp"
#include "fleet/avoidance/safety_layer.hpp"
#include "test_support.hpp"

namespace fleet::avoidance {
namespace {

// Seed 002 worked values.
TEST(PotentialField, AttractiveForceWorkedExample) {
  const Vec2 f = attractiveForce({0, 0}, {3, 4}, 1.0);
  EXPECT_DOUBLE_EQ(f.x, 3.0);
  EXPECT_DOUBLE_EQ(f.y, 4.0);
  EXPECT_EQ(attractiveForce({3, 4}, {3, 4}, 1.0), (Vec2{0, 0}));
}

TEST(PotentialField, KhatibRepulsionWorkedExample) {
  // kRep = 1, ρ0 = 1, obstacle at the origin, q = (0.5, 0): Khatib's form gives (4, 0); the
  // seed's printed (3.8) would give (1, 0).
  const Vec2 f = repulsiveForce({0.5, 0}, {0, 0}, 0.5, 1.0, 1.0);
  EXPECT_NEAR(f.x, 4.0, 1e-12);
  EXPECT_NEAR(f.y, 0.0, 1e-12);
  EXPECT_EQ(repulsiveForce({1.0, 0}, {0, 0}, 1.0, 1.0, 1.0), (Vec2{0, 0}));
  EXPECT_EQ(repulsiveForce({1.5, 0}, {0, 0}, 1.5, 1.0, 1.0), (Vec2{0, 0}));
}

TEST(PotentialField, RepulsionIsMonotoneAndPointsAway) {
  double prev = 0.0;
  for (double rho = 1.0; rho > 0.05; rho -= 0.05) {
    const Vec2 q{0.6 * rho, 0.8 * rho};
    const Vec2 f = repulsiveForce(q, {0, 0}, rho, 1.0, 1.0);
    EXPECT_GE(std::sqrt(f.squaredNorm()), prev);
    prev = std::sqrt(f.squaredNorm());
    EXPECT_GE(f.dot(q), 0.0);
    EXPECT_NEAR(f.cross(q), 0.0, 1e-9);
  }
}

TEST(PotentialField, TotalForceSumsEveryReading) {
  LocalView v;
  v.robot.pose = {0, 0, 0};
  v.robot.radius = 0.0;
  const std::vector<Vec2> path{{0, 0}};
  v.path = path;  // goal at the robot: no attraction
  const std::vector<Vec2> one{{0.5, 0}};
  const std::vector<Vec2> two{{0.5, 0}, {0.5, 0}};
  PotentialFieldParams p;
  p.kRep = 1.0;
  v.scan = one;
  const Vec2 f1 = totalForce(v, p);
  v.scan = two;
  const Vec2 f2 = totalForce(v, p);
  EXPECT_NEAR(f2.x, 2.0 * f1.x, 1e-12);
  EXPECT_NEAR(f1.x, -4.0, 1e-12);
}

TEST(PotentialField, ReachesGoalPastAnOffsetObstacleWithinLimits) {
  const auto scan = test::ring({2.5, 0.6}, 0.4);
  PotentialFieldPlanner pf;
  LocalView probe;
  const auto r = test::drive(pf, {0, 0, 0}, {{5.0, 0.0}}, scan, 800);
  EXPECT_TRUE(r.reached);
  EXPECT_GT(r.minClearance, 0.0);
}

std::vector<Vec2> uTrap() {
  // U open towards the start (−x), its base across the line to the goal.
  auto pts = test::wall({3.0, -1.2}, {3.0, 1.2});
  const auto top = test::wall({1.5, 1.2}, {3.0, 1.2});
  const auto bottom = test::wall({1.5, -1.2}, {3.0, -1.2});
  pts.insert(pts.end(), top.begin(), top.end());
  pts.insert(pts.end(), bottom.begin(), bottom.end());
  return pts;
}

TEST(PotentialField, UShapeTrapIsDetectedAndReported) {
  PotentialFieldParams p;
  p.escapeWithBug2 = false;
  PotentialFieldPlanner pf(p);
  const auto scan = uTrap();
  const auto r = test::drive(pf, {0, 0, 0}, {{6.0, 0.0}}, scan, 600);
  EXPECT_FALSE(r.reached);
  EXPECT_GT(pf.stuckDetections(), 0);
  EXPECT_LT(r.trace.back().x, 3.0);  // trapped inside the U
}

TEST(PotentialField, Bug2EscapeLeavesTheTrapAndReachesTheGoal) {
  PotentialFieldPlanner pf;
  const auto scan = uTrap();
  const auto r = test::drive(pf, {0, 0, 0}, {{6.0, 0.0}}, scan, 3000);
  EXPECT_TRUE(r.reached);
  EXPECT_GT(pf.stuckDetections(), 0);
  EXPECT_GT(r.minClearance, 0.0);
}

TEST(Bug, BothReachGoalPastABoxAndBug2IsShorter) {
  // Square obstacle on the start–goal line.
  std::vector<Vec2> box = test::wall({2.0, -0.8}, {2.0, 0.8});
  for (const auto& seg : {test::wall({2.0, 0.8}, {3.6, 0.8}), test::wall({3.6, 0.8}, {3.6, -0.8}),
                          test::wall({3.6, -0.8}, {2.0, -0.8})}) {
    box.insert(box.end(), seg.begin(), seg.end());
  }
  BugPlanner b1(BugVariant::kBug1), b2(BugVariant::kBug2);
  const auto r1 = test::drive(b1, {0, 0, 0}, {{6.0, 0.0}}, box, 4000);
  const auto r2 = test::drive(b2, {0, 0, 0}, {{6.0, 0.0}}, box, 4000);
  EXPECT_TRUE(r1.reached);
  EXPECT_TRUE(r2.reached);
  EXPECT_EQ(b1.hits(), 1);
  EXPECT_EQ(b2.hits(), 1);
  EXPECT_GT(r1.minClearance, 0.0);
  EXPECT_GT(r2.minClearance, 0.0);
  EXPECT_LT(r2.path_length, r1.path_length);
  // Bug1 went all the way round: at least the box perimeter plus the detour to L.
  EXPECT_GT(r1.path_length, 2.0 * (1.6 + 1.6) + 6.0);
}

TEST(Bug, EnclosedGoalIsReportedUnreachable) {
  const auto scan = test::ring({5.0, 0.0}, 1.0, 128);
  for (const auto variant : {BugVariant::kBug1, BugVariant::kBug2}) {
    BugPlanner b(variant);
    LocalView v;
    v.robot.pose = {0, 0, 0};
    v.robot.radius = 0.3;
    const std::vector<Vec2> path{{5.0, 0.0}};
    v.path = path;
    v.scan = scan;
    PlanStatus last = PlanStatus::kMoving;
    for (int k = 0; k < 6000 && last == PlanStatus::kMoving; ++k) {
      const Command c = b.plan(v);
      last = c.status;
      const auto lt = control::applyLimits(v.limits, c.twist, v.robot.twist, v.dt);
      v.robot.pose = control::DiffDriveKinematics::integrateExact(v.robot.pose, lt.twist, v.dt);
      v.robot.twist = lt.twist;
    }
    EXPECT_EQ(last, PlanStatus::kUnreachable) << static_cast<int>(variant);
  }
}

TEST(RiskStepping, PicksTheLowestRiskReachableCandidate) {
  // Risk is high everywhere except a band at y < −0.2: the chosen point must be in that band,
  // though the goal lies straight ahead.
  risk::ProbabilityGrid grid;
  grid.spec = {-5.0, -5.0, 0.1, 100, 100};
  grid.p.assign(grid.spec.cellCount(), 0.0);
  for (int j = 0; j < 100; ++j) {
    for (int i = 0; i < 100; ++i) {
      grid.p[grid.spec.index(i, j)] =
          grid.spec.cellCentreY(j) > -0.2 && grid.spec.cellCentreX(i) > 0.2 ? 0.8 : 0.0;
    }
  }
  LocalView v;
  v.robot.pose = {0, 0, 0};
  const std::vector<Vec2> path{{4.0, 0.0}};
  v.path = path;
  v.risk = riskLookup(grid);
  RiskSteppingPlanner rs;
  const auto c = rs.choose(v);
  ASSERT_TRUE(c.found);
  EXPECT_LT(c.point.y, -0.2);
  EXPECT_DOUBLE_EQ(c.safety, 1.0);
  // Without risk it heads straight for the goal.
  v.risk = {};
  const auto straight = rs.choose(v);
  EXPECT_NEAR(straight.point.y, 0.0, 1e-9);
}

TEST(RiskStepping, TheIsoLevelRuleNeverTradesRiskForProgressTheWeightedOneDoes) {
  // Straight at the goal the segment's P is 0.11 (level 2 of K = 10); 0.6 rad or more off it, 0.09
  // (level 1). The weighted score prefers straight (0.89 + 0.3·1 against 0.91 + 0.3·0.78); thesis
  // §3.2.3 steps into the highest-complement level, and there goes as far towards the goal as it
  // can: the level-1 candidates nearest the goal's bearing, ±4/24·4 rad on the 25-point ±2 rad fan.
  LocalView v;
  v.robot.pose = {0, 0, 0};
  const std::vector<Vec2> path{{4.0, 0.0}};
  v.path = path;
  v.risk = [](Vec2 q) { return std::abs(std::atan2(q.y, q.x)) < 0.6 ? 0.11 : 0.09; };

  const auto thesis = RiskSteppingPlanner().choose(v);
  ASSERT_TRUE(thesis.found);
  EXPECT_EQ(thesis.level, 1);
  EXPECT_NEAR(thesis.safety, 0.91, 1e-12);
  EXPECT_NEAR(std::abs(std::atan2(thesis.point.y, thesis.point.x)), 4.0 * 4.0 / 24.0, 1e-9);

  RiskSteppingParams wp;
  wp.rule = SteppingRule::kWeighted;
  const auto weighted = RiskSteppingPlanner(wp).choose(v);
  ASSERT_TRUE(weighted.found);
  EXPECT_EQ(weighted.level, 2);
  EXPECT_NEAR(weighted.point.y, 0.0, 1e-9);
  EXPECT_GT(weighted.point.x, 0.4);
}

TEST(RiskStepping, DrivesRoundARiskierPatchTheWeightedRuleCrosses) {
  // P = 0.11 over a box on the straight line to the goal, 0.09 everywhere else.
  const auto inBox = [](Vec2 q, double margin) {
    return q.x > 1.0 + margin && q.x < 2.5 - margin && std::abs(q.y) < 0.5 - margin;
  };
  const RiskLookup risk = [&](Vec2 q) { return inBox(q, 0.0) ? 0.11 : 0.09; };
  const auto entered = [&](const test::RunResult& r) {
    return std::any_of(r.trace.begin(), r.trace.end(),
                       [&](const Pose2& q) { return inBox(q.position(), 0.1); });
  };
  RiskSteppingPlanner thesis;
  const auto a = test::drive(thesis, {0, 0, 0}, {{4.0, 0.0}}, {}, 600, risk);
  EXPECT_TRUE(a.reached);
  EXPECT_FALSE(entered(a));
  RiskSteppingParams wp;
  wp.rule = SteppingRule::kWeighted;
  RiskSteppingPlanner weighted(wp);
  const auto b = test::drive(weighted, {0, 0, 0}, {{4.0, 0.0}}, {}, 600, risk);
  EXPECT_TRUE(b.reached);
  EXPECT_TRUE(entered(b));
}

TEST(RiskStepping, AimsAtTheCarrotOnThePathNotAtItsEnd) {
  // An L-shaped path whose end lies behind a wall: the first step follows the path's first leg.
  LocalView v;
  v.robot.pose = {0, 0, 0};
  const std::vector<Vec2> path{{0.0, 0.0}, {3.0, 0.0}, {3.0, -3.0}};
  v.path = path;
  const auto c = RiskSteppingPlanner().choose(v);
  ASSERT_TRUE(c.found);
  EXPECT_NEAR(c.point.y, 0.0, 1e-9);
  EXPECT_GT(c.point.x, 0.4);
}

TEST(RiskStepping, CandidatesThroughObstaclesAreUnreachable) {
  const auto scan = test::wall({0.5, -0.1}, {0.5, 0.1});
  LocalView v;
  v.robot.pose = {0, 0, 0};
  v.robot.radius = 0.2;
  const std::vector<Vec2> path{{4.0, 0.0}};
  v.path = path;
  v.scan = scan;
  RiskSteppingPlanner rs;
  const auto c = rs.choose(v);
  ASSERT_TRUE(c.found);
  EXPECT_GT(std::abs(c.point.y), 0.2);
  const auto r = test::drive(rs, {0, 0, 0}, {{4.0, 0.0}}, scan, 400, {}, 0.2);
  EXPECT_TRUE(r.reached);
  EXPECT_GT(r.minClearance, 0.0);
}

TEST(Factory, BuildsEveryPlannerByName) {
  for (const char* n :
       {"dwa", "potential_field", "bug1", "bug2", "risk_stepping", "elastic_strips", "elastic_strips_bvh"}) {
    auto p = makePlanner(n);
    ASSERT_TRUE(p.has_value()) << n;
    EXPECT_EQ((*p)->name(), n);
  }
  auto weighted = makePlanner("risk_stepping_weighted");
  ASSERT_TRUE(weighted.has_value());
  EXPECT_EQ((*weighted)->name(), "risk_stepping_weighted");
  EXPECT_FALSE(makePlanner("teleport").has_value());
}

}  // namespace
}  // namespace fleet::avoidance
