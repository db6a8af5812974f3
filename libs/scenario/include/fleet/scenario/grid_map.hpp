#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "fleet/core/vec2.hpp"
#include "fleet/geometry/grid_raycast.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::sim {

/// The simulator's static world: an occupancy grid in the map frame (row 0 at the bottom, cell (cx, cy)
/// covers [origin + (cx, cy) * res, origin + (cx + 1, cy + 1) * res), non-zero = shelf or wall).
struct GridMap {
  int width = 0;
  int height = 0;
  double resolution = 1.0;
  Vec2 origin;
  std::vector<std::uint8_t> cells;

  [[nodiscard]] geometry::GridView view() const { return {width, height, resolution, origin, cells}; }
  [[nodiscard]] bool inside(int cx, int cy) const { return cx >= 0 && cy >= 0 && cx < width && cy < height; }
  /// Outside the grid counts as blocked (the warehouse is closed).
  [[nodiscard]] bool blocked(int cx, int cy) const {
    return !inside(cx, cy) || cells[static_cast<std::size_t>(cy) * static_cast<std::size_t>(width) +
                                    static_cast<std::size_t>(cx)] != 0;
  }
  [[nodiscard]] int cellX(double x) const { return toCell((x - origin.x) / resolution); }
  [[nodiscard]] int cellY(double y) const { return toCell((y - origin.y) / resolution); }
  /// Far outside any map, or not a number (a scenario's coordinates are input): an index outside
  /// the map that an int holds, not an out-of-range cast (the scenario fuzzer's 1.3e34).
  [[nodiscard]] static int toCell(double c) {
    constexpr double kFar = 1e9;
    if (!(c > -kFar)) {
      return -static_cast<int>(kFar);
    }
    return c > kFar ? static_cast<int>(kFar) : static_cast<int>(std::floor(c));
  }
  [[nodiscard]] Vec2 cellCenter(int cx, int cy) const {
    return origin + Vec2{(cx + 0.5) * resolution, (cy + 0.5) * resolution};
  }
  [[nodiscard]] double widthM() const { return width * resolution; }
  [[nodiscard]] double heightM() const { return height * resolution; }
};

/// Penetration depth of a disc into the blocked cells (0 when clear): radius minus the distance from the
/// centre to the closest point of any blocked cell within reach. Exact for axis-aligned square cells.
double discGridPenetration(const GridMap& map, Vec2 centre, double radius);

/// Distance from `p` to the closest blocked cell within `reach` and the unit direction from that cell to
/// `p`; returns false when nothing is within reach.
bool nearestBlocked(const GridMap& map, Vec2 p, double reach, double& dist, Vec2& awayDir);

/// The simulator's copy of a planning grid (loaded by libs/planning: MovingAI, image + side file,
/// generated warehouse).
GridMap fromOccupancyGrid(const planning::OccupancyGrid& g);
/// A planning grid with the map's blocked cells (what a robot agent plans on).
planning::OccupancyGrid toOccupancyGrid(const GridMap& m);

}  // namespace fleet::sim
