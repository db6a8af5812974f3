// The site library: loading site.json (every shipped site, a corpus of bad files shared with the
// JSON Schema check), derived approach points and zone layers, and where a disc robot can go.

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include <unistd.h>

#include "fleet/core/config.hpp"
#include "fleet/site/reachability.hpp"
#include "fleet/site/site_loader.hpp"
#include "fleet/site/site_report.hpp"

namespace fleet::site {
namespace {

namespace fs = std::filesystem;
const fs::path kCorpus = fs::path(FLEET_SOURCE_DIR) / "tests/unit/site/corpus";

std::vector<std::string> problemsOf(const std::string& path) {
  try {
    (void)loadSite(path);
  } catch (const ConfigError& e) {
    return e.problems();
  }
  return {};
}

planning::OccupancyGrid gridOf(const std::vector<std::string>& rows, double res = 0.5) {
  planning::OccupancyGrid g(static_cast<int>(rows[0].size()), static_cast<int>(rows.size()), res);
  for (std::size_t r = 0; r < rows.size(); ++r) {
    for (std::size_t x = 0; x < rows[r].size(); ++x) {
      g.setBlocked({static_cast<int>(x), static_cast<int>(rows.size() - 1 - r)}, rows[r][x] == '@');
    }
  }
  return g;
}

TEST(SiteFiles, EveryShippedSiteLoadsAndEveryStationIsReachable) {
  int sites = 0;
  for (const auto& e : fs::directory_iterator(fs::path(FLEET_SOURCE_DIR) / "sim/scenarios")) {
    if (e.path().string().ends_with(".site.json")) {
      SCOPED_TRACE(e.path().string());
      const Site s = loadSite(e.path().string());
      EXPECT_GT(s.map.freeCount(), 0u);
      EXPECT_FALSE(s.stations.empty());
      const auto r = analyseSite(s);
      for (const auto& st : r.stations) {
        EXPECT_TRUE(st.reachable) << st.name;
      }
      ++sites;
    }
  }
  EXPECT_GE(sites, 6);
}

// A derived approach point keeps 0.1 m of free space beyond the disc, nearer the station if it
// must: PARK-60 of the generated 100-robot warehouse had its point 1 m out, 0.035 m beyond the
// disc from a shelf corner, and robots stood there for good.
TEST(SiteFiles, ADerivedApproachPointKeepsItsClearanceFromAShelfCorner) {
  const fs::path f =
      fs::path(::testing::TempDir()) / ("approach-" + std::to_string(::getpid()) + ".site.json");
  nlohmann::json j = {{"format", "fleet-site/1"},
                      {"name", "corner"},
                      {"map",
                       {{"rows",
                         {"@@@@@@@@@@@@", "@..........@", "@......@@@@@", "@......@@@@@", "@..........@",
                          "@..........@", "@..........@", "@..........@", "@..........@", "@@@@@@@@@@@@"}},
                        {"resolution", 0.5}}},
                      {"robot", {{"radius", 0.3}, {"wheel_base", 0.4}, {"limits", {{"v_max", 1.0}}}}},
                      {"stations",
                       {{{"name", "PARK-1"}, {"kind", "parking"}, {"pose", {3.2, 1.85, 1.5708}}},
                        {{"name", "PARK-2"}, {"kind", "parking"}, {"pose", {1.5, 1.85, 1.5708}}}}}};
  std::ofstream(f) << j.dump();
  const Site s = loadSite(f.string());
  fs::remove(f);
  ASSERT_EQ(s.stations.size(), 2u);
  // The shelf's corner (3.5, 3.0) is 0.335 m from the point 1 m out: in by 0.15 m, 0.424 m from it.
  ASSERT_TRUE(s.stations[0].approach.has_value());
  EXPECT_NEAR(s.stations[0].approach->x, 3.2, 1e-4);
  EXPECT_NEAR(s.stations[0].approach->y, 2.70, 1e-4);
  EXPECT_TRUE(discFits(s.drivable(), *s.stations[0].approach, 0.3 + kApproachClearance));
  // In the open: 1 m out as before.
  ASSERT_TRUE(s.stations[1].approach.has_value());
  EXPECT_NEAR(s.stations[1].approach->y, 2.85, 1e-4);
}

TEST(SiteFiles, TheCorpusGoodSiteLoadsWithItsParts) {
  const Site s = loadSite((kCorpus / "good.site.json").string());
  EXPECT_EQ(s.name, "corpus");
  EXPECT_EQ(s.map.width(), 12);
  EXPECT_EQ(s.map.height(), 8);
  ASSERT_EQ(s.stations.size(), 3u);
  EXPECT_EQ(s.stations[1].kind, StationKind::Dropoff);
  ASSERT_EQ(s.stations[1].queue.size(), 1u);
  EXPECT_EQ(s.stations[1].queue[0], (Vec2{5.0, 1.0}));
  // Given approach kept; derived one 1 m along the heading when the leg is free.
  ASSERT_TRUE(s.stations[2].approach.has_value());
  EXPECT_TRUE(s.stations[2].approachGiven);
  EXPECT_EQ(*s.stations[2].approach, (Vec2{1.0, 2.0}));
  // P-1 faces a shelf corner 0.25 m from its axis: no straight approach for a 0.3 m robot.
  EXPECT_FALSE(s.stations[0].approach.has_value());
  ASSERT_TRUE(s.stations[1].approach.has_value());  // D-1 faces west along the free corridor
  EXPECT_NEAR(s.stations[1].approach->x, 3.75, 1e-4);
  EXPECT_NEAR(s.stations[1].approach->y, 1.0, 1e-4);
  EXPECT_FALSE(s.stations[1].approachGiven);
  EXPECT_DOUBLE_EQ(s.robot.radius, 0.3);
  EXPECT_DOUBLE_EQ(s.robot.limits.vMax, 1.0);
  ASSERT_EQ(s.zones.size(), 3u);
  // Layers: the speed zone limits its cells, the no-go zone blocks them for planners.
  EXPECT_DOUBLE_EQ(s.speedLimitAt({4.75, 2.75}), static_cast<double>(0.3f));
  EXPECT_TRUE(std::isinf(s.speedLimitAt({1.0, 1.0})));
  const auto drivable = s.drivable();
  EXPECT_TRUE(drivable.blocked(*drivable.cellAt({3.25, 3.25})));
  EXPECT_FALSE(s.map.blocked(*s.map.cellAt({3.25, 3.25})));
  EXPECT_FLOAT_EQ(s.layers.oneWay[s.map.index(*s.map.cellAt({1.25, 2.75}))], 0.0f);
  EXPECT_TRUE(std::isnan(s.layers.oneWay[s.map.index(*s.map.cellAt({1.25, 1.25}))]));
}

// One corpus, two judges: tests/unit/site/schema_check.py holds the schema to the same list.
TEST(SiteFiles, EveryBadFileOfTheCorpusIsRefusedNamingFileAndKeyPath) {
  std::ifstream in(kCorpus / "expect.json");
  const auto expect = nlohmann::json::parse(in);
  ASSERT_GE(expect.size(), 20u);
  for (const auto& [name, e] : expect.items()) {
    SCOPED_TRACE(name);
    const std::string path = (kCorpus / (name + ".site.json")).string();
    const auto problems = problemsOf(path);
    ASSERT_FALSE(problems.empty()) << "accepted";
    const std::string want = path + ": " + e["key"].get<std::string>() + ": ";
    bool found = false;
    for (const auto& p : problems) {
      found = found || (p.rfind(want, 0) == 0 && p.find(e["what"].get<std::string>()) != std::string::npos);
    }
    EXPECT_TRUE(found) << "want '" << want << "..." << e["what"].get<std::string>() << "', got:\n"
                       << ::testing::PrintToString(problems);
  }
}

TEST(SiteFiles, EveryProblemIsReportedAtOnce) {
  auto doc = nlohmann::json::parse(std::ifstream(kCorpus / "good.site.json"));
  doc["colour"] = "blue";
  doc["stations"][0]["kind"] = "dock";
  doc["robot"]["radius"] = -1;
  try {
    (void)parseSite(doc, "inline.json", kCorpus.string());
    FAIL() << "accepted";
  } catch (const ConfigError& e) {
    EXPECT_EQ(e.problems().size(), 3u) << ::testing::PrintToString(e.problems());
  }
}

TEST(SiteFiles, ABareMapLoadsAsASiteWithoutStations) {
  const auto dir = fs::temp_directory_path() / "site_test_bare";
  fs::create_directories(dir);
  std::ofstream(dir / "m.map") << "height 2\nwidth 3\nmap\n...\n.@.\n";
  const Site s = loadSiteOrMap((dir / "m.map").string(), 0.5);
  EXPECT_EQ(s.map.width(), 3);
  EXPECT_DOUBLE_EQ(s.map.resolution(), 0.5);
  EXPECT_TRUE(s.stations.empty());
  EXPECT_EQ(s.layers.noGo.size(), s.map.size());
}

TEST(Reachability, DiscFitsMatchesDenseSamplingOfTheCells) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 6.0);
  const auto g = gridOf({"@@@@@@@@@@@@", "@.......@..@", "@.......@..@", "@..@@@@.....", "@..@@@@.@@@@",
                         "@..........@", "@..........@", "@@@@@@@@@@@@"});
  int disagreements = 0;
  for (int i = 0; i < 2000; ++i) {
    const Vec2 p{u(rng), u(rng) * 4.0 / 6.0};
    const double r = 0.1 + 0.4 * (i % 5) / 4.0;
    // Oracle: sample each blocked square densely, and the map's outside.
    bool hit = p.x - r < 0 || p.y - r < 0 || p.x + r > 6.0 || p.y + r > 4.0;
    for (int cy = 0; cy < g.height() && !hit; ++cy) {
      for (int cx = 0; cx < g.width() && !hit; ++cx) {
        if (!g.blocked({cx, cy})) {
          continue;
        }
        for (int a = 0; a <= 50 && !hit; ++a) {
          for (int b = 0; b <= 50 && !hit; ++b) {
            hit = distance(p, Vec2{(cx + a / 50.0) * 0.5, (cy + b / 50.0) * 0.5}) < r - 0.012;
          }
        }
      }
    }
    const bool fits = discFits(g, p, r);
    // The oracle's tolerance leaves a thin band where both answers are right.
    if (fits == hit) {
      bool nearEdge = false;
      for (const double rr : {r - 0.012, r + 0.012}) {
        nearEdge = nearEdge || discFits(g, p, rr) != fits;
      }
      disagreements += nearEdge ? 0 : 1;
    }
  }
  EXPECT_EQ(disagreements, 0);
}

TEST(Reachability, ARobotWiderThanAGapIsCutOffWhereCellsAreConnected) {
  const auto g = gridOf({"@@@@@@@@@@@@", "@.......@..@", "@.......@..@", "@..@@@@.....", "@..@@@@.@@@@",
                         "@..........@", "@..........@", "@@@@@@@@@@@@"});
  EXPECT_EQ(cellRegions(g).count(), 1u);
  const auto wide = discRegions(g, 0.3);
  const auto thin = discRegions(g, 0.2);
  const Vec2 pocket{5.0, 3.0};
  const Vec2 floor{1.0, 1.0};
  EXPECT_NE(regionOf(g, wide, pocket, 0.3), regionOf(g, wide, floor, 0.3));
  EXPECT_EQ(regionOf(g, thin, pocket, 0.2), regionOf(g, thin, floor, 0.2));
  EXPECT_NE(regionOf(g, thin, pocket, 0.2), 0);
}

// Cross-check: regions by flood fill over cell centres against a brute-force BFS that tests every
// step with segmentFits (dense disc sweeps), on random maps and radii.
TEST(Reachability, RegionsAgreeWithABruteForceSweepOnRandomMaps) {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 30; ++trial) {
    planning::OccupancyGrid g(14, 10, 0.5);
    std::bernoulli_distribution wall(0.25);
    for (int y = 0; y < g.height(); ++y) {
      for (int x = 0; x < g.width(); ++x) {
        g.setBlocked({x, y}, wall(rng));
      }
    }
    const double r = 0.1 + 0.05 * (trial % 5);
    const auto regions = discRegions(g, r);
    auto at = [&](int i, int j) { return regions.label[static_cast<std::size_t>(j * regions.width + i)]; };
    for (int j = 0; j < regions.height; ++j) {
      for (int i = 0; i < regions.width; ++i) {
        const Vec2 p = regions.point(i, j);
        ASSERT_EQ(at(i, j) != 0, discFits(g, p, r)) << p.x << ", " << p.y;
        for (const auto& [ni, nj] : {std::pair{i + 1, j}, std::pair{i, j + 1}}) {
          if (ni >= regions.width || nj >= regions.height || at(i, j) == 0 || at(ni, nj) == 0) {
            continue;
          }
          // Neighbouring fitting points share a region, and the sweep between them is clear.
          EXPECT_EQ(at(i, j), at(ni, nj));
          EXPECT_TRUE(segmentFits(g, p, regions.point(ni, nj), r));
        }
      }
    }
  }
}

TEST(Reachability, TheFloorIsTheRegionWithMostStationsAndOnATieTheLarger) {
  DiscRegions r;
  r.size = {0, 5, 9, 7};
  EXPECT_EQ(floorRegion(r, {1, 2}), 2);        // one station each: the larger region
  EXPECT_EQ(floorRegion(r, {1, 1, 2}), 1);     // most stations wins over size
  EXPECT_EQ(floorRegion(r, {3, 0, 3, 2}), 3);  // a walled-in station (0) counts for no region
  EXPECT_EQ(floorRegion(r, {0, 0}), 0);
}

TEST(Reachability, GrowingTheRadiusNeverGrowsTheDrivableArea) {
  const auto g = gridOf({"@@@@@@@@@@@@", "@.......@..@", "@.......@..@", "@..@@@@.....", "@..@@@@.@@@@",
                         "@..........@", "@..........@", "@@@@@@@@@@@@"});
  double previousArea = 1e300;
  for (double r = 0.05; r < 0.8; r += 0.05) {
    const auto regions = discRegions(g, r);
    double area = 0.0;
    for (std::int32_t l = 1; l <= static_cast<std::int32_t>(regions.count()); ++l) {
      area += regions.area(l);
    }
    EXPECT_LE(area, previousArea) << r;
    previousArea = area;
  }
}

TEST(SiteReport, NamesTheStationARobotCannotReach) {
  auto doc = nlohmann::json::parse(std::ifstream(kCorpus / "good.site.json"));
  doc["stations"].push_back({{"name", "P-9"}, {"kind", "pickup"}, {"pose", {5.0, 3.0, 0.0}}});
  const Site s = parseSite(doc, "inline.json", kCorpus.string(), false);
  const auto wide = analyseSite(s, 0.3);
  ASSERT_EQ(wide.stations.size(), 4u);
  EXPECT_FALSE(wide.stations[3].reachable);
  EXPECT_TRUE(wide.stations[3].fits);
  EXPECT_TRUE(wide.stations[0].reachable);
  ASSERT_EQ(wide.problems.size(), 1u);
  EXPECT_EQ(wide.problems[0].key, "stations[3].pose");
  const auto thin = analyseSite(s, 0.2);
  EXPECT_TRUE(thin.stations[3].reachable);
  EXPECT_NE(formatReport(wide).find("P-9 (pickup) at 5, 3: UNREACHABLE"), std::string::npos)
      << formatReport(wide);
  EXPECT_EQ(reportJson(wide)["stations"][3]["reachable"], false);
}

}  // namespace
}  // namespace fleet::site
