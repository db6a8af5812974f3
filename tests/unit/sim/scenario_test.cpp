#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "fleet/scenario/scenario.hpp"
#include "sim_fixtures.hpp"

using namespace fleet;
using namespace fleet::sim;

namespace {

bool anyContains(const std::vector<std::string>& v, const std::string& needle) {
  return std::any_of(v.begin(), v.end(),
                     [&](const std::string& s) { return s.find(needle) != std::string::npos; });
}

}  // namespace

TEST(Scenario, ShippedScenariosLoad) {
  const std::string dir = std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/";
  for (const char* f :
       {"small_warehouse.json", "large_warehouse.json", "aisle_crossing.json", "circle_swap.json"}) {
    SCOPED_TRACE(f);
    const Scenario s = loadScenario(dir + f);
    EXPECT_FALSE(s.robots.empty());
    EXPECT_GT(s.map.width, 0);
  }
  EXPECT_LE(loadScenario(dir + "small_warehouse.json").robots.size(), 20U);
  EXPECT_GE(loadScenario(dir + "large_warehouse.json").robots.size(), 200U);
  EXPECT_EQ(loadScenario(dir + "large_warehouse.json").crowd.count, 100);
}

TEST(Scenario, ReadsMapStationsRobotsAndOverrides) {
  auto j = test::room(20, 10);
  j["stations"] = {{{"name", "C1"}, {"kind", "charging"}, {"pose", {2.0, 2.0, 0.5}}}};
  j["robots"] = {{{"id", "a"}, {"start", {1.0, 1.0}}},
                 {{"id", "b"}, {"start_station", "C1"}, {"radius", 0.2}, {"limits", {{"v_max", 0.5}}}}};
  const Scenario s = test::parse(j);
  EXPECT_EQ(s.map.width, 20);
  EXPECT_EQ(s.map.height, 10);
  EXPECT_TRUE(s.map.blocked(0, 0));
  EXPECT_FALSE(s.map.blocked(1, 1));
  ASSERT_EQ(s.robots.size(), 2U);
  EXPECT_DOUBLE_EQ(s.robots[0].radius, 0.3);
  EXPECT_DOUBLE_EQ(s.robots[1].radius, 0.2);
  EXPECT_DOUBLE_EQ(s.robots[1].limits.vMax, 0.5);
  EXPECT_DOUBLE_EQ(s.robots[1].limits.omegaMax, 1.5);  // from the defaults
  EXPECT_DOUBLE_EQ(s.robots[1].start.x, 2.0);
  EXPECT_DOUBLE_EQ(s.robots[1].start.theta, 0.5);
  EXPECT_EQ(s.stations[0].kind, StationKind::Charging);
}

TEST(Scenario, RefusesBadScenarioListingEveryProblem) {
  // One room split by a full wall at column 10: the right half is unreachable from the left.
  auto j = test::room(20, 10);
  for (auto& row : j["map"]["rows"]) {
    std::string r = row.get<std::string>();
    r[10] = '@';
    row = r;
  }
  j["stations"] = {{{"name", "FAR"}, {"kind", "pickup"}, {"pose", {8.0, 2.0}}}};
  j["robots"] = {{{"id", "a"}, {"start", {1.0, 1.0}}},
                 {{"id", "inwall"}, {"start", {0.1, 2.0}}},       // inside the border wall
                 {{"id", "overlap"}, {"start", {1.2, 1.1}}},      // overlaps 'a'
                 {{"id", "lost"}, {"start_station", "NOWHERE"}},  // unknown station
                 {{"id", "island"}, {"start", {7.0, 3.0}}},       // right half: unreachable
                 {{"id", "neg"}, {"start", {3.0, 3.0}}, {"limits", {{"v_max", -1.0}}}}};  // negative speed
  j["humans"] = {{"count", 1}, {"speed_mean", -1.3}, {"colour", "red"}};
  try {
    test::parse(j);
    FAIL() << "scenario accepted";
  } catch (const ConfigError& e) {
    const auto& p = e.problems();
    for (const auto& s : p) {
      std::cerr << "  " << s << "\n";
    }
    EXPECT_TRUE(anyContains(p, "'inwall'")) << "robot inside a wall";
    EXPECT_TRUE(anyContains(p, "robot 'overlap' overlaps robot 'a'"));
    EXPECT_TRUE(anyContains(p, "unknown station 'NOWHERE'"));
    EXPECT_TRUE(anyContains(p, "robot 'island' starts in an area unreachable"));
    EXPECT_TRUE(anyContains(p, "station 'FAR' is unreachable"));
    EXPECT_TRUE(anyContains(p, "robots[5].limits.v_max"));
    EXPECT_TRUE(anyContains(p, "humans.speed_mean"));
    EXPECT_TRUE(anyContains(p, "humans.colour: unknown key"));
    EXPECT_TRUE(anyContains(p, "test.json: "));  // every message names the file
    EXPECT_GE(p.size(), 8U);
  }
}

TEST(Scenario, RefusesMalformedValues) {
  auto j = test::room(10, 10);
  j["dt"] = 0.0;
  j["map"]["resolution"] = "big";
  j["robots"] = {{{"id", "a"}, {"start", {1.0}}}};
  try {
    test::parse(j);
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_TRUE(anyContains(e.problems(), "dt"));
    EXPECT_TRUE(anyContains(e.problems(), "map.resolution"));
    EXPECT_TRUE(anyContains(e.problems(), "robots[0].start"));
  }
}

TEST(Scenario, FleetPlacementFillsFreeSpotsOnly) {
  auto j = test::room(20, 20);
  j["robot_fleet"] = {{"count", 9}, {"prefix", "f"}, {"area", {0.0, 0.0, 10.0, 10.0}}, {"spacing", 1.0}};
  const Scenario s = test::parse(j);
  ASSERT_EQ(s.robots.size(), 9U);
  for (const auto& r : s.robots) {
    EXPECT_EQ(discGridPenetration(s.map, r.start.position(), r.radius), 0.0) << r.id;
  }
  j["robot_fleet"]["count"] = 1000;
  EXPECT_THROW(test::parse(j), ConfigError);
}

TEST(Scenario, LoadsMovingAiFileRelativeToScenarioAndNamesItsErrors) {
  const auto dir = std::filesystem::temp_directory_path() / ("sim_map_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "m.map") << "type octile\nheight 3\nwidth 4\nmap\n@@@@\n@..@\n@@@@\n";
  std::ofstream(dir / "bad.map") << "type octile\nheight 3\nwidth 4\nmap\n@@@@\n@..\n@@@@\n";
  nlohmann::json j = {{"map", {{"file", "m.map"}, {"resolution", 1.0}}}, {"robots", nlohmann::json::array()}};
  const Scenario s = parseScenario(j, (dir / "s.json").string(), dir.string());
  EXPECT_EQ(s.map.width, 4);
  EXPECT_FALSE(s.map.blocked(1, 1));
  EXPECT_TRUE(s.map.blocked(0, 1));
  j["map"]["file"] = "bad.map";
  try {
    parseScenario(j, "s.json", dir.string());
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_TRUE(anyContains(e.problems(), "map.file"));
    EXPECT_TRUE(anyContains(e.problems(), "bad.map"));
  }
  std::filesystem::remove_all(dir);
}

TEST(GridMap, DiscPenetrationIsExactAgainstCellBoxes) {
  planning::OccupancyGrid g(5, 5, 1.0);
  g.setBlocked({2, 2});
  const GridMap map = fromOccupancyGrid(g);
  const GridMap* m = &map;
  // Blocked cell spans [2,3]x[2,3]. A disc at (1.5, 2.5) of radius 0.6 overlaps the left face by 0.1.
  EXPECT_NEAR(discGridPenetration(*m, {1.5, 2.5}, 0.6), 0.1, 1e-12);
  // Corner: distance from (1.5, 1.5) to (2, 2) is sqrt(0.5).
  EXPECT_NEAR(discGridPenetration(*m, {1.5, 1.5}, 0.8), 0.8 - std::sqrt(0.5), 1e-12);
  EXPECT_EQ(discGridPenetration(*m, {1.5, 1.5}, 0.7), 0.0);
  // Out of the map counts as blocked.
  EXPECT_NEAR(discGridPenetration(*m, {0.2, 0.9}, 0.3), 0.1, 1e-12);
}

// A scenario that names its site loads exactly as the same scenario with the site's parts inline
// (how every scenario looked before sites): same map, stations, landmarks and robots.
TEST(Scenario, NamingASiteIsTheSameAsCarryingItInline) {
  const std::filesystem::path dir = std::filesystem::path(FLEET_SOURCE_DIR) / "sim/scenarios";
  for (const char* f :
       {"small_warehouse.json", "one_robot.json", "large_warehouse.json", "circle_swap.json"}) {
    SCOPED_TRACE(f);
    const auto named = nlohmann::json::parse(std::ifstream(dir / f));
    const auto site = nlohmann::json::parse(std::ifstream(dir / named["site"].get<std::string>()));
    auto inlined = named;
    inlined.erase("site");
    for (const char* k : {"map", "stations", "landmarks"}) {
      if (site.contains(k)) {
        inlined[k] = site[k];
      }
    }
    // Stations carried inline give their poses only: where robots enter, wait and leave a station
    // (approach, queue, exit) is said in a site file, which the traffic manager plans on.
    for (auto& st : inlined["stations"]) {
      st.erase("approach");
      st.erase("queue");
      st.erase("exit");
    }
    for (const auto& [k, v] : site["robot"].items()) {
      if (v.is_object() && inlined["robot_defaults"].contains(k)) {
        inlined["robot_defaults"][k].update(v);
      } else {
        inlined["robot_defaults"][k] = v;
      }
    }
    const Scenario a = parseScenario(named, (dir / f).string(), dir.string());
    const Scenario b = parseScenario(inlined, (dir / f).string(), dir.string());
    EXPECT_EQ(a.map.cells, b.map.cells);
    EXPECT_EQ(a.map.width, b.map.width);
    EXPECT_DOUBLE_EQ(a.map.resolution, b.map.resolution);
    ASSERT_EQ(a.stations.size(), b.stations.size());
    for (std::size_t i = 0; i < a.stations.size(); ++i) {
      EXPECT_EQ(a.stations[i].name, b.stations[i].name);
      EXPECT_EQ(a.stations[i].kind, b.stations[i].kind);
      EXPECT_EQ(a.stations[i].pose, b.stations[i].pose);
    }
    ASSERT_EQ(a.landmarks.size(), b.landmarks.size());
    ASSERT_EQ(a.robots.size(), b.robots.size());
    for (std::size_t i = 0; i < a.robots.size(); ++i) {
      EXPECT_EQ(a.robots[i].start, b.robots[i].start);
      EXPECT_DOUBLE_EQ(a.robots[i].radius, b.robots[i].radius);
      EXPECT_DOUBLE_EQ(a.robots[i].limits.vMax, b.robots[i].limits.vMax);
      EXPECT_EQ(a.robots[i].sensors.rays, b.robots[i].sensors.rays);
      EXPECT_DOUBLE_EQ(a.robots[i].sensors.rangeSigma, b.robots[i].sensors.rangeSigma);
    }
    ASSERT_TRUE(a.site);
    EXPECT_FALSE(a.sitePath.empty());
    EXPECT_EQ(a.site->stations.size(), a.stations.size());
    ASSERT_TRUE(b.site);  // an inline scenario gets a site made of its parts
    EXPECT_EQ(b.site->map.cells(), a.site->map.cells());
  }
}

TEST(Scenario, ASiteAndInlinePartsTogetherAreRefusedAndSiteProblemsAreNamed) {
  const std::filesystem::path dir = std::filesystem::path(FLEET_SOURCE_DIR) / "sim/scenarios";
  auto j = nlohmann::json::parse(std::ifstream(dir / "one_robot.json"));
  j["stations"] = nlohmann::json::array();
  try {
    parseScenario(j, "s.json", dir.string());
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_TRUE(anyContains(e.problems(), "s.json: stations: comes from the site file"));
  }
  j.erase("stations");
  j["site"] = "no_such.site.json";
  try {
    parseScenario(j, "s.json", dir.string());
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_TRUE(anyContains(e.problems(), "s.json: site: ")) << ::testing::PrintToString(e.problems());
    EXPECT_TRUE(anyContains(e.problems(), "no_such.site.json"));
  }
}
