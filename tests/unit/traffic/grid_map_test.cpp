#include "fleet/traffic/grid_map.hpp"

#include <gtest/gtest.h>

#include <cstdint>

#include "pibt_test_support.hpp"

using namespace fleet;
using namespace fleet::traffic;
using fleet::traffic::test::gridOf;

namespace {

std::uint64_t fnv1a(const std::string& s) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (const unsigned char c : s) {
    h = (h ^ c) * 0x100000001b3ULL;
  }
  return h;
}

std::size_t countEdges(const Graph& g) {
  std::size_t n = 0;
  for (std::size_t v = 0; v < g.size(); ++v) {
    n += g.edges(static_cast<NodeId>(v)).size();
  }
  return n;
}

}  // namespace

TEST(GridMap, CellsAndNodesMapBothWaysWithRowsFromTheTop) {
  const GridMap m = gridOf({
      "..@",
      "G.T",
      "S@.",
  });
  ASSERT_EQ(m.width, 3);
  ASSERT_EQ(m.height, 3);
  EXPECT_EQ(m.freeCells(), 6U);
  // Numbered row by row from the top, like pibt2 numbers its cells.
  EXPECT_EQ(m.node(0, 0), 0);
  EXPECT_EQ(m.node(1, 0), 1);
  EXPECT_EQ(m.node(2, 0), kNoNode);
  EXPECT_EQ(m.node(0, 1), 2);
  EXPECT_EQ(m.node(2, 2), 5);
  EXPECT_EQ(m.node(-1, 0), kNoNode);
  EXPECT_EQ(m.node(3, 0), kNoNode);
  for (std::size_t v = 0; v < m.freeCells(); ++v) {
    const GridCell c = m.cell(static_cast<NodeId>(v));
    EXPECT_EQ(m.node(c.x, c.y), static_cast<NodeId>(v));
  }
  // Positions are in the project's y-up frame: row 0 of the file is the top.
  EXPECT_DOUBLE_EQ(m.graph.position(m.node(0, 0)).y, 2.5);
  EXPECT_DOUBLE_EQ(m.graph.position(m.node(0, 2)).y, 0.5);
  EXPECT_DOUBLE_EQ(m.graph.position(m.node(1, 0)).x, 1.5);
  // 4-neighbour edges both ways, unit durations, no conflict sets.
  EXPECT_NE(m.graph.edge(m.node(0, 0), m.node(1, 0)), nullptr);
  EXPECT_NE(m.graph.edge(m.node(1, 0), m.node(0, 0)), nullptr);
  EXPECT_EQ(m.graph.edge(m.node(0, 0), m.node(1, 1)), nullptr);  // no diagonals
  EXPECT_EQ(m.graph.edge(m.node(2, 2), m.node(1, 1)), nullptr);
  EXPECT_EQ(countEdges(m.graph), 10U);  // 5 undirected pairs
  EXPECT_DOUBLE_EQ(m.graph.edge(m.node(0, 0), m.node(0, 1))->duration, 1.0);
  EXPECT_FALSE(m.graph.hasConflicts());
}

TEST(GridMap, BadFilesNameTheFileAndLine) {
  auto bad = parseGridMap("type octile\nheight 2\nwidth 3\nmap\n...\n.x.\n", "shop.map");
  ASSERT_FALSE(bad.has_value());
  EXPECT_NE(bad.error().message.find("shop.map:6"), std::string::npos) << bad.error().message;
  EXPECT_NE(bad.error().message.find("'x'"), std::string::npos) << bad.error().message;

  auto narrow = parseGridMap("type octile\nheight 2\nwidth 3\nmap\n...\n..\n", "shop.map");
  ASSERT_FALSE(narrow.has_value());
  EXPECT_NE(narrow.error().message.find("shop.map:6"), std::string::npos) << narrow.error().message;

  auto missing = loadGridMap("/nonexistent/dir/x.map");
  ASSERT_FALSE(missing.has_value());
  EXPECT_NE(missing.error().message.find("/nonexistent/dir/x.map"), std::string::npos);
}

TEST(GridMap, PickupDeliveryFileGivesRolesPerCell) {
  const GridMap m = gridOf({
      "....",
      ".@@.",
      "....",
  });
  auto pd = parsePickupDelivery("pdsa\n.TT.\ne..e", m, "m.pd");
  ASSERT_TRUE(pd.has_value()) << pd.error().message;
  const auto at = [&](int x, int y) { return m.node(x, y); };
  EXPECT_EQ(pd->pickups, (std::vector<NodeId>{at(0, 0), at(2, 0), at(3, 0)}));
  EXPECT_EQ(pd->deliveries, (std::vector<NodeId>{at(1, 0), at(2, 0), at(3, 0)}));
  EXPECT_EQ(pd->endpoints, (std::vector<NodeId>{at(3, 0), at(0, 2), at(3, 2)}));
}

TEST(GridMap, BadPickupDeliveryFilesAreRefusedWithLineAndColumn) {
  const GridMap m = gridOf({
      "....",
      ".@@.",
  });
  const auto message = [&](const std::string& text) {
    auto r = parsePickupDelivery(text, m, "m.pd");
    return r.has_value() ? std::string("accepted") : r.error().message;
  };
  EXPECT_NE(message("pd..\n.ss.\n").find("m.pd:2"), std::string::npos);  // role on a shelf
  EXPECT_NE(message("pd..\n.ss.\n").find("blocked"), std::string::npos);
  EXPECT_NE(message("pd.\n.@@.\n").find("m.pd:1"), std::string::npos);  // short row
  EXPECT_NE(message("pdq.\n.@@.\n").find("unknown character 'q'"), std::string::npos);
  EXPECT_NE(message("pd..\n").find("1 rows"), std::string::npos);              // too few rows
  EXPECT_NE(message("pd..\n.@@.\n....\n").find("m.pd:3"), std::string::npos);  // too many
  EXPECT_NE(message("....\n.@@.\n").find("no pickup"), std::string::npos);
  EXPECT_EQ(message("pd..\r\n.@@.\r\n\n"), "accepted");  // CRLF and a trailing blank line are fine
  EXPECT_NE(message("pd..\n\n.@@.\n").find("empty row"), std::string::npos);
}

TEST(GridMap, WarehouseFormulaGivesThePublishedMapsByteForByte) {
  // FNV-1a of the published files (the MovingAI warehouse-10-20-10-2-1 and pibt2's copy of
  // warehouse-20-40-10-2-2); scripts/traffic-maps checks the same bytes against their sha256.
  const std::string small = warehouseMapText({10, 20, 10, 2, 1});
  EXPECT_EQ(fnv1a(small), 0xe8e6da7648aaa061ULL);
  const std::string large = warehouseMapText({20, 40, 10, 2, 2});
  EXPECT_EQ(fnv1a(large), 0x98a711ff4ce78fd2ULL);
  // No published copy of this one here: its size and free cells are what MovingAI states.
  const std::string wide = warehouseMapText({10, 20, 10, 2, 2});
  EXPECT_EQ(fnv1a(wide), 0x218eebc7292fce66ULL);  // what scripts/traffic-maps writes

  auto m = parseGridMap(small, "warehouse-10-20-10-2-1");
  ASSERT_TRUE(m.has_value());
  EXPECT_EQ(m->width, 161);
  EXPECT_EQ(m->height, 63);
  EXPECT_EQ(m->freeCells(), 5699U);
  EXPECT_EQ(m->node(26, 2), kNoNode);  // first shelf block
  EXPECT_NE(m->node(25, 2), kNoNode);
  EXPECT_NE(m->node(36, 2), kNoNode);  // the aisle between blocks
  auto w = parseGridMap(wide, "warehouse-10-20-10-2-2");
  ASSERT_TRUE(w.has_value());
  EXPECT_EQ(w->width, 170);
  EXPECT_EQ(w->height, 84);
  EXPECT_EQ(w->freeCells(), 9776U);
}
