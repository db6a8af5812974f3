#pragma once

#include <vector>

#include "fleet/scenario/grid_map.hpp"

namespace fleet::sim {

/// Breadth-first distance (in cells, 4-connected) from every free cell to a goal cell, and the
/// walking direction it implies: towards the 8-neighbour closest to the goal, never cutting a corner.
/// Humans follow it between points of interest so they walk around shelves.
class FlowField {
 public:
  FlowField(const GridMap& map, Vec2 goal);
  /// Unit direction to walk from p; straight at the goal inside its cell, zero where unreachable.
  [[nodiscard]] Vec2 direction(const GridMap& map, Vec2 p) const;
  /// Cells to the goal (-1 unreachable or blocked).
  [[nodiscard]] int cellsToGoal(const GridMap& map, Vec2 p) const;
  [[nodiscard]] Vec2 goal() const { return goal_; }

 private:
  [[nodiscard]] int at(const GridMap& map, int cx, int cy) const;
  Vec2 goal_;
  std::vector<int> dist_;
};

}  // namespace fleet::sim
