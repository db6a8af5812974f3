#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "fleet/planning/astar.hpp"
#include "fleet/planning/map_io.hpp"
#include "fleet/planning/movingai_scen.hpp"

using namespace fleet;
using namespace fleet::planning;

namespace {

const std::string kData = std::string(FLEET_SOURCE_DIR) + "/tests/unit/planning/data/";

// ost003d (Dragon Age: Origins) and its first random scenario from the MovingAI MAPF benchmark
// (data/README.md): 1,000 start/goal pairs with their optimal octile lengths.
TEST(MovingAiScen, AStarMatchesTheBenchmarksOptimalLengths) {
  auto grid = loadMovingAiMap(kData + "ost003d.map");
  ASSERT_TRUE(grid.has_value()) << grid.error().message;
  auto scen = loadMovingAiScen(kData + "ost003d-random-1.scen", &*grid, "ost003d.map");
  ASSERT_TRUE(scen.has_value()) << scen.error().message;
  EXPECT_TRUE(scen->skipped.empty());
  ASSERT_EQ(scen->entries.size(), 1000u);
  // The benchmark prints 8 decimals; our cost is exact up to the fixed-point error (astar.cpp).
  int checked = 0;
  for (const ScenEntry& e : scen->entries) {
    const auto path = astar(*grid, e.start, e.goal, Connectivity::Eight);
    ASSERT_TRUE(path.has_value()) << "line " << e.line;
    ASSERT_NEAR(path->cost, e.optimal, 1e-6) << "line " << e.line;
    ASSERT_EQ(path->cells.front(), e.start);
    ASSERT_EQ(path->cells.back(), e.goal);
    ++checked;
  }
  EXPECT_EQ(checked, 1000);
}

TEST(MovingAiScen, RowsAreInMovingAiCoordinatesFromTheTop) {
  // In file coordinates (0, 0) is the top-left character and (2, 1) the bottom-right one.
  const auto grid = parseMovingAiMap("type octile\nheight 2\nwidth 3\nmap\n..@\n@..\n");
  ASSERT_TRUE(grid.has_value());
  const auto scen = parseMovingAiScen("version 1\n0\tm.map\t3\t2\t0\t0\t2\t1\t3\n", "s", &*grid, "m.map");
  ASSERT_TRUE(scen.has_value());
  ASSERT_EQ(scen->entries.size(), 1u);
  EXPECT_EQ(scen->entries[0].start, (Cell{0, 1}));
  EXPECT_EQ(scen->entries[0].goal, (Cell{2, 0}));
  // No corner cutting: (0,1) -> (1,1) -> (1,0) -> (2,0), 3 straight moves, as the row says.
  const auto path = astar(*grid, scen->entries[0].start, scen->entries[0].goal);
  ASSERT_TRUE(path.has_value());
  EXPECT_DOUBLE_EQ(path->cost, scen->entries[0].optimal);
}

TEST(MovingAiScen, BadRowsAreSkippedWithANamedCountedReason) {
  const auto grid = parseMovingAiMap("type octile\nheight 3\nwidth 4\nmap\n....\n.@..\n....\n");
  ASSERT_TRUE(grid.has_value());
  const std::string text =
      "version 1\r\n"
      "0\tm.map\t4\t3\t0\t0\t3\t2\t3.82842712\r\n"  // good
      "0\tother.map\t4\t3\t0\t0\t3\t2\t3.8\n"       // another map
      "0\tm.map\t4\t3\t0\t0\t4\t2\t3.8\n"           // goal x off the map
      "0\tm.map\t4\t3\t0\t-1\t3\t2\t3.8\n"          // start y off the map
      "0\tm.map\t4\t3\t1\t1\t3\t2\t2.0\n"           // start on the '@'
      "0\tm.map\t4\t3\t0\t0\t3\t2\n"                // 8 columns
      "0 m.map 4 3 0 0 3 2 3.8\n"                   // spaces, not tabs
      "0\tm.map\t4\t3\tx\t0\t3\t2\t3.8\n"           // not a number
      "0\tm.map\t4\t3\t0\t0\t3\t2\tnan\n"           // not a finite length
      "0\tm.map\t5\t3\t0\t0\t3\t2\t3.8\n"           // the map is 4 wide
      "\n"
      "1\tdir/m.map\t4\t3\t3\t0\t0\t2\t3.82842712\n";  // good: compared by file name
  const auto scen = parseMovingAiScen(text, "s.scen", &*grid, "/some/where/m.map");
  ASSERT_TRUE(scen.has_value()) << scen.error().message;
  ASSERT_EQ(scen->entries.size(), 2u);
  EXPECT_EQ(scen->entries[0].line, 2);
  EXPECT_EQ(scen->entries[1].line, 13);
  EXPECT_EQ(scen->entries[1].bucket, 1);
  const auto by = scen->skippedBy();
  EXPECT_EQ(by.at("other_map"), 1);
  EXPECT_EQ(by.at("off_map"), 2);
  EXPECT_EQ(by.at("blocked"), 1);
  EXPECT_EQ(by.at("columns"), 2);
  EXPECT_EQ(by.at("not_a_number"), 2);
  EXPECT_EQ(by.at("map_size"), 1);
  EXPECT_EQ(scen->skipped.size(), 9u);
  EXPECT_EQ(scen->skipped[0].line, 3);
  EXPECT_NE(scen->skipped[0].detail.find("other.map"), std::string::npos);
}

TEST(MovingAiScen, TheVersionLineIsRequired) {
  const auto none = parseMovingAiScen("0\tm.map\t4\t3\t0\t0\t3\t2\t3.8\n", "a.scen");
  ASSERT_FALSE(none.has_value());
  EXPECT_EQ(none.error().code, "scen_format");
  EXPECT_NE(none.error().message.find("a.scen:1"), std::string::npos);
  EXPECT_FALSE(parseMovingAiScen("version 2\n", "b.scen").has_value());
  EXPECT_FALSE(parseMovingAiScen("", "c.scen").has_value());
  EXPECT_TRUE(parseMovingAiScen("version 1.0\n", "d.scen").has_value());
  EXPECT_FALSE(loadMovingAiScen("/nonexistent/x.scen").has_value());
}

}  // namespace
