// The roadmap built from a site: zones (no-go, one-way, speed limits), edge durations and turns,
// stations with their docks, approaches, exits and queues, and closures made at run time.

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fleet/core/bends.hpp"
#include "fleet/site/reachability.hpp"
#include "fleet/traffic/roadmap.hpp"
#include "roadmap_test_support.hpp"

namespace fleet::traffic {
namespace {

using namespace test;  // NOLINT(google-build-using-namespace): the roadmap tests' shared helpers

// ---- zones -------------------------------------------------------------------------------------

TEST(Roadmap, NoGoZoneHasNoNodesAndNoEdgesThrough) {
  const nlohmann::json zones = {
      {{"name", "spill"}, {"kind", "no_go"}, {"polygon", {{4.0, 1.0}, {6.0, 1.0}, {6.0, 3.0}, {4.0, 3.0}}}}};
  const auto s = rowsSite(hall(), twoStations(), zones);
  const Roadmap r = buildRoadmap(s);
  ASSERT_GT(r.graph.size(), 0U);
  for (NodeId v = 0; v < static_cast<NodeId>(r.graph.size()); ++v) {
    const Vec2 p = r.graph.position(v);
    // The disc stays out of the no-go cells (x 4..6, y 1..3) altogether.
    const double dx = std::max({4.0 - p.x, 0.0, p.x - 6.0});
    const double dy = std::max({1.0 - p.y, 0.0, p.y - 3.0});
    EXPECT_GE(std::hypot(dx, dy), 0.3 - 1e-9) << "node at " << p.x << ", " << p.y;
  }
  // Without the zone there are nodes there.
  const Roadmap open = buildRoadmap(rowsSite(hall(), twoStations()));
  EXPECT_LT(distance(open.graph.position(open.nearest({5.0, 2.0})), {5.0, 2.0}), 0.4);
  EXPECT_GT(distance(r.graph.position(r.nearest({5.0, 2.0})), {5.0, 2.0}), 1.0);
  EXPECT_TRUE(r.problems.empty()) << describe(r.problems);
}

TEST(Roadmap, OneWayZoneDropsEdgesAgainstItsDirection) {
  // Eastbound band along the middle of the hall; the rest stays two-way so every station is
  // still reachable both ways.
  const nlohmann::json zones = {{{"name", "east"},
                                 {"kind", "one_way"},
                                 {"polygon", {{2.5, 1.5}, {8.5, 1.5}, {8.5, 2.5}, {2.5, 2.5}}},
                                 {"direction", 0.0}}};
  const Roadmap r = buildRoadmap(rowsSite(hall(), twoStations(), zones));
  const Roadmap two = buildRoadmap(rowsSite(hall(), twoStations()));
  EXPECT_GT(r.oneWayDropped, 0U);
  EXPECT_EQ(two.oneWayDropped, 0U);
  EXPECT_LT(r.edgeCount(), two.edgeCount());
  std::size_t eastbound = 0;
  for (NodeId v = 0; v < static_cast<NodeId>(r.graph.size()); ++v) {
    for (const auto& e : r.graph.edges(v)) {
      const Vec2 a = r.graph.position(v);
      const Vec2 b = r.graph.position(e.to);
      auto inside = [](Vec2 p) { return p.x > 2.5 && p.x < 8.5 && p.y > 1.5 && p.y < 2.5; };
      if (inside(a) && inside(b)) {
        EXPECT_GE(b.x - a.x, -1e-9) << "westbound edge in the one-way zone at " << a.x << ", " << a.y;
        eastbound += b.x > a.x ? 1 : 0;
      }
    }
  }
  EXPECT_GT(eastbound, 10U);
  EXPECT_EQ(errors(r), 0U) << describe(r.problems);
}

TEST(Roadmap, OneWayDeadEndIsReported) {
  // A spur 1.5 m wide off the hall's top whose whole length is one-way northbound: robots can go
  // up it but never come back.
  auto rows = hall();
  const std::string spur = std::string(9, '@') + "..." + std::string(10, '@');  // x 4.5..6.0 m
  rows[0] = spur;                                                               // the hall's top wall, opened
  rows.insert(rows.begin(), {std::string(22, '@'), spur, spur, spur});
  const nlohmann::json zones = {{{"name", "up"},
                                 {"kind", "one_way"},
                                 {"polygon", {{4.5, 4.5}, {6.0, 4.5}, {6.0, 6.5}, {4.5, 6.5}}},
                                 {"direction", kPi / 2}}};
  const Roadmap r = buildRoadmap(rowsSite(rows, twoStations(), zones));
  bool deadEnd = false;
  for (const auto& p : r.problems) {
    if (p.severity == RoadmapProblem::Severity::Warning && p.what.find("dead end") != std::string::npos) {
      deadEnd = true;
      EXPECT_GT(p.at.y, 4.5) << p.what;
    }
  }
  EXPECT_TRUE(deadEnd) << describe(r.problems);
  EXPECT_EQ(errors(r), 0U) << describe(r.problems);
}

TEST(Roadmap, SpeedLimitZoneLengthensDurations) {
  const nlohmann::json zones = {{{"name", "slow"},
                                 {"kind", "speed_limit"},
                                 {"polygon", {{0.1, 0.1}, {10.9, 0.1}, {10.9, 4.9}, {0.1, 4.9}}},
                                 {"max_speed", 0.4}}};
  const Roadmap slow = buildRoadmap(rowsSite(hall(), twoStations(), zones));
  const Roadmap fast = buildRoadmap(rowsSite(hall(), twoStations()));
  const NodeId a = fast.nearest({5.25, 2.25});
  const NodeId b = fast.nearest({5.75, 2.25});
  ASSERT_NE(fast.graph.edge(a, b), nullptr);
  EXPECT_NEAR(fast.graph.edge(a, b)->duration, 0.5 / 0.8, 1e-9);
  const NodeId sa = slow.nearest({5.25, 2.25});
  const NodeId sb = slow.nearest({5.75, 2.25});
  ASSERT_NE(slow.graph.edge(sa, sb), nullptr);
  EXPECT_NEAR(slow.graph.edge(sa, sb)->duration, 0.5 / 0.4, 1e-6);  // the limit is stored as a float
}

// ---- durations and turning ------------------------------------------------------------------

TEST(Roadmap, DurationsAreDriveTimeAndTheTurnsANodeForces) {
  const Roadmap r = buildRoadmap(shipped("small_warehouse.site.json"));
  const auto* d1 = r.station("D-1");
  ASSERT_NE(d1, nullptr);
  ASSERT_NE(d1->approach, kNoNode);
  ASSERT_NE(d1->exit, kNoNode);
  // In along the last leg (one way), out to the exit beside the approach point after the turn on
  // the spot that the dock's only way in forces.
  EXPECT_EQ(r.graph.edge(d1->dock, d1->approach), nullptr);
  const Vec2 dock = r.graph.position(d1->dock);
  const Vec2 in = dock - r.graph.position(d1->approach);
  const Vec2 out = r.graph.position(d1->exit) - dock;
  const double turn = std::acos(std::clamp(in.dot(out) / (in.norm() * out.norm()), -1.0, 1.0));
  EXPECT_NEAR(turn, 3.0 * kPi / 4.0, 1e-6);  // the exit is a following distance beside the approach point
  EXPECT_NEAR(r.turnTime(kPi), kPi / 1.5 + 1.5 / 3.0, 1e-9);  // the site robot: 1.5 rad/s, 3 rad/s²
  ASSERT_NE(r.graph.edge(d1->dock, d1->exit), nullptr);
  EXPECT_NEAR(r.graph.edge(d1->dock, d1->exit)->duration, out.norm() / 0.8 + r.turnTime(turn), 1e-9);
  // A straight lattice step costs its length at cruise; a corner costs its turn on top, which
  // only a planner that knows the previous node can add.
  const NodeId a = r.nearest({10.25, 4.25});
  const NodeId b = r.nearest({10.75, 4.25});
  ASSERT_NE(r.graph.edge(a, b), nullptr);
  EXPECT_NEAR(r.graph.edge(a, b)->duration, 0.625, 1e-9);
  EXPECT_NEAR(r.extraTurn(a, b, r.nearest({11.25, 4.25})), 0.0, 1e-9);  // straight on
  const NodeId west = r.nearest({5.25, 17.75});
  const NodeId mid = r.nearest({5.75, 17.75});
  const NodeId north = r.nearest({5.75, 18.25});
  ASSERT_NE(r.graph.edge(mid, north), nullptr);
  EXPECT_NEAR(r.extraTurn(west, mid, north), r.turnTime(kPi / 2), 1e-9);
  EXPECT_NEAR(r.turnTime(0.5), 2.0 * std::sqrt(0.5 / 3.0), 1e-9);  // too short to reach 1.5 rad/s
}

/// Turns are timed as the agent takes them (fleet/core/bends.hpp): the lattice's 45° bends driven
/// round where the disc has room, costing only what turning by the angle needs beyond driving the
/// two half edges at cruise; corners, tight bends and the legs onto docks on the spot. Checked on
/// every bend of a site: never more than the turn on the spot, exactly it for corners, and what an
/// edge's duration folds in plus extraTurn() is the bend's whole time.
struct BendCount {
  std::size_t roomy = 0;    ///< bends driven round
  std::size_t corners = 0;  ///< sharper than bends::kDrivenRound, or onto or off a dock
  /// Bends driven round in the open, turned on the spot here. None on 0.5 m maps: the lattice keeps
  /// its nodes 0.75 m from walls, so only parking places (entered and left by one leg) are tight.
  std::size_t tightCorners = 0;
};

BendCount checkEveryBend(const site::Site& site, const Roadmap& r) {
  const auto drivable = site.drivable();  // the agent's map: no-go zones blocked
  std::vector<std::vector<NodeId>> into(r.graph.size());
  for (NodeId w = 0; w < static_cast<NodeId>(r.graph.size()); ++w) {
    for (const Edge& e : r.graph.edges(w))
      into[static_cast<std::size_t>(e.to)].push_back(w);
  }
  BendCount n;
  for (NodeId v = 0; v < static_cast<NodeId>(r.graph.size()); ++v) {
    const Vec2 p = r.graph.position(v);
    const bool room = site::discFits(drivable, p, r.options.radius + bends::kTightClearance);
    const auto out = r.graph.edges(v);
    for (const NodeId w : into[static_cast<std::size_t>(v)]) {
      for (std::size_t k = 0; k < out.size(); ++k) {
        const Vec2 a = p - r.graph.position(w);
        const Vec2 b = r.graph.position(out[k].to) - p;
        const double angle = std::acos(std::clamp(a.dot(b) / (a.norm() * b.norm()), -1.0, 1.0));
        const double t = r.bendTime(w, v, k);
        // The edge's duration holds its drive and the least bend into it; extraTurn the rest.
        const double folded = out[k].duration - r.baseDuration(v, out[k].to);
        EXPECT_NEAR(folded + r.extraTurn(w, v, out[k].to), std::max(t, folded), 1e-9);
        EXPECT_LE(t, r.turnTime(angle) + 1e-6);
        if (angle < 1e-6)
          continue;
        const bool station = r.kind(v) == NodeKind::Station || r.kind(out[k].to) == NodeKind::Station;
        const bool sharp = angle > bends::kDrivenRound || station;
        if (sharp || (!room && angle > bends::kTight)) {
          EXPECT_NEAR(t, r.turnTime(angle), 1e-6) << v;
          (sharp ? n.corners : n.tightCorners) += 1;
        } else {
          const double along = 0.5 * (r.baseDuration(w, v) + r.baseDuration(v, out[k].to));
          EXPECT_NEAR(t, std::max(0.0, r.turnTime(angle) - along), 1e-6) << v;
          n.roomy += room ? 1 : 0;
        }
      }
    }
  }
  return n;
}

TEST(Roadmap, BendsAreDrivenRoundWhereTheAgentDrivesRoundAndCornersTurnedOnTheSpot) {
  const auto site = shipped("small_warehouse.site.json");
  const Roadmap r = buildRoadmap(site);
  const auto n = checkEveryBend(site, r);
  EXPECT_GT(n.roomy, 100U);
  EXPECT_GT(n.corners, 100U);
  const auto drivable = site.drivable();
  // A 45° bend between a 0.5 m axis step and a diagonal in the open: turning by π/4 takes 1.02 s
  // and the half edges 0.75 s, so the bend costs 0.27 s where the turn on the spot cost 1.02 s.
  std::size_t found = 0;
  for (NodeId mid = 0; mid < static_cast<NodeId>(r.graph.size()) && found == 0; ++mid) {
    const Vec2 p = r.graph.position(mid);
    const NodeId west = r.nearest(p - Vec2{0.5, 0.0});
    const NodeId ne = r.nearest(p + Vec2{0.5, 0.5});
    if (r.kind(mid) != NodeKind::Lane ||
        !site::discFits(drivable, p, r.options.radius + bends::kTightClearance) ||
        r.graph.edge(west, mid) == nullptr || r.graph.edge(mid, ne) == nullptr ||
        distance(r.graph.position(ne), p + Vec2{0.5, 0.5}) > 1e-6 ||
        distance(r.graph.position(west), p - Vec2{0.5, 0.0}) > 1e-6)
      continue;
    ++found;
    const double whole =
        r.graph.edge(mid, ne)->duration - r.baseDuration(mid, ne) + r.extraTurn(west, mid, ne);
    EXPECT_NEAR(whole, r.turnTime(kPi / 4) - 0.5 * (0.625 + std::sqrt(0.5) / 0.8), 1e-9);
  }
  EXPECT_EQ(found, 1U);
  EXPECT_NEAR(r.turnTime(kPi / 4), kPi / 4 / 1.5 + 0.5, 1e-9);
}

// ---- stations and queues ----------------------------------------------------------------------

// The shipped site spells its lines out (fleetctl site lines) as the roadmap generated them.
TEST(Roadmap, StationsHaveDockApproachAndQueueInOrder) {
  const Roadmap r = buildRoadmap(shipped("small_warehouse.site.json"));
  const double f = r.options.followingDistance;
  EXPECT_NEAR(f, 1.0, 1e-9);  // 2 × 0.3 + 0.3 stop gap + 0.1 margin
  std::size_t withQueue = 0;
  for (const auto& station : r.stations) {
    if (station.kind == site::StationKind::Parking) {
      continue;
    }
    ++withQueue;
    const auto* st = &station;
    const char* name = st->name.c_str();
    // Three places unless a wall (P-1's row ends) or another station's line (P-5's beside D-4) is
    // in the way.
    EXPECT_EQ(st->queue.size(), st->name == "P-1" ? 2U : st->name == "D-4" ? 1U : 3U) << name;
    EXPECT_FALSE(st->queueGenerated) << name;  // the site's own points
    const NodeId entry = st->approach != kNoNode ? st->approach : st->dock;
    NodeId next = entry;
    double lastDistance = 0.0;
    for (std::size_t k = 0; k < st->queue.size(); ++k) {
      const NodeId q = st->queue[k];
      EXPECT_EQ(r.kind(q), NodeKind::Queue);
      // Nearest first, one following distance after the other, leading to the station one way.
      const double d = distance(r.graph.position(q), r.graph.position(entry));
      EXPECT_GT(d, lastDistance) << name << " queue " << k;
      lastDistance = d;
      EXPECT_NEAR(distance(r.graph.position(q), r.graph.position(next)), f, 1e-9) << name << " queue " << k;
      EXPECT_TRUE(hasEdge(r.graph, q, next)) << name << " queue " << k;
      EXPECT_FALSE(hasEdge(r.graph, next, q)) << name << " queue " << k;
      // Robots wait in line: no queue node excludes another, or the station's dock.
      for (std::size_t j = 0; j < k; ++j) {
        EXPECT_FALSE(r.graph.conflicting(q, st->queue[j])) << name << " queue " << k << " and " << j;
      }
      EXPECT_FALSE(r.graph.conflicting(q, st->dock)) << name << " queue " << k;
      next = q;
    }
  }
  EXPECT_EQ(withQueue, 12U);  // 5 pickups, 4 drop-offs, 3 chargers
  // Parking places get no queue; pickups along a row have no approach node.
  EXPECT_TRUE(r.station("PARK-3")->queue.empty());
  EXPECT_EQ(r.station("P-1")->approach, kNoNode);
  EXPECT_EQ(r.kind(r.station("PARK-3")->dock), NodeKind::Parking);
  EXPECT_EQ(r.kind(r.station("CHG-1")->dock), NodeKind::Charger);
  EXPECT_EQ(r.kind(r.station("D-2")->dock), NodeKind::Station);
  EXPECT_EQ(r.kind(r.station("D-2")->approach), NodeKind::Approach);
  // Neighbouring parking places (1 m apart, side by side) do not exclude each other.
  EXPECT_FALSE(r.graph.conflicting(r.station("PARK-3")->dock, r.station("PARK-4")->dock));
  EXPECT_FALSE(r.graph.conflicting(r.station("PARK-3")->approach, r.station("PARK-4")->approach));
}

TEST(Roadmap, PickupsAndDropOffsAreServersWithAWayOutApartFromTheirQueue) {
  const Roadmap r = buildRoadmap(shipped("small_warehouse.site.json"));
  EXPECT_EQ(errors(r), 0U) << describe(r.problems);
  for (const auto& st : r.stations) {
    const char* name = st.name.c_str();
    if (st.kind != site::StationKind::Pickup && st.kind != site::StationKind::Dropoff) {
      EXPECT_EQ(st.exit, kNoNode) << name;  // chargers and parking places are left the way in
      continue;
    }
    ASSERT_NE(st.exit, kNoNode) << name;
    EXPECT_EQ(r.kind(st.exit), NodeKind::Exit);
    // The dock is left only by its exit, entered only from its approach point (or its row).
    const auto out = r.graph.edges(st.dock);
    ASSERT_EQ(out.size(), 1U) << name;
    EXPECT_EQ(out.front().to, st.exit) << name;
    EXPECT_FALSE(hasEdge(r.graph, st.exit, st.dock)) << name;
    if (st.approach != kNoNode) {
      EXPECT_TRUE(hasEdge(r.graph, st.approach, st.dock)) << name;
    }
    // The exit leads on to the lanes, and never into the station's own line.
    EXPECT_FALSE(r.graph.edges(st.exit).empty()) << name;
    for (const Edge& e : r.graph.edges(st.exit)) {
      EXPECT_EQ(r.kind(e.to), NodeKind::Lane) << name;
    }
    for (const NodeId q : st.queue) {
      EXPECT_GE(distance(r.graph.position(q), r.graph.position(st.exit)), r.options.followingDistance - 1e-9)
          << name;
    }
  }
  // Pickups along the top row: queue on the west side, left to the east (towards the drop-offs).
  for (const char* name : {"P-1", "P-2", "P-3", "P-4"}) {
    const auto* st = r.station(name);
    const double x = r.graph.position(st->dock).x;
    EXPECT_NEAR(r.graph.position(st->exit).x, x + 1.0, 1e-9) << name;
    for (const NodeId q : st->queue) {
      EXPECT_LT(r.graph.position(q).x, x) << name;
    }
  }
}

TEST(Roadmap, SiteExitIsUsedAsGiven) {
  nlohmann::json st = twoStations();
  st[1]["exit"] = {8.5, 1.5};
  const Roadmap r = buildRoadmap(rowsSite(hall(), st));
  EXPECT_EQ(errors(r), 0U) << describe(r.problems);
  const auto* b = r.station("B");
  ASSERT_NE(b->exit, kNoNode);
  EXPECT_NEAR(r.graph.position(b->exit).x, 8.5, 1e-9);
  EXPECT_NEAR(r.graph.position(b->exit).y, 1.5, 1e-9);
  EXPECT_EQ(connectedStations(r), (std::vector<std::string>{"A", "B"}));
}

TEST(Roadmap, SiteQueuePointsAreUsedAsGiven) {
  nlohmann::json st = twoStations();
  st[1]["queue"] = {{8.0, 3.0}, {6.8, 3.0}};
  const Roadmap r = buildRoadmap(rowsSite(hall(), st));
  const auto* b = r.station("B");
  ASSERT_EQ(b->queue.size(), 2U);
  EXPECT_FALSE(b->queueGenerated);
  EXPECT_NEAR(r.graph.position(b->queue[0]).x, 8.0, 1e-12);
  EXPECT_NEAR(r.graph.position(b->queue[1]).x, 6.8, 1e-12);
  EXPECT_TRUE(hasEdge(r.graph, b->queue[1], b->queue[0]));
  EXPECT_TRUE(r.problems.empty()) << describe(r.problems);
}

TEST(Roadmap, OneMetreCorridorOffTheLatticeLinesIsFilledIn) {
  // Two rooms joined by a corridor 1 m wide (cells y 4..5, y 2..3 m): its middle, y = 2.5, is a
  // cell edge, between the lattice rows 2.25 and 2.75 where the disc does not fit.
  auto rows = hall();
  for (std::size_t r = 1; r + 1 < rows.size(); ++r) {
    if (r != 4 && r != 5) {
      rows[r].replace(9, 4, "@@@@");
    }
  }
  const Roadmap r = buildRoadmap(rowsSite(rows, twoStations()));
  EXPECT_EQ(errors(r), 0U) << describe(r.problems);
  EXPECT_EQ(connectedStations(r), (std::vector<std::string>{"A", "B"}));
  int inCorridor = 0;
  for (NodeId v = 0; v < static_cast<NodeId>(r.graph.size()); ++v) {
    const Vec2 p = r.graph.position(v);
    if (p.x > 4.5 && p.x < 6.5) {
      EXPECT_NEAR(p.y, 2.5, 1e-9);
      inCorridor += r.kind(v) == NodeKind::Lane ? 1 : 0;  // (A's generated queue runs in there too)
    }
  }
  EXPECT_EQ(inCorridor, 4);  // x = 4.75 … 6.25
}

TEST(Roadmap, AQueueInTheOnlyCorridorBetweenTwoRoomsIsRefusedByItsKeyPath) {
  // Two rooms joined by a corridor 1 m wide (x 4.5..6.5 m, y 2..3 m): A in the west room, B and C
  // in the east one, their lines generated inside their rooms.
  auto rows = hall();
  for (std::size_t r = 1; r + 1 < rows.size(); ++r) {
    if (r != 4 && r != 5) {
      rows[r].replace(9, 4, "@@@@");
    }
  }
  // C has no room for a way out of its own: left by its way in, on purpose.
  nlohmann::json st = {
      {{"name", "A"}, {"kind", "pickup"}, {"pose", {1.5, 4.0, kPi / 2}}},
      {{"name", "B"}, {"kind", "dropoff"}, {"pose", {9.5, 4.0, kPi / 2}}},
      {{"name", "C"}, {"kind", "dropoff"}, {"pose", {7.5, 4.0, kPi / 2}}, {"exit", "entry"}}};
  const Roadmap fine = buildRoadmap(rowsSite(rows, st));
  EXPECT_EQ(errors(fine), 0U) << describe(fine.problems);
  // C docked from the west at the corridor's mouth, its queue points in the corridor: robots waiting
  // in its full line cut the west room (A) off from B.
  st[2]["pose"] = {7.5, 2.5, 0.0};
  st[2]["queue"] = {{6.0, 2.5}, {5.0, 2.5}};
  const Roadmap r = buildRoadmap(rowsSite(rows, st));
  ASSERT_EQ(errors(r), 1U) << describe(r.problems);
  const auto& p = r.problems.front();
  EXPECT_EQ(p.station, "C");
  EXPECT_EQ(p.what.rfind("stations[2].queue: ", 0), 0U) << p.what;
  EXPECT_NE(p.what.find("cut off 1 station: 'B'"), std::string::npos) << p.what;
  // With the line empty the three are connected: the line, not the layout, cuts the site.
  EXPECT_EQ(connectedStations(r), (std::vector<std::string>{"A", "B", "C"}));
}

TEST(Roadmap, QueuePointsTooCloseToTheStationAreAWarning) {
  nlohmann::json st = twoStations();
  st[1]["queue"] = {{9.0, 2.8}};  // 0.58 m from the dock
  const Roadmap r = buildRoadmap(rowsSite(hall(), st));
  ASSERT_EQ(r.problems.size(), 1U) << describe(r.problems);
  EXPECT_EQ(r.problems.front().severity, RoadmapProblem::Severity::Warning);
  EXPECT_NE(r.problems.front().what.find("too close to the dock"), std::string::npos)
      << r.problems.front().what;
  EXPECT_EQ(r.problems.front().what.rfind("stations[1].queue: ", 0), 0U) << r.problems.front().what;
}

// A dead end one robot wide: no room beside the approach point for a way out apart from the way
// in. Refused by its key path unless the site says it is left by its way in ("exit": "entry"); then
// it serves that way.
TEST(Roadmap, AStationWithNoRoomForAWayOutIsRefusedUnlessTheSiteLeavesItByItsEntry) {
  auto rows = hall();
  for (const std::size_t y : {1, 2, 3, 6, 7, 8}) {
    for (std::size_t c = 14; c <= 20; ++c) {
      rows[y][c] = '@';
    }
  }
  const Roadmap r = buildRoadmap(rowsSite(rows, twoStations()));
  ASSERT_EQ(errors(r), 1U) << describe(r.problems);
  const auto& p = *std::find_if(r.problems.begin(), r.problems.end(), [](const RoadmapProblem& q) {
    return q.severity == RoadmapProblem::Severity::Error;
  });
  EXPECT_EQ(p.station, "B");
  EXPECT_EQ(p.what.rfind("stations[1].exit: station 'B': no room for a way out", 0), 0U) << p.what;
  EXPECT_NE(p.what.find("\"exit\": \"entry\""), std::string::npos) << p.what;
  // A has room: nothing said of it.
  EXPECT_NE(r.station("A")->exit, kNoNode);

  auto st = twoStations();
  st[1]["exit"] = "entry";
  const Roadmap byEntry = buildRoadmap(rowsSite(rows, st));
  EXPECT_EQ(errors(byEntry), 0U) << describe(byEntry.problems);
  const auto* b = byEntry.station("B");
  ASSERT_NE(b->dock, kNoNode);
  EXPECT_EQ(b->exit, kNoNode);
  EXPECT_EQ(connectedStations(byEntry), (std::vector<std::string>{"A", "B"}));
  EXPECT_NE(byEntry.station("A")->exit, kNoNode);
}

TEST(Roadmap, StationThatCannotBeConnectedIsAClearProblem) {
  // B stands in a closed room (walls all round) at the hall's east end.
  auto rows = hall();
  for (std::size_t y = 1; y + 1 < rows.size(); ++y) {
    rows[y][16] = '@';
  }
  const Roadmap r = buildRoadmap(rowsSite(rows, twoStations()));
  ASSERT_EQ(errors(r), 1U) << describe(r.problems);
  const auto& p = r.problems.front();
  EXPECT_EQ(p.station, "B");
  EXPECT_NE(p.what.find("station 'B'"), std::string::npos) << p.what;
  EXPECT_NE(p.what.find("cut off"), std::string::npos) << p.what;
  EXPECT_NE(p.what.find("9.5"), std::string::npos) << p.what;
  EXPECT_EQ(connectedStations(r), std::vector<std::string>{"A"});

  // And one the robot's disc does not fit at: named, with its position.
  nlohmann::json st = twoStations();
  st.push_back({{"name", "C"}, {"kind", "pickup"}, {"pose", {0.75, 2.5, 0.0}}});
  const Roadmap r2 = buildRoadmap(rowsSite(hall(), st));
  ASSERT_EQ(errors(r2), 1U) << describe(r2.problems);
  EXPECT_NE(r2.problems.front().what.find("station 'C' at (0.75, 2.5)"), std::string::npos)
      << r2.problems.front().what;
  EXPECT_EQ(r2.problems.front().what.rfind("stations[2].pose: ", 0), 0U) << r2.problems.front().what;
  EXPECT_EQ(r2.station("C")->dock, kNoNode);
}

TEST(Roadmap, NearestNode) {
  const Roadmap r = buildRoadmap(shipped("small_warehouse.site.json"));
  const auto* d1 = r.station("D-1");
  EXPECT_EQ(r.nearest(r.graph.position(d1->dock) + Vec2{0.01, 0.0}), d1->dock);
  // Against brute force at random points, including off the map.
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(-3.0, 33.0);
  std::uniform_real_distribution<double> y(-3.0, 23.0);
  for (int i = 0; i < 300; ++i) {
    const Vec2 p{x(rng), y(rng)};
    double best = 1e9;
    for (NodeId v = 0; v < static_cast<NodeId>(r.graph.size()); ++v) {
      best = std::min(best, distance(p, r.graph.position(v)));
    }
    EXPECT_NEAR(distance(p, r.graph.position(r.nearest(p))), best, 1e-12);
  }
}

// ---- closures -----------------------------------------------------------------------------------

TEST(Roadmap, ClosureThatCutsOffAStationIsReportedAndReopenRestores) {
  Roadmap r = buildRoadmap(shipped("small_warehouse.site.json"));
  const std::size_t all = connectedStations(r).size();
  const auto* d1 = r.station("D-1");
  const Vec2 ap = r.graph.position(d1->approach);
  // A spill across the drop-off's approach leg.
  const std::vector<Vec2> spill{ap + Vec2{-0.2, -0.2}, ap + Vec2{0.2, -0.2}, ap + Vec2{0.2, 0.2},
                                ap + Vec2{-0.2, 0.2}};
  const Closure c = r.closeArea(spill);
  EXPECT_FALSE(r.graph.isOpen(d1->approach));
  EXPECT_EQ(c.cutOff, std::vector<std::string>{"D-1"});
  const auto problems = checkRoadmap(r);
  ASSERT_EQ(problems.size(), 1U) << describe(problems);
  EXPECT_EQ(problems.front().station, "D-1");
  EXPECT_EQ(connectedStations(r).size(), all - 1);

  // A second closure over the same place: reopening the first keeps it closed.
  const Closure c2 = r.closeNodes({d1->approach});
  EXPECT_TRUE(c2.cutOff.empty());
  r.reopen(c);
  EXPECT_FALSE(r.graph.isOpen(d1->approach));
  r.reopen(c2);
  EXPECT_TRUE(r.graph.isOpen(d1->approach));
  EXPECT_TRUE(checkRoadmap(r).empty()) << describe(checkRoadmap(r));
  EXPECT_EQ(connectedStations(r).size(), all);
}

TEST(Roadmap, ClosingALaneOneWayMakesADeadEndThatReopenUndoes) {
  // Close the dock's way out only: the station can be reached but not left.
  Roadmap r = buildRoadmap(shipped("small_warehouse.site.json"));
  const auto* d2 = r.station("D-2");
  const Closure c = r.closeEdges({{d2->dock, d2->exit}});
  EXPECT_EQ(c.cutOff, std::vector<std::string>{"D-2"});
  const auto problems = checkRoadmap(r);
  ASSERT_EQ(problems.size(), 1U) << describe(problems);
  EXPECT_NE(problems.front().what.find("cannot get back"), std::string::npos) << problems.front().what;
  r.reopen(c);
  EXPECT_TRUE(checkRoadmap(r).empty());
}

TEST(Roadmap, ClosedAreaKeepsTheRobotsDiscOut) {
  Roadmap r = buildRoadmap(shipped("small_warehouse.site.json"));
  const std::vector<Vec2> area{{26.0, 8.0}, {27.0, 8.0}, {27.0, 9.0}, {26.0, 9.0}};
  const Closure c = r.closeArea(area);
  EXPECT_FALSE(c.nodes.empty());
  for (NodeId v = 0; v < static_cast<NodeId>(r.graph.size()); ++v) {
    const Vec2 p = r.graph.position(v);
    const double dx = std::max({26.0 - p.x, 0.0, p.x - 27.0});
    const double dy = std::max({8.0 - p.y, 0.0, p.y - 9.0});
    EXPECT_EQ(r.graph.isOpen(v), std::hypot(dx, dy) >= r.options.radius) << p.x << ", " << p.y;
  }
  EXPECT_TRUE(c.cutOff.empty());
}

}  // namespace
}  // namespace fleet::traffic
