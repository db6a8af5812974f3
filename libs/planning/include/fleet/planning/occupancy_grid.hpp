#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/geometry/grid_raycast.hpp"

namespace fleet::planning {

/// A grid cell: x = column (rightwards), y = row counted from the BOTTOM (y-up map frame).
struct Cell {
  int x = 0;
  int y = 0;
  constexpr bool operator==(const Cell&) const = default;
};

/// Occupancy grid in the warehouse map frame. Cell (x, y) covers
/// [origin + (x, y) * resolution, origin + (x + 1, y + 1) * resolution); row 0 is at the bottom.
class OccupancyGrid {
 public:
  OccupancyGrid() = default;
  OccupancyGrid(int width, int height, double resolution = 1.0, Vec2 origin = {});

  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] int height() const { return height_; }
  [[nodiscard]] double resolution() const { return resolution_; }
  [[nodiscard]] Vec2 origin() const { return origin_; }
  [[nodiscard]] std::size_t size() const { return cells_.size(); }

  [[nodiscard]] bool inside(Cell c) const { return c.x >= 0 && c.y >= 0 && c.x < width_ && c.y < height_; }
  [[nodiscard]] std::size_t index(Cell c) const {
    return static_cast<std::size_t>(c.y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(c.x);
  }
  [[nodiscard]] Cell cellOf(std::size_t idx) const {
    return {static_cast<int>(idx % static_cast<std::size_t>(width_)),
            static_cast<int>(idx / static_cast<std::size_t>(width_))};
  }
  /// Outside the grid counts as blocked.
  [[nodiscard]] bool blocked(Cell c) const { return !inside(c) || cells_[index(c)] != 0; }
  [[nodiscard]] bool freeCell(Cell c) const { return !blocked(c); }
  void setBlocked(Cell c, bool b = true) { cells_[index(c)] = b ? 1 : 0; }
  [[nodiscard]] std::size_t freeCount() const;

  /// Cell containing a map-frame point, if inside the grid.
  [[nodiscard]] std::optional<Cell> cellAt(Vec2 p) const;
  [[nodiscard]] Vec2 cellCenter(Cell c) const {
    return origin_ + Vec2{(c.x + 0.5) * resolution_, (c.y + 0.5) * resolution_};
  }

  /// Every cell whose centre lies within `radius` of a blocked cell's centre becomes blocked
  /// (a disc robot of that radius planned as a point). Cells outside the map are not obstacles here.
  [[nodiscard]] OccupancyGrid inflated(double radius) const;

  [[nodiscard]] geometry::GridView view() const { return {width_, height_, resolution_, origin_, cells_}; }
  [[nodiscard]] const std::vector<std::uint8_t>& cells() const { return cells_; }

 private:
  int width_ = 0;
  int height_ = 0;
  double resolution_ = 1.0;
  Vec2 origin_;
  std::vector<std::uint8_t> cells_;
};

/// Procedural warehouse (similar in spirit to MovingAI warehouse-20-40-10-2-2): border walls, a free
/// margin, and a regular array of shelf blocks separated by aisles. The defaults give 340 x 164 cells
/// with 32 x 25 shelf blocks and 38,756 free cells, the free-cell count of warehouse-20-40-10-2-2.
struct WarehouseParams {
  int width = 340;
  int height = 164;
  int margin = 18;      ///< free band inside the border wall (docks, stations)
  int shelfWidth = 10;  ///< cells along x of one shelf block
  int shelfHeight = 2;  ///< cells along y of one shelf block
  int aisleX = 2;       ///< free cells between blocks along x
  int aisleY = 2;       ///< free cells between blocks along y
  double resolution = 1.0;
  Vec2 origin;
};
OccupancyGrid makeWarehouseGrid(const WarehouseParams& p = {});

}  // namespace fleet::planning
