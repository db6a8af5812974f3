#include "traffic_node.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

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
  EXPECT_EQ(node.control()->planner().distances().nodeCost().size(), g.size()) << "the planner has them";

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

// Bad input: a goal the roadmap does not connect (a station walled off from the robot's part of
// the hall) is refused with a logged reason and the robot gets no route, instead of a goal the
// planner can never bring it to.
TEST(TrafficNode, AGoalTheRoadmapDoesNotConnectIsRefused) {
  std::vector<std::string> rows(10, "@" + std::string(20, '.') + "@");
  rows.front() = rows.back() = std::string(22, '@');
  for (auto& r : rows)
    r[14] = '@';  // a wall at x 7.0..7.5 m from top to bottom
  const nlohmann::json doc = {{"format", "fleet-site/1"},
                              {"name", "walled"},
                              {"map", {{"rows", rows}, {"resolution", 0.5}}},
                              {"robot", {{"radius", 0.3}}},
                              {"stations",
                               {{{"name", "A"}, {"kind", "pickup"}, {"pose", {1.5, 2.5, 0.0}}},
                                {{"name", "C"}, {"kind", "dropoff"}, {"pose", {5.5, 2.5, 0.0}}},
                                {{"name", "B"}, {"kind", "dropoff"}, {"pose", {9.5, 2.5, M_PI}}}}}};
  const auto site = site::parseSite(doc, "walled.site.json", ".", false);
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

TEST(TrafficNode, DetoursAreOnByDefaultAndCanBeTurnedOff) {
  Config none = Config::fromText("{}", "test");
  EXPECT_EQ(readSettings(none).traffic.pibt.detourAfter, 4);
  Config off = Config::fromText(R"({"detour_after": 0, "detour_penalty": 12.5})", "test");
  const Settings s = readSettings(off);
  ASSERT_TRUE(off.ok());
  EXPECT_EQ(s.traffic.pibt.detourAfter, 0);
  EXPECT_FLOAT_EQ(s.traffic.pibt.detourPenalty, 12.5F);
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
