#include "fleet/scenario/grid_map.hpp"

#include <algorithm>
#include <cmath>

namespace fleet::sim {

namespace {
// Closest point of cell (cx, cy)'s square to p.
Vec2 closestOnCell(const GridMap& map, int cx, int cy, Vec2 p) {
  const double x0 = map.origin.x + cx * map.resolution;
  const double y0 = map.origin.y + cy * map.resolution;
  return {std::clamp(p.x, x0, x0 + map.resolution), std::clamp(p.y, y0, y0 + map.resolution)};
}
}  // namespace

bool nearestBlocked(const GridMap& map, Vec2 p, double reach, double& dist, Vec2& awayDir) {
  const int x0 = map.cellX(p.x - reach);
  const int x1 = map.cellX(p.x + reach);
  const int y0 = map.cellY(p.y - reach);
  const int y1 = map.cellY(p.y + reach);
  double best = reach;
  bool found = false;
  Vec2 bestPoint;
  for (int cy = y0; cy <= y1; ++cy) {
    for (int cx = x0; cx <= x1; ++cx) {
      if (!map.blocked(cx, cy)) {
        continue;
      }
      const Vec2 q = closestOnCell(map, cx, cy, p);
      const double d = std::sqrt((p - q).squaredNorm());
      if (d < best || (!found && d <= best)) {
        best = d;
        bestPoint = q;
        found = true;
      }
    }
  }
  if (!found) {
    return false;
  }
  dist = best;
  const Vec2 away = p - bestPoint;
  if (away.squaredNorm() > 0.0) {
    awayDir = away.normalized();
  } else {
    // Centre inside a blocked cell: push towards the nearest free neighbour's centre.
    const int cx = map.cellX(p.x);
    const int cy = map.cellY(p.y);
    awayDir = {};
    for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
      if (!map.blocked(cx + dx, cy + dy)) {
        awayDir = Vec2{static_cast<double>(dx), static_cast<double>(dy)};
        break;
      }
    }
  }
  return true;
}

double discGridPenetration(const GridMap& map, Vec2 centre, double radius) {
  double d = 0.0;
  Vec2 dir;
  if (!nearestBlocked(map, centre, radius, d, dir)) {
    return 0.0;
  }
  // A centre inside a blocked cell is at least a full radius deep.
  return d <= 0.0 ? radius : std::max(0.0, radius - d);
}

GridMap fromOccupancyGrid(const planning::OccupancyGrid& g) {
  GridMap m;
  m.width = g.width();
  m.height = g.height();
  m.resolution = g.resolution();
  m.origin = g.origin();
  m.cells = g.cells();
  return m;
}

planning::OccupancyGrid toOccupancyGrid(const GridMap& m) {
  planning::OccupancyGrid g(m.width, m.height, m.resolution, m.origin);
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      if (m.blocked(x, y)) {
        g.setBlocked({x, y});
      }
    }
  }
  return g;
}

}  // namespace fleet::sim
