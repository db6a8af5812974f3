#include <gtest/gtest.h>

#include <algorithm>

#include <cmath>
#include <random>

#include "fleet/sim/flow_field.hpp"
#include "fleet/sim/social_force.hpp"
#include "fleet/sim/spatial_hash.hpp"
#include "fleet/sim/world.hpp"
#include "sim_fixtures.hpp"

using namespace fleet;
using namespace fleet::sim;

TEST(SocialForce, DrivingForceRelaxesWithinTau) {
  const Vec2 f = drivingForce({1.3, 0.0}, {0.3, 0.0}, 0.5);
  EXPECT_DOUBLE_EQ(f.x, 2.0);
  EXPECT_DOUBLE_EQ(f.y, 0.0);
}

TEST(SocialForce, RepulsionIsSymmetricWithoutAnisotropyAndDecaysExponentially) {
  const Vec2 a{0.0, 0.0};
  const Vec2 b{0.8, 0.3};
  const Vec2 fab = bodyRepulsion(2.1, 0.3, 1.0, a, 0.25, {1.0, 0.0}, b, 0.25);
  const Vec2 fba = bodyRepulsion(2.1, 0.3, 1.0, b, 0.25, {1.0, 0.0}, a, 0.25);
  EXPECT_NEAR(fab.x, -fba.x, 1e-12);
  EXPECT_NEAR(fab.y, -fba.y, 1e-12);
  EXPECT_LT(fab.dot(b - a), 0.0);  // pushes away
  // Magnitude A exp((ri + rj - d)/B).
  const double d = distance(a, b);
  EXPECT_NEAR(fab.norm(), 2.1 * std::exp((0.5 - d) / 0.3), 1e-12);
  // Monotone decreasing in distance.
  double prev = 1e300;
  for (double x = 0.3; x < 4.0; x += 0.1) {
    const double m = bodyRepulsion(2.1, 0.3, 1.0, a, 0.25, {}, {x, 0.0}, 0.25).norm();
    EXPECT_LT(m, prev);
    prev = m;
  }
}

TEST(SocialForce, AnisotropyWeighsWhatIsAheadMore) {
  const Vec2 heading{1.0, 0.0};
  const double ahead = bodyRepulsion(2.1, 0.3, 0.35, {0, 0}, 0.25, heading, {1.0, 0.0}, 0.25).norm();
  const double behind = bodyRepulsion(2.1, 0.3, 0.35, {0, 0}, 0.25, heading, {-1.0, 0.0}, 0.25).norm();
  EXPECT_NEAR(behind / ahead, 0.35, 1e-12);
  const Vec2 w = wallRepulsion(5.0, 0.2, 0.25, 0.5, {0.0, 1.0});
  EXPECT_NEAR(w.y, 5.0 * std::exp(-0.25 / 0.2), 1e-12);
}

TEST(SpatialHash, FindsEveryPointWithinRadiusLikeBruteForce) {
  std::mt19937_64 g(3);
  std::uniform_real_distribution<double> u(-5.0, 25.0);  // some outside the hashed rectangle
  std::vector<Vec2> pts(500);
  for (auto& p : pts) {
    p = {u(g), u(g)};
  }
  SpatialHash h({0, 0}, {20, 20}, 2.0);
  h.build(pts);
  for (int q = 0; q < 50; ++q) {
    const Vec2 c{u(g), u(g)};
    std::vector<int> found;
    h.forEachNear(c, 3.0, [&](int i) {
      if (distance(pts[static_cast<std::size_t>(i)], c) <= 3.0) {
        found.push_back(i);
      }
    });
    std::sort(found.begin(), found.end());
    std::vector<int> brute;
    for (std::size_t i = 0; i < pts.size(); ++i) {
      if (distance(pts[i], c) <= 3.0) {
        brute.push_back(static_cast<int>(i));
      }
    }
    EXPECT_EQ(found, brute);
  }
}

TEST(FlowField, FollowingDirectionsReachesGoalAroundAWall) {
  auto j = test::room(20, 20, 1.0);
  auto& rows = j["map"]["rows"];
  for (int r = 1; r < 15; ++r) {  // wall at column 10 with a gap near the bottom rows
    std::string s = rows[static_cast<std::size_t>(r)].get<std::string>();
    s[10] = '@';
    rows[static_cast<std::size_t>(r)] = s;
  }
  const Scenario sc = test::parse(j);
  const FlowField f(sc.map, {15.5, 10.5});
  Vec2 p{4.5, 10.5};
  EXPECT_GT(f.cellsToGoal(sc.map, p), 11);  // must detour through the gap
  for (int k = 0; k < 400 && distance(p, f.goal()) > 0.2; ++k) {
    p += f.direction(sc.map, p) * 0.1;
    ASSERT_FALSE(sc.map.blocked(sc.map.cellX(p.x), sc.map.cellY(p.y))) << p.x << "," << p.y;
  }
  EXPECT_LT(distance(p, f.goal()), 0.2);
}

TEST(Humans, WalkRouteAroundShelvesNeverInsideWalls) {
  auto j = test::room(40, 20);
  auto& rows = j["map"]["rows"];
  for (int r = 1; r < 14; ++r) {
    std::string s = rows[static_cast<std::size_t>(r)].get<std::string>();
    s[20] = '@';
    s[21] = '@';
    rows[static_cast<std::size_t>(r)] = s;
  }
  // The wall between start and goal is open only below y = 3 m.
  j["humans"] = {{"list", {{{"id", "h"}, {"start", {3.0, 5.0}}, {"route", {{16.0, 5.0}}}}}},
                 {"stop_probability", 0.0}};
  const Scenario sc = test::parse(j);
  World w(sc);
  double maxSpeed = 0.0;
  bool reached = false;
  for (int k = 0; k < 400; ++k) {
    w.advance();
    const auto& h = w.humans()[0];
    EXPECT_FALSE(w.scenario().map.blocked(w.scenario().map.cellX(h.p.x), w.scenario().map.cellY(h.p.y)));
    maxSpeed = std::max(maxSpeed, h.v.norm());
    reached = reached || distance(h.p, {16.0, 5.0}) < 0.7;
  }
  EXPECT_TRUE(reached);
  EXPECT_LE(maxSpeed, 1.3 * 1.3 + 1e-9);
  EXPECT_GT(maxSpeed, 1.0);
}

TEST(Humans, CrowdKeepsApartAndAvoidsParkedRobots) {
  auto j = test::room(40, 40);
  j["robots"] = {{{"id", "r1"}, {"start", {10.0, 10.0}}}, {{"id", "r2"}, {"start", {5.0, 15.0}}}};
  j["points_of_interest"] = {{3.0, 3.0}, {17.0, 17.0}, {3.0, 17.0}, {17.0, 3.0}, {10.0, 10.5}};
  j["humans"] = {{"count", 30}, {"stop_probability", 0.0}, {"speed_sd", 0.1}};
  World w(test::parse(j));
  ASSERT_EQ(w.humans().size(), 30U);
  double minHH = 1e9;
  for (int k = 0; k < 600; ++k) {
    w.advance();
    const auto& hs = w.humans();
    for (std::size_t a = 0; a < hs.size(); ++a) {
      for (std::size_t b = a + 1; b < hs.size(); ++b) {
        minHH = std::min(minHH, distance(hs[a].p, hs[b].p) - hs[a].r - hs[b].r);
      }
    }
  }
  EXPECT_GT(minHH, -0.25);  // people may brush, never walk through each other
  // A goal next to a parked robot: repulsion keeps people off it.
  EXPECT_GT(w.metrics().minSepRobotHuman, -0.15);
  double moved = 0.0;
  for (const auto& h : w.humans()) {
    moved += h.v.norm();
  }
  EXPECT_GT(moved / 30.0, 0.3);  // the crowd is still walking, not jammed
}

TEST(Humans, PredictionIsConstantVelocityWithGrowingSigma) {
  auto j = test::room(40, 20);
  j["humans"] = {{"list", {{{"id", "h"}, {"start", {3.0, 5.0}}, {"route", {{16.0, 5.0}}}}}}};
  World w(test::parse(j));
  for (int k = 0; k < 20; ++k) {
    w.advance();
  }
  const auto d = w.predictHuman(0);
  ASSERT_EQ(d.size(), 7U);  // 3 s at 0.5 s, t = 0 included
  const auto& h = w.humans()[0];
  for (std::size_t k = 0; k < d.size(); ++k) {
    const double t = 0.5 * static_cast<double>(k);
    EXPECT_NEAR(d[k].x, h.p.x + h.v.x * t, 1e-12);
    EXPECT_NEAR(d[k].y, h.p.y + h.v.y * t, 1e-12);
    EXPECT_NEAR(d[k].sigma, 0.05 + 0.3 * t, 1e-12);
  }
}

TEST(Humans, GroupsShareGoals) {
  auto j = test::room(40, 40);
  j["points_of_interest"] = {{3.0, 3.0}, {17.0, 17.0}, {3.0, 17.0}};
  j["humans"] = {{"count", 6}, {"group_size", 3}};
  World w(test::parse(j));
  for (int k = 0; k < 100; ++k) {
    w.advance();
    const auto& hs = w.humans();
    for (const auto& h : hs) {
      EXPECT_EQ(h.field, hs[static_cast<std::size_t>(h.leader)].field);
    }
  }
}

TEST(Humans, SomeoneBlockedInAnAisleTurnsToAnotherGoal) {
  // A 1 m wide corridor with a parked robot in the middle; the person's goal is behind the robot.
  auto j = test::room(40, 20);
  auto& rows = j["map"]["rows"];
  for (int r = 1; r < 19; ++r) {
    if (r == 9 || r == 10) {
      continue;  // the corridor: rows 9-10 (y 4.5..5.5 m from the bottom of the 20-row map)
    }
    std::string s = rows[static_cast<std::size_t>(r)].get<std::string>();
    for (int c = 8; c < 32; ++c) {
      s[static_cast<std::size_t>(c)] = '@';
    }
    rows[static_cast<std::size_t>(r)] = s;
  }
  j["robots"] = {{{"id", "r1"}, {"start", {10.0, 5.0}}}};
  j["points_of_interest"] = {{17.0, 5.0}, {2.0, 2.0}, {2.0, 8.0}};
  j["humans"] = {{"list", {{{"id", "h"}, {"start", {13.0, 5.0}}, {"route", {{6.0, 5.0}, {17.0, 5.0}}}}}},
                 {"stop_probability", 0.0}};
  const Scenario sc = test::parse(j);
  World w(sc);
  double minX = 1e9;
  double maxXLater = -1e9;
  for (int k = 0; k < 300; ++k) {  // 30 s
    w.advance();
    const auto& h = w.humans()[0];
    minX = std::min(minX, h.p.x);
    if (k > 150) {
      maxXLater = std::max(maxXLater, h.p.x);
    }
  }
  EXPECT_GT(minX, 10.0) << "nobody walks through the robot";
  EXPECT_GT(maxXLater, 14.0) << "after giving up the person walks away from the robot instead of pushing";
}

TEST(Humans, NeverWalkIntoAStandingRobotUnlessTheKeepDistanceIsOff) {
  // Everyone walks to a point of interest just behind a parked robot, pushed on by the people
  // behind them: the social force alone lets them press into the robot; the keep distance does not.
  auto closest = [](double keep) {
    auto j = test::room(40, 40);
    j["robots"] = {{{"id", "r1"}, {"start", {10.0, 10.0}}}};
    j["points_of_interest"] = {{3.0, 10.0}, {10.5, 10.0}};
    j["humans"] = {{"count", 12}, {"stop_probability", 0.0}, {"speed_sd", 0.1}};
    j["social_force"] = {{"robot_keep", keep}};
    World w(test::parse(j));
    for (int k = 0; k < 900; ++k) {
      w.advance();
    }
    return std::pair{w.metrics().minSepRobotHuman, w.metrics().robotHumanContacts};
  };
  const auto [sepOn, contactsOn] = closest(0.05);
  EXPECT_EQ(contactsOn, 0U);
  EXPECT_GE(sepOn, 0.0);
  const auto [sepOff, contactsOff] = closest(-1.0);
  EXPECT_GT(contactsOff, 0U) << "the scene must press people into the robot for this test to mean anything";
  EXPECT_LT(sepOff, 0.0);
}

/// A 40 x 30 cell room (0.5 m cells) walled inside except where `open(row, column)`.
template <typename Open>
nlohmann::json carvedRoom(std::uint64_t seed, Open open) {
  auto j = test::room(40, 30);
  j["seed"] = seed;
  auto& rows = j["map"]["rows"];
  for (int r = 1; r < 29; ++r) {
    std::string s = rows[static_cast<std::size_t>(r)].get<std::string>();
    for (int c = 1; c < 39; ++c) {
      if (!open(r, c)) {
        s[static_cast<std::size_t>(c)] = '@';
      }
    }
    rows[static_cast<std::size_t>(r)] = s;
  }
  return j;
}

/// Over `steps` steps, the longest time in one go that the first person spends within `within` m
/// of any of `robots`.
double longestStayNear(World& w, int steps, const std::vector<Vec2>& robots, double within) {
  double stretch = 0.0;
  double since = -1.0;
  for (int k = 0; k < steps; ++k) {
    w.advance();
    const Vec2 p = w.humans()[0].p;
    const bool near =
        std::any_of(robots.begin(), robots.end(), [&](Vec2 r) { return distance(p, r) < within; });
    if (!near) {
      since = -1.0;
    } else if (since < 0.0) {
      since = w.time();
    } else {
      stretch = std::max(stretch, w.time() - since);
    }
  }
  return stretch;
}

TEST(Humans, SomeoneBetweenTwoStandingRobotsStepsOutOfTheGap) {
  // A 2.5 m corridor (y 9..11.5) along a shelf; two robots stand by the shelf facing each other 2 m
  // apart (vehicles whose protective fields a person stopped), the person between them. Every goal
  // lies along the corridor, so every way leads into one robot or the other and no goal turns away
  // from both: in a mixed-fleet run such a person stood there for 400 s, and both vehicles with
  // them. They must step out of the gap (the corridor is free beside it).
  auto trapped = [](std::uint64_t seed) {
    auto j = carvedRoom(seed, [](int r, int) { return r >= 7 && r <= 11; });
    j["robots"] = {{{"id", "r1"}, {"start", {8.8, 9.75, 0.0}}},
                   {{"id", "r2"}, {"start", {10.8, 9.75, 3.1416}}}};
    j["points_of_interest"] = {{1.5, 9.5}, {18.5, 9.5}, {4.0, 9.5}, {16.0, 9.5}};
    j["humans"] = {{"list", {{{"id", "h"}, {"start", {9.8, 9.3}}}}}, {"stop_probability", 0.0}};
    World w(test::parse(j));
    return longestStayNear(w, 900, {{8.8, 9.75}, {10.8, 9.75}}, 1.0);  // 90 s
  };
  double worst = 0.0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    worst = std::max(worst, trapped(seed));
  }
  // Drawing goals, they went to and fro between the two: up to 40 s at a time within 1 m of one (90 s
  // within 1.2 m); stepping out of the gap, 6-8 s.
  EXPECT_LT(worst, 12.0) << "someone stood within 1 m of the robots for that many seconds at a time";
}

TEST(Humans, SomeoneWhoseWayIsThroughAStandingRobotTurnsAwayInsteadOfPacingBesideIt) {
  // A 1.5 m cross corridor (y 10..11.5) crossed by a 1.5 m aisle (x 9..10.5); a robot stands in the
  // aisle's mouth south of the corridor, facing it. Most goals lie south, beyond the robot: someone
  // who comes down the aisle from the north cannot pass it. Drawing another goal at random, they
  // mostly draw another one beyond the robot and pace in front of it (what held robots for minutes
  // in the dense fleet check); they must turn to a way that leads away.
  auto nearTime = [](std::uint64_t seed) {
    auto j = carvedRoom(seed, [](int r, int c) {
      const bool corridor = r >= 7 && r <= 9;
      const bool aisle = c >= 18 && c <= 20;
      const bool south = r >= 25;
      return corridor || aisle || south;
    });
    j["robots"] = {{{"id", "r1"}, {"start", {9.75, 9.75, 1.5708}}}};
    j["points_of_interest"] = {{2.0, 1.0},  {5.0, 1.0},  {8.0, 1.0},   {11.0, 1.0},
                               {14.0, 1.0}, {17.0, 1.0}, {2.0, 10.75}, {18.0, 10.75}};
    j["humans"] = {{"list", {{{"id", "h"}, {"start", {9.75, 14.0}}}}}, {"stop_probability", 0.0}};
    World w(test::parse(j));
    return longestStayNear(w, 900, {{9.75, 9.75}}, 1.2);  // 90 s
  };
  double worst = 0.0;
  int cameNear = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const double t = nearTime(seed);
    worst = std::max(worst, t);
    cameNear += t > 3.0 ? 1 : 0;
  }
  EXPECT_GE(cameNear, 5) << "people must come down to the robot for this test to mean anything";
  EXPECT_LT(worst, 15.0) << "someone stood within 1.2 m of the robot for that many seconds at a time";
}

TEST(Humans, SomeoneWedgedBetweenAShelfCornerAndARobotGetsOut) {
  // A shelf row across the room (y 5..6) with a 1.5 m gap (x 6.5..8); a robot stands at the gap's
  // mouth, the person at the gap's west corner at the robot's keep distance, every goal south
  // through the gap. Their step, and both slides along the axes, each bring them nearer to the
  // corner or to the robot: in a CI run such a person stood frozen 1,400 s and the robot with them.
  auto moved = [](std::uint64_t seed) {
    auto j = carvedRoom(seed, [](int r, int c) {
      const bool shelf = (r == 18 || r == 19) && !(c >= 13 && c <= 15);
      return !shelf;
    });
    j["robots"] = {{{"id", "r1"}, {"start", {7.17, 6.51, -1.5}}}};
    j["points_of_interest"] = {{3.0, 2.0}, {10.0, 2.0}, {16.0, 2.0}, {7.0, 1.0}};
    j["humans"] = {{"list", {{{"id", "h"}, {"start", {6.67, 6.19}}}}}, {"stop_probability", 0.0}};
    World w(test::parse(j));
    const Vec2 start = w.humans()[0].p;
    double farthest = 0.0;
    for (int k = 0; k < 300; ++k) {  // 30 s
      w.advance();
      farthest = std::max(farthest, distance(w.humans()[0].p, start));
    }
    EXPECT_EQ(w.metrics().robotHumanContacts, 0U);
    return farthest;
  };
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    EXPECT_GT(moved(seed), 0.5) << "seed " << seed << ": the person stayed wedged where they stood";
  }
}

TEST(Humans, SomeoneBesideAStandingRobotWithTooNarrowAGapToAShelfTurnsAway) {
  // As in the dense fleet check (seed 8; shifted by -8 m in x here): a robot stands 0.54 m below a
  // shelf face (its disc to the face), less than a person needs (0.5 m across and the 0.05 m keep
  // distance), the person beside it 0.6 m off, their way west through that gap. The way runs 69°
  // off the robot's bearing, outside the 60° that counted as "into the robot", so the person kept
  // choosing goals beyond it and stood there for minutes, the robot held by them.
  auto nearTime = [](std::uint64_t seed) {
    auto j = carvedRoom(seed, [](int r, int c) { return !((r == 19 || r == 20) && c >= 15 && c <= 18); });
    j["robots"] = {{{"id", "r1"}, {"start", {7.684, 3.661, 2.26}}}};
    j["points_of_interest"] = {{1.0, 4.2}, {2.0, 4.3}, {3.0, 4.2}, {1.5, 4.0}, {16.0, 4.0}, {17.0, 2.0}};
    j["humans"] = {{"list", {{{"id", "h"}, {"start", {7.9, 4.22}}}}}, {"stop_probability", 0.0}};
    World w(test::parse(j));
    return longestStayNear(w, 900, {{7.684, 3.661}}, 1.0);  // 90 s
  };
  double worst = 0.0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    worst = std::max(worst, nearTime(seed));
  }
  EXPECT_LT(worst, 15.0) << "someone stood within 1 m of the robot for that many seconds at a time";
}
