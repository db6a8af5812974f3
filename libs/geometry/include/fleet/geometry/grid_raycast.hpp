#pragma once

#include <cstdint>
#include <span>

#include "fleet/core/vec2.hpp"

namespace fleet::geometry {

/// Read-only view of an occupancy grid: row-major cells, row 0 at the bottom (y-up map frame),
/// cell (cx, cy) covers [origin + (cx, cy) * resolution, origin + (cx+1, cy+1) * resolution).
/// A cell is blocked when its value is non-zero. Cells outside the grid are treated as blocked.
struct GridView {
  int width = 0;
  int height = 0;
  double resolution = 1.0;
  Vec2 origin;
  std::span<const std::uint8_t> cells;

  [[nodiscard]] bool inside(int cx, int cy) const { return cx >= 0 && cy >= 0 && cx < width && cy < height; }
  [[nodiscard]] bool blocked(int cx, int cy) const {
    return !inside(cx, cy) || cells[static_cast<std::size_t>(cy) * static_cast<std::size_t>(width) +
                                    static_cast<std::size_t>(cx)] != 0;
  }
};

struct GridRayHit {
  bool hit = false;  ///< false: max range reached in free space
  double range = 0.0;
  int cx = -1;  ///< the blocked cell that was hit
  int cy = -1;
};

/// Amanatides-Woo DDA: walks exactly the cells the ray crosses, so the range is the distance to the
/// first blocked cell's boundary (0 if the origin cell is blocked).
GridRayHit raycastGrid(const GridView& grid, Vec2 origin, double angle, double maxRange);

}  // namespace fleet::geometry
