#include "traffic_node.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "fleet/site/site_loader.hpp"

namespace fleet::trafficmgr {
namespace {

constexpr std::int64_t kS = 1'000'000'000;

const site::Site& smallWarehouse() {
  static const site::Site s =
      site::loadSite(std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/small_warehouse.site.json");
  return s;
}

Settings settings() {
  Settings s;
  s.settleS = 2.0;
  return s;
}

msg::TrafficProgress at(const std::string& id, const Pose2& pose, const std::string& goalStation = "",
                        std::int32_t node = -1, std::uint32_t epoch = 0) {
  msg::TrafficProgress p;
  p.robot_id = id;
  p.epoch = epoch;
  p.node = node;
  p.pose = pose;
  p.has_goal = !goalStation.empty();
  p.goal_station = goalStation;
  p.follows = true;
  return p;
}

Pose2 stationPose(const std::string& name) {
  for (const auto& s : smallWarehouse().stations) {
    if (s.name == name)
      return s.pose;
  }
  return {};
}

TEST(TrafficNode, WaitsForReportsThenPlacesAndReleases) {
  TrafficNode node(smallWarehouse(), settings(), 7);
  EXPECT_FALSE(node.onProgress(at("r1", stationPose("PARK-1"), "P-1"), 0));
  EXPECT_FALSE(node.onProgress(at("r2", stationPose("PARK-2"), "D-1"), 0));
  EXPECT_TRUE(node.tick(0).empty());
  EXPECT_TRUE(node.tick(1 * kS).empty());  // still settling
  const auto rel = node.tick(2 * kS);
  ASSERT_EQ(rel.size(), 2U);
  EXPECT_EQ(node.robotsPlaced(), 2U);
  for (const auto& r : rel) {
    EXPECT_EQ(r.epoch, 7U);
    EXPECT_EQ(r.seq, 1U);
    ASSERT_GE(r.base.size(), 2U) << r.robot_id;  // something to drive at once
    const auto dock = node.roadmap().station(r.robot_id == "r1" ? "PARK-1" : "PARK-2")->dock;
    EXPECT_EQ(r.base.front().node, dock);
    EXPECT_FALSE(r.ends_at_goal);
  }
  // Nothing changed: nothing new to send.
  EXPECT_TRUE(node.tick(2 * kS + kS / 10).empty());
}

// A risk map whose cells left of x = 10 m are at the top level K (probability 1) and the rest at 0.
std::shared_ptr<const risk::RiskLookup> leftHalfRisky() {
  risk::EncodedRiskMap e;
  e.origin = {-1.0, -1.0};
  e.resolution = 1.0;
  e.width = 40;
  e.height = 30;
  e.levels = 4;
  for (std::uint32_t y = 0; y < e.height; ++y) {
    e.runs.push_back({4, 11});  // x from -1 to 10 m
    e.runs.push_back({0, e.width - 11});
  }
  auto r = risk::RiskLookup::decode(e);
  EXPECT_TRUE(r) << (r ? "" : r.error().message);
  return *r;
}

TEST(TrafficNode, TheRiskMapSetsEachNodesCostAtMostEveryPeriod) {
  Settings s = settings();
  s.riskCostS = 3.0;
  s.riskPeriodS = 2.0;
  TrafficNode node(smallWarehouse(), s, 7);
  const auto risk = leftHalfRisky();
  EXPECT_TRUE(node.onRiskMap(*risk, 1 * kS));
  const auto& g = node.roadmap().graph;
  ASSERT_EQ(node.riskCost().size(), g.size());
  std::size_t risky = 0;
  for (traffic::NodeId v = 0; v < static_cast<traffic::NodeId>(g.size()); ++v) {
    const double expected = g.position(v).x < 10.0 ? 3.0 : 0.0;
    EXPECT_NEAR(node.riskCost()[static_cast<std::size_t>(v)], expected, 1e-6) << g.position(v).x;
    risky += expected > 0.0 ? 1 : 0;
  }
  EXPECT_GT(risky, 10U);
  EXPECT_LT(risky, g.size());
  EXPECT_FALSE(node.onRiskMap(*risk, 2 * kS)) << "1 s after the last: too soon";
  EXPECT_TRUE(node.onRiskMap(*risk, 3 * kS));
  EXPECT_EQ(node.counters().riskUpdates, 2U);
  EXPECT_EQ(node.control()->nodeCost().size(), g.size()) << "the planner has them";

  s.riskCostS = 0.0;
  TrafficNode off(smallWarehouse(), s, 7);
  EXPECT_FALSE(off.onRiskMap(*risk, 1 * kS)) << "risk_cost_s 0: the map is not used";
  EXPECT_TRUE(off.riskCost().empty());
}

TEST(TrafficNode, RiskSettingsAreReadAndChecked) {
  auto cfg = Config::fromText(R"({"risk_cost_s": 2.5, "risk_period_s": 5})", "traffic.json");
  const auto s = readSettings(cfg);
  cfg.finish();
  EXPECT_DOUBLE_EQ(s.riskCostS, 2.5);
  EXPECT_DOUBLE_EQ(s.riskPeriodS, 5.0);
  auto bad = Config::fromText(R"({"risk_cost_s": -1})", "traffic.json");
  readSettings(bad);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.problems()[0].find("risk_cost_s"), std::string::npos) << bad.problems()[0];
}

// The Roadmap message says which robot disc its conflicts keep apart (a VDA 5050 bridge refuses
// vehicles that do not fit it): the site's robot, or roadmap.radius when set.
TEST(TrafficNode, TheRoadmapMessageStatesTheRobotRadiusItWasBuiltFor) {
  const TrafficNode site(smallWarehouse(), settings(), 7);
  EXPECT_DOUBLE_EQ(site.roadmapMessage(0).robot_radius, smallWarehouse().robot.radius);
  auto cfg = Config::fromText(R"({"roadmap": {"radius": 0.42}})", "traffic.json");
  auto s = readSettings(cfg);
  cfg.finish();
  ASSERT_TRUE(cfg.ok()) << cfg.problems()[0];
  const TrafficNode larger(smallWarehouse(), s, 7);
  EXPECT_DOUBLE_EQ(larger.roadmapMessage(0).robot_radius, 0.42);
  auto bad = Config::fromText(R"({"roadmap": {"radius": -1}})", "traffic.json");
  readSettings(bad);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.problems()[0].find("radius"), std::string::npos) << bad.problems()[0];
}

TEST(TrafficNode, YieldSettingsAreReadAndChecked) {
  EXPECT_DOUBLE_EQ(Settings{}.yieldAfterS, 0.0) << "off by default";
  auto cfg =
      Config::fromText(R"({"yield_after_s": 10, "yield_for_s": 15, "yield_cost_s": 30})", "traffic.json");
  const auto s = readSettings(cfg);
  cfg.finish();
  EXPECT_DOUBLE_EQ(s.yieldAfterS, 10.0);
  EXPECT_DOUBLE_EQ(s.yieldForS, 15.0);
  EXPECT_DOUBLE_EQ(s.yieldCostS, 30.0);
  auto bad = Config::fromText(R"({"yield_after_s": -2})", "traffic.json");
  readSettings(bad);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.problems()[0].find("yield_after_s"), std::string::npos) << bad.problems()[0];
}

/// A 10 m × 5 m room split by a wall at x 7.0..7.5 m, with a 2 m door in it or none; A and C on
/// the left of the wall, B on the right.
site::Site wallSite(bool door) {
  std::vector<std::string> rows(10, "@" + std::string(20, '.') + "@");
  rows.front() = rows.back() = std::string(22, '@');
  for (std::size_t r = 0; r < rows.size(); ++r) {
    if (!door || r < 3 || r > 6)
      rows[r][14] = '@';
  }
  const nlohmann::json doc = {{"format", "fleet-site/1"},
                              {"name", door ? "door" : "walled"},
                              {"map", {{"rows", rows}, {"resolution", 0.5}}},
                              {"robot", {{"radius", 0.3}}},
                              {"stations",
                               {{{"name", "A"}, {"kind", "pickup"}, {"pose", {1.5, 2.5, 0.0}}},
                                {{"name", "C"}, {"kind", "dropoff"}, {"pose", {4.5, 4.0, M_PI / 2}}},
                                {{"name", "B"}, {"kind", "dropoff"}, {"pose", {9.5, 2.5, M_PI}}}}}};
  return site::parseSite(doc, "wall.site.json", ".", false);
}

// Bad input: a goal the roadmap does not connect (a station walled off from the robot's part of
// the hall) is refused with a logged reason and the robot gets no route, instead of a goal the
// planner can never bring it to.
TEST(TrafficNode, AGoalTheRoadmapDoesNotConnectIsRefused) {
  const auto site = wallSite(false);
  TrafficNode node(site, settings(), 1);
  ASSERT_FALSE(node.roadmap().problems.empty()) << "the roadmap says B is cut off";
  const auto refused = node.onProgress(at("r1", {1.5, 2.5, 0.0}, "B"), 0);
  ASSERT_TRUE(refused);
  EXPECT_NE(refused->find("goal station \"B\" cannot be reached on the roadmap"), std::string::npos)
      << *refused;
  node.tick(0);
  const auto rel = node.tick(3 * kS);
  ASSERT_EQ(rel.size(), 1U);
  EXPECT_EQ(rel[0].base.size(), 1U) << "held where it is";
  // A goal on its side of the wall is taken.
  EXPECT_FALSE(node.onProgress(at("r1", {1.5, 2.5, 0.0}, "C", rel[0].base[0].node, 1), 3 * kS));
  bool moves = false;
  for (int i = 1; i <= 20 && !moves; ++i) {
    for (const auto& r : node.tick(3 * kS + i * kS / 10))
      moves = moves || r.base.size() > 1;
  }
  EXPECT_TRUE(moves);
}

msg::TrafficClosure closure(const std::string& id, std::vector<Vec2> area,
                            std::vector<std::int32_t> nodes = {}, std::vector<msg::NodePair> lanes = {}) {
  msg::TrafficClosure c;
  c.closure_id = id;
  c.area = std::move(area);
  c.nodes = std::move(nodes);
  c.lanes = std::move(lanes);
  c.reason = "test";
  return c;
}

/// Ticks `node` for `seconds` from `now` with robot r1 (epoch `epoch`, goal `goal`) reporting
/// every tick: it drives each release's next node at once. `last` is its latest release (kept across
/// calls); every node released to it goes into `released`.
void drive(TrafficNode& node, std::int64_t& now, double seconds, const std::string& goal, std::uint32_t epoch,
           msg::TrafficRelease& last, std::vector<std::int32_t>& released) {
  for (const auto end = now + static_cast<std::int64_t>(seconds * kS); now < end; now += kS / 10) {
    for (const auto& r : node.tick(now))
      last = r;
    for (const auto& n : last.base)
      released.push_back(n.node);
    if (last.base.size() > 1) {
      node.onProgress(at("r1", {last.base[1].x, last.base[1].y, 0}, goal, last.base[1].node, epoch), now);
    } else if (!last.base.empty()) {
      node.onProgress(at("r1", {last.base[0].x, last.base[0].y, 0}, goal, last.base[0].node, epoch), now);
    } else {
      node.onProgress(at("r1", {1.5, 2.5, 0.0}, goal), now);
    }
  }
}

TEST(TrafficNode, AClosedDoorIsNotDrivenThroughUntilItIsReopened) {
  TrafficNode node(wallSite(true), settings(), 5);
  ASSERT_TRUE(node.roadmap().problems.empty()) << node.roadmap().problems.front().what;
  const std::vector<Vec2> door = {{6.6, -1.0}, {7.9, -1.0}, {7.9, 6.0}, {6.6, 6.0}};
  const auto r = node.onClosure(closure("spill-1", door));
  ASSERT_FALSE(r.error) << *r.error;
  EXPECT_TRUE(r.changed);
  EXPECT_GT(r.nodes, 0U);
  EXPECT_EQ(r.cutOff, std::vector<std::string>{"B"}) << "the door was the only way to B";
  EXPECT_EQ(node.revision(), 1U);
  EXPECT_EQ(node.closures(), std::vector<std::string>{"spill-1"});
  const auto m = node.roadmapMessage(0);
  EXPECT_EQ(m.revision, 1U);
  EXPECT_EQ(static_cast<std::size_t>(std::count(m.open.begin(), m.open.end(), false)), r.nodes);
  std::set<std::int32_t> closed;
  for (std::size_t v = 0; v < m.open.size(); ++v) {
    if (!m.open[v])
      closed.insert(static_cast<std::int32_t>(v));
  }
  // Sent to B while the door is closed: refused (held), never released into the closed nodes.
  EXPECT_TRUE(node.onProgress(at("r1", {1.5, 2.5, 0.0}, "B"), 0));
  std::int64_t now = 0;
  std::vector<std::int32_t> released;
  msg::TrafficRelease last;
  drive(node, now, 20.0, "B", 5, last, released);
  for (const auto v : released)
    EXPECT_FALSE(closed.contains(v)) << "node " << v << " is closed";
  // Reopened: it drives through to B.
  msg::TrafficClosure reopen;
  reopen.closure_id = "spill-1";
  reopen.active = false;
  const auto o = node.onClosure(reopen);
  EXPECT_TRUE(o.changed);
  EXPECT_EQ(node.revision(), 2U);
  EXPECT_TRUE(node.closures().empty());
  const auto m2 = node.roadmapMessage(now);
  EXPECT_EQ(std::count(m2.open.begin(), m2.open.end(), false), 0);
  released.clear();
  drive(node, now, 60.0, "B", 5, last, released);
  ASSERT_FALSE(last.base.empty());
  EXPECT_EQ(last.base.back().node, node.roadmap().station("B")->dock);
  EXPECT_TRUE(last.ends_at_goal);
}

TEST(TrafficNode, ClosuresAreCheckedWholeReplacedByIdAndReopenedOnce) {
  TrafficNode node(wallSite(true), settings(), 5);
  const auto& g = node.roadmap().graph;
  const auto n = static_cast<std::int32_t>(g.size());
  // A node off the roadmap or a lane that is no edge: refused, nothing changed.
  auto bad = node.onClosure(closure("x", {}, {0, n}));
  ASSERT_TRUE(bad.error);
  EXPECT_NE(bad.error->find("node " + std::to_string(n) + " is not on the roadmap"), std::string::npos)
      << *bad.error;
  const traffic::NodeId a = node.roadmap().station("A")->dock;
  const traffic::NodeId b = node.roadmap().station("B")->dock;
  bad = node.onClosure(closure("x", {}, {}, {{a, b}}));
  ASSERT_TRUE(bad.error);
  EXPECT_NE(bad.error->find("no roadmap edge"), std::string::npos) << *bad.error;
  bad = node.onClosure(closure("x", {}));
  ASSERT_TRUE(bad.error);
  EXPECT_NE(bad.error->find("closes nothing"), std::string::npos) << *bad.error;
  EXPECT_EQ(node.revision(), 0U);
  EXPECT_TRUE(g.isOpen(0));
  // The same id again replaces the closure: the first node opens, the second closes.
  ASSERT_FALSE(node.onClosure(closure("c", {}, {a})).error);
  EXPECT_FALSE(g.isOpen(a));
  ASSERT_FALSE(node.onClosure(closure("c", {}, {b})).error);
  EXPECT_TRUE(g.isOpen(a));
  EXPECT_FALSE(g.isOpen(b));
  // A lane closed one way: the edge closes, its nodes stay open.
  const traffic::NodeId next = g.edges(a).front().to;
  const auto lane = node.onClosure(closure("lane", {}, {}, {{a, next}}));
  ASSERT_FALSE(lane.error) << *lane.error;
  EXPECT_EQ(lane.edges, 1U);
  EXPECT_FALSE(g.edges(a).front().open);
  EXPECT_TRUE(g.isOpen(a));
  EXPECT_EQ(node.closures(), (std::vector<std::string>{"c", "lane"}));
  // Reopening twice, or an id never closed, changes nothing the second time.
  msg::TrafficClosure reopen;
  reopen.closure_id = "c";
  reopen.active = false;
  EXPECT_TRUE(node.onClosure(reopen).changed);
  EXPECT_FALSE(node.onClosure(reopen).changed);
  reopen.closure_id = "never";
  EXPECT_FALSE(node.onClosure(reopen).changed);
  EXPECT_TRUE(g.isOpen(b));
  EXPECT_EQ(node.revision(), 4U);
}

/// r1 drives from PARK-1 towards P-1 following its releases until it is out on the lanes with a
/// way ahead, then reports itself blocked where it stands for 10 s (a person in front of it).
/// Returns whether it was released another way meanwhile (a base[1] other than the one towards
/// the person) and how many yields the node counted.
/// r1 sent from PARK-1 to P-1 (epoch 3) drives a second or so and stops on a node with at least two
/// more released ahead of it; `now` is then the time after its last report.
msg::TrafficRelease driveAWhile(TrafficNode& node, std::int64_t& now) {
  node.onProgress(at("r1", stationPose("PARK-1"), "P-1"), 0);
  msg::TrafficRelease last;
  now = 2 * kS;
  for (int i = 0; i < 200 && !(last.base.size() >= 3 && i >= 10); ++i, now += kS / 10) {
    for (const auto& r : node.tick(now))
      last = r;
    if (last.base.size() > 1 && !(last.base.size() >= 3 && i >= 9))
      node.onProgress(at("r1", {last.base[1].x, last.base[1].y, 0}, "P-1", last.base[1].node, 3), now);
  }
  return last;
}

std::pair<bool, std::uint64_t> blockedFor10s(double yieldAfterS) {
  auto s = settings();
  s.yieldAfterS = yieldAfterS;
  TrafficNode node(smallWarehouse(), s, 3);
  std::int64_t now = 0;
  const msg::TrafficRelease last = driveAWhile(node, now);
  EXPECT_GE(last.base.size(), 3U);
  if (last.base.size() < 3)
    return {false, 0};
  const auto here = last.base[0];
  const auto ahead = last.base[1].node;
  auto blocked = at("r1", {here.x, here.y, 0}, "P-1", here.node, 3);
  blocked.blocked = true;
  bool otherWay = false;
  for (int i = 0; i < 100; ++i, now += kS / 10) {
    node.onProgress(blocked, now);
    for (const auto& r : node.tick(now)) {
      if (r.base.size() > 1 && r.base[1].node != ahead)
        otherWay = true;
    }
  }
  return {otherWay, node.counters().yields};
}

// A robot held by a person it cannot get by (it reports itself blocked) is made to yield after
// yield_after_s: the nodes just ahead cost more for a while and it is planned instead of held, so
// it is released another way (back, or round by another aisle) rather than waiting for ever.
// Without yielding (0, the default) it is held where it is.
TEST(TrafficNode, ARobotBlockedByAPersonForLongIsReleasedAnotherWay) {
  const auto [otherWay, yields] = blockedFor10s(3.0);
  EXPECT_EQ(yields, 1U);
  EXPECT_TRUE(otherWay) << "still released only towards the person";
  const auto [otherWayOff, yieldsOff] = blockedFor10s(0.0);
  EXPECT_EQ(yieldsOff, 0U);
  EXPECT_FALSE(otherWayOff) << "held: no new way";
}

// Held by a person on its node, a robot keeps the node after its own released, so the plan
// places it there and others wait on a step it cannot make. Blocked 10 s, it gives that node back:
// released and planned only where it stands, still held (not sent another way). Unblocked, it goes
// on from there.
TEST(TrafficNode, ARobotBlockedOnItsNodeGivesBackTheNextAfterAWhileAndStaysHeld) {
  TrafficNode node(smallWarehouse(), settings(), 3);
  std::int64_t now = 0;
  msg::TrafficRelease last = driveAWhile(node, now);
  ASSERT_GE(last.base.size(), 3U);
  const auto here = last.base[0];
  auto blocked = at("r1", {here.x, here.y, 0}, "P-1", here.node, 3);
  blocked.blocked = true;
  const auto& ex = node.control()->execution();
  const std::int64_t from = now;
  for (; now < from + 9 * kS; now += kS / 10) {
    node.onProgress(blocked, now);
    for (const auto& r : node.tick(now))
      last = r;
  }
  EXPECT_NE(ex.releasedEnd(0), here.node) << "gave back before 10 s";
  EXPECT_EQ(node.counters().gaveBack, 0U);
  for (; now < from + 12 * kS; now += kS / 10) {
    node.onProgress(blocked, now);
    for (const auto& r : node.tick(now))
      last = r;
  }
  EXPECT_EQ(node.counters().gaveBack, 1U);
  EXPECT_EQ(ex.releasedEnd(0), here.node);
  EXPECT_EQ(ex.plannedEnd(0), here.node) << "planned on past where it stands";
  ASSERT_EQ(last.base.size(), 1U) << "the agent was not told";
  EXPECT_EQ(last.base[0].node, here.node);
  EXPECT_TRUE(node.control()->held(0));
  // The person leaves: it is released on again.
  blocked.blocked = false;
  for (int i = 0; i < 30 && last.base.size() < 2; ++i, now += kS / 10) {
    node.onProgress(blocked, now);
    for (const auto& r : node.tick(now))
      last = r;
  }
  EXPECT_GE(last.base.size(), 2U);
  EXPECT_EQ(node.counters().gaveBack, 1U);
}

TEST(TrafficNode, FollowingTheReleasesReachesTheGoal) {
  TrafficNode node(smallWarehouse(), settings(), 3);
  node.onProgress(at("r1", stationPose("PARK-1"), "P-1"), 0);
  const auto goal = node.roadmap().station("P-1")->dock;
  msg::TrafficRelease last;
  std::int64_t now = 2 * kS;
  for (int i = 0; i < 600 && !(last.ends_at_goal && last.base.size() == 1); ++i, now += kS / 10) {
    for (const auto& r : node.tick(now)) {
      EXPECT_GT(r.seq, last.seq);
      last = r;
    }
    if (last.base.size() > 1) {
      // The robot drives to the next released node and reports it.
      auto p = at("r1", {last.base[1].x, last.base[1].y, 0}, "P-1", last.base[1].node, 3);
      EXPECT_FALSE(node.onProgress(p, now));
    }
  }
  ASSERT_FALSE(last.base.empty());
  EXPECT_EQ(last.base.back().node, goal);
  EXPECT_TRUE(last.ends_at_goal);
}

TEST(TrafficNode, BadReportsAreRefusedWithAReasonAndChangeNothing) {
  TrafficNode node(smallWarehouse(), settings(), 5);
  node.onProgress(at("r1", stationPose("PARK-1"), "P-1"), 0);
  const auto first = node.tick(2 * kS);
  ASSERT_EQ(first.size(), 1U);
  const auto held = first[0].base.front().node;
  auto refused = [&](msg::TrafficProgress p, const std::string& what) {
    const auto problem = node.onProgress(p, 2 * kS);
    ASSERT_TRUE(problem.has_value()) << "accepted: " << what;
    EXPECT_NE(problem->find(what), std::string::npos) << *problem;
  };
  // A node it was never released (far away), in this epoch.
  const auto far = node.roadmap().station("D-4")->dock;
  refused(at("r1", stationPose("PARK-1"), "P-1", far, 5), "was not released");
  refused(at("r1", stationPose("PARK-1"), "P-1", 999999, 5), "not on the roadmap");
  refused(at("", stationPose("PARK-1"), "P-1"), "no robot id");
  refused(at("r1", {std::nan(""), 0, 0}, "P-1"), "not finite");
  refused(at("r1", stationPose("PARK-1"), "NOWHERE", held, 5), "\"NOWHERE\" is not on the site");
  auto offMap = at("r1", stationPose("PARK-1"), "", held, 5);
  offMap.has_goal = true;
  offMap.goal = {500, 500, 0};
  refused(offMap, "from the roadmap");
  EXPECT_EQ(node.control()->at(0), held);
  EXPECT_GE(node.counters().refused, 6U);
}

TEST(TrafficNode, ARobotOffTheRoadmapIsNotPlacedUntilItComesBack) {
  TrafficNode node(smallWarehouse(), settings(), 9);
  node.onProgress(at("r1", {-20, -20, 0}, "P-1"), 0);
  EXPECT_TRUE(node.tick(3 * kS).empty());
  EXPECT_EQ(node.robotsPlaced(), 0U);
  node.onProgress(at("r1", stationPose("PARK-3"), "P-1"), 3 * kS);
  EXPECT_EQ(node.tick(3 * kS + kS / 10).size(), 1U);
}

TEST(TrafficNode, ARestartedManagerPlacesRobotsWhereTheyReported) {
  TrafficNode before(smallWarehouse(), settings(), 1);
  before.onProgress(at("r1", stationPose("PARK-1"), "P-1"), 0);
  const auto rel = before.tick(2 * kS);
  ASSERT_EQ(rel.size(), 1U);
  ASSERT_GE(rel[0].base.size(), 2U);
  const auto& n = rel[0].base[1];
  // The robot reached base[1] under the old epoch; a new manager hears that report first.
  TrafficNode after(smallWarehouse(), settings(), 2);
  after.onProgress(at("r1", {n.x, n.y, 0}, "P-1", n.node, 1), 10 * kS);
  const auto again = after.tick(12 * kS);
  ASSERT_EQ(again.size(), 1U);
  EXPECT_EQ(again[0].epoch, 2U);
  EXPECT_EQ(again[0].base.front().node, n.node);
}

TEST(TrafficNode, HoldingAndSilentRobotsArePlannedAround) {
  auto s = settings();
  s.robotTimeoutS = 3.0;
  TrafficNode node(smallWarehouse(), s, 4);
  auto p = at("r1", stationPose("PARK-1"), "P-1");
  p.holding = true;
  node.onProgress(p, 0);
  node.onProgress(at("r2", stationPose("PARK-2"), "P-2"), 0);
  node.tick(2 * kS);
  ASSERT_NE(node.control(), nullptr);
  EXPECT_TRUE(node.control()->held(static_cast<std::size_t>(node.indexOf("r1"))));
  EXPECT_FALSE(node.control()->held(static_cast<std::size_t>(node.indexOf("r2"))));
  node.tick(4 * kS);  // r1 and r2 silent for 4 s
  EXPECT_TRUE(node.control()->held(static_cast<std::size_t>(node.indexOf("r2"))));
}

TEST(TrafficNode, SettingsNameWhatIsWrong) {
  Config bad = Config::fromText(
      R"({"rate_hz": -1, "lockstep": true, "detour_after": -2, "roadmap": {"spacng": 1}})", "test");
  readSettings(bad);
  ASSERT_FALSE(bad.ok());
  std::string all;
  for (const auto& p : bad.problems())
    all += p + "\n";
  EXPECT_NE(all.find("rate_hz"), std::string::npos) << all;
  EXPECT_NE(all.find("lockstep"), std::string::npos) << all;
  EXPECT_NE(all.find("spacng"), std::string::npos) << all;
  EXPECT_NE(all.find("detour_after"), std::string::npos) << all;
}

// The timed core by default; `core` names either; anything else is bad input named by its key.
TEST(TrafficNode, TheTimedCoreIsTheDefaultAndTheCoreIsChosenByName) {
  Config none = Config::fromText("{}", "test");
  EXPECT_EQ(readSettings(none).traffic.core, traffic::PlannerCore::Sipp);
  Config pibt = Config::fromText(R"({"core": "pibt"})", "test");
  EXPECT_EQ(readSettings(pibt).traffic.core, traffic::PlannerCore::Pibt);
  ASSERT_TRUE(pibt.ok());
  Config bad = Config::fromText(R"({"core": "astar"})", "test");
  readSettings(bad);
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.problems().front().find("core"), std::string::npos) << bad.problems().front();
}

TEST(TrafficNode, DetoursAreOnByDefaultAndCanBeTurnedOff) {
  Config none = Config::fromText("{}", "test");
  EXPECT_EQ(readSettings(none).traffic.pibt.detourAfter, 4);
  Config off = Config::fromText(R"({"detour_after": 0, "detour_penalty": 12.5})", "test");
  const Settings s = readSettings(off);
  ASSERT_TRUE(off.ok());
  EXPECT_EQ(s.traffic.pibt.detourAfter, 0);
  EXPECT_FLOAT_EQ(s.traffic.pibt.detourPenalty, 12.5F);
}

// A push is priced by default (1 s, PibtOptions::occupiedCost); 0 gives PIBT's plain ranking; a
// negative price is bad input named by its key.
TEST(TrafficNode, PushesArePricedByDefaultAndThePriceIsChecked) {
  Config none = Config::fromText("{}", "test");
  EXPECT_FLOAT_EQ(readSettings(none).traffic.pibt.occupiedCost, 1.0F);
  Config plain = Config::fromText(R"({"occupied_cost_s": 0})", "test");
  EXPECT_FLOAT_EQ(readSettings(plain).traffic.pibt.occupiedCost, 0.0F);
  EXPECT_TRUE(plain.ok());
  Config bad = Config::fromText(R"({"occupied_cost_s": -1})", "test");
  readSettings(bad);
  ASSERT_FALSE(bad.ok());
  bool named = false;
  for (const auto& p : bad.problems()) {
    named = named || p.find("occupied_cost_s") != std::string::npos;
  }
  EXPECT_TRUE(named);
}

TEST(TrafficNode, RobotsSentToOneStationWaitInItsLine) {
  // Both are sent to P-1: the first is planned to its dock, the second to its queue, not to the
  // dock's only way in. With the lines off (as before they were wired in) both target the dock.
  for (const bool lines : {true, false}) {
    auto s = settings();
    s.stationLines = lines;
    TrafficNode node(smallWarehouse(), s, 2);
    node.onProgress(at("r1", stationPose("PARK-1"), "P-1"), 0);
    node.onProgress(at("r2", stationPose("PARK-2"), "P-1"), 0);
    node.tick(2 * kS);
    const auto* p1 = node.roadmap().station("P-1");
    ASSERT_NE(p1, nullptr);
    ASSERT_FALSE(p1->queue.empty());
    const auto& tc = *node.control();
    const auto r1 = static_cast<std::size_t>(node.indexOf("r1"));
    const auto r2 = static_cast<std::size_t>(node.indexOf("r2"));
    EXPECT_EQ(tc.goal(r1), p1->dock);
    EXPECT_EQ(tc.goal(r2), p1->dock);
    if (lines) {
      EXPECT_EQ(tc.line(p1->dock).size(), 2U);
      const auto first = tc.line(p1->dock).front();
      const auto second = first == r1 ? r2 : r1;
      EXPECT_EQ(tc.target(first), p1->dock);
      EXPECT_NE(std::find(p1->queue.begin(), p1->queue.end(), tc.target(second)), p1->queue.end())
          << "the second in line is planned to node " << tc.target(second);
    } else {
      EXPECT_TRUE(tc.line(p1->dock).empty());
      EXPECT_EQ(tc.target(r1), p1->dock);
      EXPECT_EQ(tc.target(r2), p1->dock);
    }
  }
  Config off = Config::fromText(R"({"station_lines": false})", "test");
  EXPECT_FALSE(readSettings(off).stationLines);
  Config on = Config::fromText("{}", "test");
  EXPECT_TRUE(readSettings(on).stationLines);
}

TEST(TrafficNode, ARobotThatReachesNoNewNodeIsReportedWithWhatHoldsIt) {
  TrafficNode node(smallWarehouse(), settings(), 9);
  node.onProgress(at("r1", stationPose("PARK-1"), "P-1"), 0);
  const auto rel = node.tick(2 * kS);
  ASSERT_EQ(rel.size(), 1U);
  const auto start = rel[0].base.front().node;
  EXPECT_TRUE(node.stalled(2 * kS, 60.0).empty());
  // It keeps reporting its first node and never moves on.
  std::int64_t now = 2 * kS;
  for (; now < 70 * kS; now += kS) {
    node.onProgress(at("r1", stationPose("PARK-1"), "P-1", start, 9), now);
    node.tick(now);
  }
  const auto report = node.stalled(now, 60.0);
  ASSERT_EQ(report.size(), 1U);
  EXPECT_NE(report[0].find("\"r1\""), std::string::npos) << report[0];
  EXPECT_NE(report[0].find("at node " + std::to_string(start)), std::string::npos) << report[0];
  EXPECT_NE(report[0].find("ways out:"), std::string::npos) << report[0];
  EXPECT_TRUE(node.stalled(now, 600.0).empty());
  // Once it moves on, it is not reported any more.
  node.tick(now);
  const auto& last = node.allReleases();
  ASSERT_EQ(last.size(), 1U);
  ASSERT_GE(last[0].base.size(), 2U);
  node.onProgress(at("r1", {last[0].base[1].x, last[0].base[1].y, 0}, "P-1", last[0].base[1].node, 9), now);
  EXPECT_TRUE(node.stalled(now + kS, 60.0).empty());
}

}  // namespace
}  // namespace fleet::trafficmgr
