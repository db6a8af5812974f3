#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/avoidance/risk_stepping.hpp"
#include "fleet/avoidance/safety_layer.hpp"
#include "fleet/core/angles.hpp"
#include "test_support.hpp"

namespace fleet::avoidance {
namespace {

using control::DiffDriveKinematics;

TEST(ArcClearance, AnalyticDistanceMatchesDenseSampling) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int trial = 0; trial < 300; ++trial) {
    const Pose2 start{u(rng), u(rng), u(rng)};
    const Twist t{0.5 * u(rng), trial % 5 == 0 ? 0.0 : u(rng)};
    const Vec2 p{u(rng), u(rng)};
    const double T = 1.7;
    double brute = 1e9;
    for (int k = 0; k <= 20000; ++k) {
      const double s = T * static_cast<double>(k) / 20000.0;
      brute = std::min(brute, distance(DiffDriveKinematics::integrateExact(start, t, s).position(), p));
    }
    EXPECT_NEAR(arcPointDistance(start, t, T, p), brute, 2e-4) << trial;
  }
}

TEST(ArcClearance, SweepsPastAHalfAndAFullTurnMatchDenseSampling) {
  // The sector test by cross products has three cases (up to half a turn, more, a full turn or
  // more); points on the circle itself and near both ends of the arc are the ones it can get wrong.
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::uniform_real_distribution<double> turn(0.2, 2.0 * kPi + 1.0);
  for (int trial = 0; trial < 400; ++trial) {
    const Pose2 start{u(rng), u(rng), kPi * u(rng)};
    const double T = 1.0;
    const double w = (trial % 2 ? 1.0 : -1.0) * turn(rng);
    const Twist t{(trial % 3 == 0 ? -0.4 : 0.6) * (1.0 + u(rng) * 0.5), w};
    // On or near the arc's circle, at any angle.
    const double R = std::abs(t.v / t.omega);
    const Vec2 c = start.position() + start.heading().perp() * (t.v / t.omega);
    const double phi = kPi * u(rng);
    const double rr = R * (1.0 + 0.3 * u(rng) * (trial % 4 == 0 ? 0.0 : 1.0));
    const Vec2 p = c + Vec2{std::cos(phi), std::sin(phi)} * rr;
    double brute = 1e9;
    for (int k = 0; k <= 20000; ++k) {
      const double s = T * static_cast<double>(k) / 20000.0;
      brute = std::min(brute, distance(DiffDriveKinematics::integrateExact(start, t, s).position(), p));
    }
    EXPECT_NEAR(arcPointDistance(start, t, T, p), brute, 2e-4) << trial << " sweep " << std::abs(w * T);
  }
}

// A planner that always asks for full speed straight ahead, whatever is there.
class Reckless final : public LocalPlanner {
 public:
  Command plan(const LocalView& v) override { return {{v.limits.vMax, 0.0}, PlanStatus::kMoving, false}; }
  [[nodiscard]] std::string_view name() const override { return "reckless"; }
};

TEST(SafetyLayer, OverrulesAPlannerDrivingIntoAWall) {
  const auto scan = test::wall({2.0, -1.0}, {2.0, 1.0});
  // Without the layer the reckless planner hits the wall.
  Reckless raw;
  const auto bad = test::drive(raw, {0, 0, 0}, {{5.0, 0.0}}, scan, 100);
  EXPECT_LT(bad.minClearance, 0.0);
  SafePlanner safe(std::make_unique<Reckless>());
  const auto good = test::drive(safe, {0, 0, 0}, {{5.0, 0.0}}, scan, 200);
  EXPECT_GT(good.overruled, 0);
  EXPECT_GE(good.minClearance, 0.0);
  EXPECT_GT(good.trace.back().x, 1.0);  // it still drove up to the wall, then stopped
  EXPECT_EQ(safe.lastSafety().twist.v, 0.0);
}

TEST(SafetyLayer, StopsForADiscCrossingItsPath) {
  LocalView v;
  v.robot.pose = {0, 0, 0};
  v.robot.twist = {0.45, 0.0};
  std::vector<MovingDisc> discs{{{1.0, -1.0}, {0.0, 1.0}, 0.3}};  // will cross at x = 1 in ~1 s
  v.discs = discs;
  const SafetyLayer layer;
  const auto r = layer.filter(v, {0.45, 0.0});
  EXPECT_TRUE(r.overruled);
  EXPECT_LT(r.twist.v, 0.45);
  EXPECT_LT(r.timeToCollision, 2.0);
  // Far away and moving away: untouched.
  discs[0] = {{5.0, 5.0}, {0.0, 1.0}, 0.3};
  const auto ok = layer.filter(v, {0.45, 0.0});
  EXPECT_FALSE(ok.overruled);
  EXPECT_EQ(ok.twist.v, 0.45);
}

TEST(SafetyLayer, AllowsBackingAwayFromSomethingTooClose) {
  LocalView v;
  v.robot.pose = {0, 0, 0};
  v.robot.radius = 0.3;
  const std::vector<Vec2> scan{{0.32, 0.0}};  // 2 cm from the surface: inside the stop zone
  v.scan = scan;
  const SafetyLayer layer;
  EXPECT_EQ(layer.filter(v, {0.2, 0.0}).twist.v, 0.0);
  EXPECT_EQ(layer.filter(v, {-0.2, 0.0}).twist.v, -0.2);
  EXPECT_FALSE(layer.filter(v, {-0.2, 0.0}).overruled);
}

TEST(SafetyLayer, RejectsNonFiniteRequests) {
  LocalView v;
  const SafetyLayer layer;
  const auto r = layer.filter(v, {std::nan(""), 0.0});
  EXPECT_TRUE(r.blocked);
  EXPECT_EQ(r.twist, Twist{});
}

TEST(SafetyLayer, SlowDownZoneCapsSpeedNearObstacles) {
  LocalView v;
  v.robot.pose = {0, 0, 0};
  v.robot.twist = {0.45, 0.0};
  v.robot.radius = 0.3;
  const auto scan = test::wall({0.0, 0.5}, {3.0, 0.5});  // wall alongside, 0.2 m from the surface
  v.scan = scan;
  const SafetyLayer layer;
  const auto r = layer.filter(v, {0.45, 0.0});
  EXPECT_TRUE(r.slowed);
  EXPECT_NEAR(r.twist.v, 0.5 * 0.45, 1e-12);
}

TEST(SafetyLayer, WithoutStaticSlowingOnlyDiscsSlowTheRobot) {
  LocalView v;
  v.robot.pose = {0, 0, 0};
  v.robot.twist = {0.45, 0.0};
  v.robot.radius = 0.3;
  const auto scan = test::wall({0.0, 0.5}, {3.0, 0.5});  // as above: 0.2 m beside the surface
  v.scan = scan;
  SafetyParams p;
  p.slowForStatic = false;
  const SafetyLayer layer(p);
  const auto r = layer.filter(v, {0.45, 0.0});
  EXPECT_FALSE(r.slowed);
  EXPECT_EQ(r.twist.v, 0.45);
  // A person 0.2 m beside the path still slows it, and the wall still stops it when driven at.
  const std::vector<MovingDisc> person{{{0.5, -0.75}, {}, 0.25}};
  v.discs = person;
  EXPECT_TRUE(layer.filter(v, {0.45, 0.0}).slowed);
  v.discs = {};
  v.robot.pose = {0, 0.1, 1.5707963};  // facing the wall, 0.1 m off it
  EXPECT_LT(layer.filter(v, {0.45, 0.0}).twist.v, 0.45);
}

TEST(Dwa, RolloutPointsFollowTheExactArc) {
  // arcPoints carries the heading's sine and cosine from point to point; every point must still lie
  // on the exact arc (integrateExact), for turns both ways, straight lines and near-straight ones.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<Vec2> pts;
  for (int trial = 0; trial < 500; ++trial) {
    const Pose2 start{10.0 * u(rng), 10.0 * u(rng), 3.2 * u(rng)};
    const double omega = trial % 5 == 0 ? 1e-10 * u(rng) : trial % 7 == 0 ? 1e-6 * u(rng) : 2.0 * u(rng);
    const Twist tw{u(rng), omega};
    const int count = 1 + trial % 12;
    arcPoints(start, tw, 1.7, count, pts);
    ASSERT_EQ(pts.size(), static_cast<std::size_t>(count));
    for (int k = 1; k <= count; ++k) {
      const Pose2 exact = DiffDriveKinematics::integrateExact(start, tw, 1.7 * k / count);
      EXPECT_NEAR(distance(pts[static_cast<std::size_t>(k - 1)], exact.position()), 0.0, 1e-9)
          << "trial " << trial << " point " << k;
    }
  }
}

TEST(Dwa, SamplesStayInsideTheDynamicWindow) {
  DynamicWindowPlanner dwa;
  LocalView v;
  v.robot.pose = {0, 0, 0};
  v.robot.twist = {0.2, 0.1};
  const std::vector<Vec2> path{{5.0, 0.0}};
  v.path = path;
  (void)dwa.plan(v);
  ASSERT_EQ(dwa.lastSamples().size(), 400u);
  for (const auto& s : dwa.lastSamples()) {
    EXPECT_LE(std::abs(s.twist.v - 0.2), v.limits.accelMax * v.dt + 1e-12);
    EXPECT_LE(std::abs(s.twist.omega - 0.1), v.limits.alphaMax * v.dt + 1e-12);
    EXPECT_GE(s.twist.v, 0.0);
  }
}

TEST(Dwa, ReachesGoalAroundAnObstacleWithoutTouchingIt) {
  const auto scan = test::ring({2.5, 0.05}, 0.5);
  SafePlanner p(std::make_unique<DynamicWindowPlanner>());
  const auto r = test::drive(p, {0, 0, 0}, {{5.0, 0.0}}, scan, 600);
  EXPECT_TRUE(r.reached);
  EXPECT_GT(r.minClearance, 0.0);
}

TEST(Dwa, RiskTermSteersToTheLowRiskSide) {
  // Mirror-symmetric scene (obstacle on the line to the goal); the risk lookup marks one half-plane
  // as risky, so the chosen turn must go to the other side, and flip when the risk is mirrored.
  const auto scan = test::ring({2.5, 0.0}, 0.5);
  const std::vector<Vec2> path{{5.0, 0.0}};
  for (const double side : {1.0, -1.0}) {
    DynamicWindowPlanner dwa;
    LocalView v;
    v.robot.pose = {0.8, 0.0, 0.0};
    v.robot.twist = {0.3, 0.0};
    v.path = path;
    v.scan = scan;
    v.risk = [side](Vec2 p) { return side * p.y > 1e-9 ? 0.9 : 0.0; };
    const Command c = dwa.plan(v);
    ASSERT_EQ(c.status, PlanStatus::kMoving);
    EXPECT_LT(side * c.twist.omega, 0.0) << side;
    // Without risk the scene is symmetric up to sampling; the risk weight is what decides.
    v.risk = [](Vec2) { return 0.0; };
    DwaParams no_risk;
    no_risk.wRisk = 0.0;
    v.risk = [side](Vec2 p) { return side * p.y > 1e-9 ? 0.9 : 0.0; };
    DynamicWindowPlanner blind(no_risk);
    const Command cb = blind.plan(v);
    double max_risk_chosen = 0.0;
    for (const auto& s : blind.lastSamples()) {
      if (s.twist == cb.twist)
        max_risk_chosen = s.risk;
    }
    double risk_aware_chosen = 1.0;
    for (const auto& s : dwa.lastSamples()) {
      if (s.twist == c.twist)
        risk_aware_chosen = s.risk;
    }
    EXPECT_LE(risk_aware_chosen, max_risk_chosen);
    EXPECT_EQ(risk_aware_chosen, 0.0);
  }
}

TEST(Dwa, RiskThroughTheRiskMapQueryApiSteersToTheLowRiskSide) {
  // The same mirrored scene as above, with the risk read the way the agent reads the risk map:
  // riskLookup over a ProbabilityGrid (cells of the map, bilinear lookup), one half-plane at 0.9.
  const auto scan = test::ring({2.5, 0.0}, 0.5);
  const std::vector<Vec2> path{{5.0, 0.0}};
  for (const double side : {1.0, -1.0}) {
    risk::ProbabilityGrid grid;
    grid.spec = {-2.0, -4.0, 0.1, 100, 80};
    grid.p.assign(grid.spec.cellCount(), 0.0);
    for (int j = 0; j < grid.spec.height; ++j) {
      for (int i = 0; i < grid.spec.width; ++i) {
        grid.p[grid.spec.index(i, j)] = side * grid.spec.cellCentreY(j) > 0.0 ? 0.9 : 0.0;
      }
    }
    LocalView v;
    v.robot.pose = {0.8, 0.0, 0.0};
    v.robot.twist = {0.3, 0.0};
    v.path = path;
    v.scan = scan;
    v.risk = riskLookup(grid);
    ASSERT_GT(v.riskAt({2.0, side * 0.5}), 0.5);
    ASSERT_EQ(v.riskAt({2.0, -side * 0.5}), 0.0);
    DynamicWindowPlanner dwa;
    const Command c = dwa.plan(v);
    ASSERT_EQ(c.status, PlanStatus::kMoving);
    EXPECT_LT(side * c.twist.omega, 0.0) << side;
    for (const auto& smp : dwa.lastSamples()) {
      if (smp.twist == c.twist) {
        EXPECT_EQ(smp.risk, 0.0) << side;
      }
    }
  }
}

TEST(Dwa, WeightsChangeTheChoice) {
  // With clearance weighted heavily the robot keeps farther from a wall it drives along.
  const auto scan = test::wall({0.0, 0.6}, {6.0, 0.6});
  DwaParams greedy;
  greedy.wClearance = 0.0;
  DwaParams careful;
  careful.wClearance = 3.0;
  DynamicWindowPlanner a(greedy), b(careful);
  const auto ra = test::drive(a, {0, 0, 0}, {{6.0, 0.3}}, scan, 400);
  const auto rb = test::drive(b, {0, 0, 0}, {{6.0, 0.3}}, scan, 400);
  EXPECT_GT(rb.minClearance, ra.minClearance);
}

}  // namespace
}  // namespace fleet::avoidance

namespace fleet::avoidance {
namespace {

// Discs too far for any rollout to come within clearanceCap of are left out of the rollouts'
// check: adding any number of them (moving towards the robot at up to 1.5 m/s, just past that
// reach) changes no sample and no command, with and without pruning.
TEST(Dwa, DiscsBeyondTheClearanceCapChangeNothing) {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int farDiscs = 0;
  int insideChanged = 0;
  for (int k = 0; k < 200; ++k) {
    DwaParams params;
    params.prune = k % 2 == 0;
    std::vector<Vec2> scan;
    for (int i = 0; i < static_cast<int>(rng() % 200); ++i)
      scan.push_back({3.0 * u(rng), 3.0 * u(rng)});
    std::vector<MovingDisc> discs;
    for (int i = 0; i < static_cast<int>(rng() % 5); ++i)
      discs.push_back({{2.5 * u(rng), 2.5 * u(rng)}, {0.5 * u(rng), 0.5 * u(rng)}, 0.3});
    LocalView v;
    v.robot = {{0.0, 0.0, 3.0 * u(rng)}, {0.4 + 0.4 * u(rng), 0.5 * u(rng)}, 0.3};
    const std::vector<Vec2> path{{5.0 * u(rng), 5.0 * u(rng)}};
    v.path = path;
    v.scan = scan;
    v.discs = discs;
    DynamicWindowPlanner a(params);
    const Command ca = a.plan(v);
    // The farthest a rollout's point gets: the window's fastest speed over the horizon (a robot
    // faster than its limit brakes by at most one cycle's deceleration).
    const double vHi = std::min(v.robot.twist.v + v.limits.accelMax * v.dt, v.limits.vMax);
    const double vLo = std::max(0.0, v.robot.twist.v - v.limits.accelMax * v.dt);
    const double travel = std::max(vHi, vLo) * params.simTime;
    std::vector<MovingDisc> more = discs;
    for (int i = 0; i < 30; ++i) {
      const double speed = 1.5 * std::abs(u(rng));
      const double r = 0.2 + 0.2 * std::abs(u(rng));
      const double d = travel + speed * params.simTime + v.robot.radius + r + params.clearanceCap + 1e-6 +
                       0.02 * std::abs(u(rng));
      // Most of them ahead, where the fastest rollouts end.
      const double a0 = i % 3 == 0 ? 3.2 * u(rng) : v.robot.pose.theta + 0.3 * u(rng);
      const Vec2 at{d * std::cos(a0), d * std::sin(a0)};
      more.push_back({at, at * (-speed / d), r});  // heading straight at the robot
      ++farDiscs;
    }
    // The rule is tight: a disc just inside that reach, straight ahead and coming at the robot,
    // does change the clearance of the fastest straight rollout.
    {
      const double speed = 1.0;
      const double d = travel + speed * params.simTime + v.robot.radius + 0.3 + params.clearanceCap - 0.01;
      const Vec2 dir{std::cos(v.robot.pose.theta), std::sin(v.robot.pose.theta)};
      std::vector<MovingDisc> inside = discs;
      inside.push_back({dir * d, dir * -speed, 0.3});
      v.discs = inside;
      DynamicWindowPlanner c(params);
      (void)c.plan(v);
      for (std::size_t i = 0; i < a.lastSamples().size(); ++i)
        insideChanged += c.lastSamples()[i].clearance != a.lastSamples()[i].clearance ? 1 : 0;
    }
    v.discs = more;
    DynamicWindowPlanner b(params);
    const Command cb = b.plan(v);
    EXPECT_EQ(ca.twist, cb.twist) << k;
    EXPECT_EQ(ca.status, cb.status) << k;
    ASSERT_EQ(a.lastSamples().size(), b.lastSamples().size());
    for (std::size_t i = 0; i < a.lastSamples().size(); ++i) {
      const DwaSample& x = a.lastSamples()[i];
      const DwaSample& y = b.lastSamples()[i];
      EXPECT_EQ(x.score, y.score) << k << " sample " << i;
      EXPECT_EQ(x.clearance, y.clearance) << k << " sample " << i;
      EXPECT_EQ(x.admissible, y.admissible) << k << " sample " << i;
      EXPECT_EQ(x.evaluated, y.evaluated) << k << " sample " << i;
    }
  }
  EXPECT_EQ(farDiscs, 6000);
  EXPECT_GT(insideChanged, 0);
}

// The pruned search must pick exactly the command the exhaustive one picks.
TEST(Dwa, PrunedSearchChoosesTheSameCommandAsTheExhaustiveOne) {
  std::mt19937 rng(2024);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  DwaParams full;
  full.prune = false;
  DwaParams fast;
  fast.prune = true;
  int evaluated_fewer = 0;
  for (int k = 0; k < 150; ++k) {
    std::vector<Vec2> scan;
    const int pts = static_cast<int>(rng() % 360);
    for (int i = 0; i < pts; ++i)
      scan.push_back({3.0 * u(rng), 3.0 * u(rng)});
    std::vector<MovingDisc> discs;
    for (int i = 0; i < static_cast<int>(rng() % 6); ++i)
      discs.push_back({{4.0 * u(rng), 4.0 * u(rng)}, {0.5 * u(rng), 0.5 * u(rng)}, 0.3});
    const std::vector<Vec2> path{{5.0 * u(rng), 5.0 * u(rng)}};
    LocalView v;
    v.robot = {{0.0, 0.0, 3.0 * u(rng)}, {0.2 + 0.2 * u(rng), 0.5 * u(rng)}, 0.3};
    v.path = path;
    v.scan = scan;
    v.discs = discs;
    if (k % 2 == 0) {
      const double cx = u(rng), cy = u(rng);
      v.risk = [cx, cy](Vec2 p) { return std::exp(-((p.x - cx) * (p.x - cx) + (p.y - cy) * (p.y - cy))); };
    }
    DynamicWindowPlanner a(full), b(fast);
    const Command ca = a.plan(v);
    const Command cb = b.plan(v);
    EXPECT_EQ(ca.twist, cb.twist) << k;
    EXPECT_EQ(ca.status, cb.status) << k;
    int n_eval = 0;
    for (const auto& s : b.lastSamples())
      n_eval += s.evaluated ? 1 : 0;
    if (n_eval < static_cast<int>(a.lastSamples().size()))
      ++evaluated_fewer;
  }
  EXPECT_GT(evaluated_fewer, 0);  // the pruning actually prunes
}

}  // namespace
}  // namespace fleet::avoidance
