#pragma once

// A MovingAI grid as a traffic Graph: one node per free cell, 4-neighbour edges of duration 1, no
// conflict sets (a robot excludes its own cell only: the MAPF convention the planner benchmarks use).
// Cells are named the way MovingAI files and Kei18/pibt2 name them: x is the column, y the row
// counted from the TOP of the file. Node positions are in the project's y-up frame at 1 m per cell
// (cell centre (x + 0.5, height - 1 - y + 0.5), as planning::OccupancyGrid puts them), so geometry
// code reading the graph sees the same map the rest of the fleet does.

#include <string>
#include <string_view>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/traffic/graph.hpp"

namespace fleet::traffic {

struct GridCell {
  int x = 0;  ///< column
  int y = 0;  ///< row from the top of the file
  constexpr bool operator==(const GridCell&) const = default;
};

struct GridMap {
  std::string source;
  int width = 0;
  int height = 0;
  Graph graph;
  std::vector<NodeId> nodeAt;    ///< y * width + x -> node, kNoNode where blocked
  std::vector<GridCell> cellOf;  ///< node -> cell

  /// The node of a free cell; kNoNode outside the map or on a blocked cell.
  [[nodiscard]] NodeId node(int x, int y) const {
    if (x < 0 || y < 0 || x >= width || y >= height) {
      return kNoNode;
    }
    return nodeAt[static_cast<std::size_t>(y) * static_cast<std::size_t>(width) +
                  static_cast<std::size_t>(x)];
  }
  [[nodiscard]] GridCell cell(NodeId v) const { return cellOf[static_cast<std::size_t>(v)]; }
  [[nodiscard]] std::size_t freeCells() const { return cellOf.size(); }
};

/// MovingAI `.map` text (planning::parseMovingAiMap's rules: `.`, `G`, `S` free; `@`, `O`, `T`, `W`
/// blocked; errors name `source` and the line). Nodes are numbered row by row from the top.
Expected<GridMap> parseGridMap(std::string_view text, const std::string& source = "<text>");
Expected<GridMap> loadGridMap(const std::string& path);

/// Kei18/pibt2's pickup-and-delivery side file (`X.map.pd`): the map's rows without a header, one
/// character per cell: `p` pickup, `d` delivery, `s` both, `e` non-task endpoint (where agents start
/// and may rest), `a` all three; `.`, `@`, `T` (and the map's other letters) carry no role.
struct PickupDelivery {
  std::vector<NodeId> pickups;
  std::vector<NodeId> deliveries;
  std::vector<NodeId> endpoints;  ///< non-task endpoints, in file order
};
/// Errors name `source`, the line and the column: wrong row count or width, an unknown character,
/// a role on a blocked cell (pibt2 skips those silently; we refuse, since the file and map disagree).
Expected<PickupDelivery> parsePickupDelivery(std::string_view text, const GridMap& map,
                                             const std::string& source = "<text>");
Expected<PickupDelivery> loadPickupDelivery(const std::string& path, const GridMap& map);

/// MovingAI's warehouse family `warehouse-C-R-W-H-A` by formula: a border of `T`, C columns by R rows
/// of W x H shelf blocks (`T`) separated by A free cells, a free band of A rows above and below the
/// blocks and of 2.5 C cells left and right of them. warehouse-10-20-10-2-1 (161 x 63, 5,699 free
/// cells) and warehouse-20-40-10-2-2 come out byte for byte as published (scripts/traffic-maps checks
/// the hashes).
struct WarehouseLayout {
  int columns = 10;
  int rows = 20;
  int shelfWidth = 10;
  int shelfHeight = 2;
  int aisle = 1;
};
std::string warehouseMapText(const WarehouseLayout& layout);

}  // namespace fleet::traffic
