#include "fleet/planning/occupancy_grid.hpp"

#include <algorithm>
#include <cmath>

namespace fleet::planning {

OccupancyGrid::OccupancyGrid(int width, int height, double resolution, Vec2 origin)
    : width_(std::max(0, width)), height_(std::max(0, height)), resolution_(resolution), origin_(origin) {
  cells_.assign(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), 0);
}

std::size_t OccupancyGrid::freeCount() const {
  return static_cast<std::size_t>(std::count(cells_.begin(), cells_.end(), std::uint8_t{0}));
}

std::optional<Cell> OccupancyGrid::cellAt(Vec2 p) const {
  const Vec2 l = (p - origin_) / resolution_;
  // Off the grid before the cast: a point far away (a site file's 4e14 m) is no int.
  if (!std::isfinite(l.x) || !std::isfinite(l.y) || l.x < 0.0 || l.y < 0.0 || l.x >= width_ ||
      l.y >= height_) {
    return std::nullopt;
  }
  const Cell c{static_cast<int>(std::floor(l.x)), static_cast<int>(std::floor(l.y))};
  if (!inside(c)) {
    return std::nullopt;
  }
  return c;
}

OccupancyGrid OccupancyGrid::inflated(double radius) const {
  OccupancyGrid out = *this;
  const int r = static_cast<int>(std::floor(radius / resolution_ + 1e-9));
  if (r <= 0) {
    return out;
  }
  // Precomputed disc stencil in cell units (centre-to-centre distance <= radius).
  std::vector<Cell> stencil;
  const double rr = radius / resolution_;
  for (int dy = -r; dy <= r; ++dy) {
    for (int dx = -r; dx <= r; ++dx) {
      if (dx * dx + dy * dy <= rr * rr + 1e-9) {
        stencil.push_back({dx, dy});
      }
    }
  }
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) {
      if (cells_[index({x, y})] == 0) {
        continue;
      }
      for (const Cell& s : stencil) {
        const Cell c{x + s.x, y + s.y};
        if (inside(c)) {
          out.cells_[index(c)] = 1;
        }
      }
    }
  }
  return out;
}

OccupancyGrid makeWarehouseGrid(const WarehouseParams& p) {
  OccupancyGrid g(p.width, p.height, p.resolution, p.origin);
  for (int x = 0; x < p.width; ++x) {
    g.setBlocked({x, 0});
    g.setBlocked({x, p.height - 1});
  }
  for (int y = 0; y < p.height; ++y) {
    g.setBlocked({0, y});
    g.setBlocked({p.width - 1, y});
  }
  const int x0 = p.margin;
  const int x1 = p.width - p.margin;
  const int y0 = p.margin;
  const int y1 = p.height - p.margin;
  for (int by = y0; by + p.shelfHeight <= y1; by += p.shelfHeight + p.aisleY) {
    for (int bx = x0; bx + p.shelfWidth <= x1; bx += p.shelfWidth + p.aisleX) {
      for (int y = by; y < by + p.shelfHeight; ++y) {
        for (int x = bx; x < bx + p.shelfWidth; ++x) {
          g.setBlocked({x, y});
        }
      }
    }
  }
  return g;
}

}  // namespace fleet::planning
