#include "fleet/geometry/grid_raycast.hpp"

#include <cmath>
#include <limits>

namespace fleet::geometry {

GridRayHit raycastGrid(const GridView& grid, Vec2 origin, double angle, double maxRange) {
  const double inf = std::numeric_limits<double>::infinity();
  const Vec2 dir{std::cos(angle), std::sin(angle)};
  const Vec2 local = (origin - grid.origin) / grid.resolution;
  int cx = static_cast<int>(std::floor(local.x));
  int cy = static_cast<int>(std::floor(local.y));
  if (grid.blocked(cx, cy)) {
    return {true, 0.0, cx, cy};
  }
  const int stepX = dir.x > 0.0 ? 1 : -1;
  const int stepY = dir.y > 0.0 ? 1 : -1;
  // Ray parameter (metres) at which the next vertical / horizontal cell boundary is crossed.
  const double dtx = dir.x != 0.0 ? grid.resolution / std::abs(dir.x) : inf;
  const double dty = dir.y != 0.0 ? grid.resolution / std::abs(dir.y) : inf;
  const double fx = local.x - std::floor(local.x);
  const double fy = local.y - std::floor(local.y);
  double tx = dir.x != 0.0 ? (stepX > 0 ? 1.0 - fx : fx) * dtx : inf;
  double ty = dir.y != 0.0 ? (stepY > 0 ? 1.0 - fy : fy) * dty : inf;
  while (true) {
    double t = 0.0;
    if (tx < ty) {
      t = tx;
      tx += dtx;
      cx += stepX;
    } else {
      t = ty;
      ty += dty;
      cy += stepY;
    }
    if (t > maxRange) {
      return {false, maxRange, -1, -1};
    }
    if (grid.blocked(cx, cy)) {
      return {true, t, cx, cy};
    }
  }
}

}  // namespace fleet::geometry
