#include "fleet/planning/segment_free.hpp"

#include <cmath>

#include "fleet/geometry/grid_raycast.hpp"

namespace fleet::planning {

bool segmentFree(const OccupancyGrid& grid, Vec2 a, Vec2 b) {
  const auto ca = grid.cellAt(a);
  if (!ca || grid.blocked(*ca)) {
    return false;
  }
  const Vec2 d = b - a;
  const double len = d.norm();
  if (len == 0.0) {
    return true;
  }
  return !geometry::raycastGrid(grid.view(), a, std::atan2(d.y, d.x), len).hit;
}

}  // namespace fleet::planning
