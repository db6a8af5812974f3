#include "fleet/geometry/aabb.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fleet::geometry {

Aabb2 Aabb2::merged(const Aabb2& o) const {
  return {{std::min(min.x, o.min.x), std::min(min.y, o.min.y)},
          {std::max(max.x, o.max.x), std::max(max.y, o.max.y)}};
}

double Aabb2::distanceTo(Vec2 p) const {
  const double dx = std::max({min.x - p.x, 0.0, p.x - max.x});
  const double dy = std::max({min.y - p.y, 0.0, p.y - max.y});
  return std::hypot(dx, dy);
}

std::optional<double> Aabb2::rayEntry(Vec2 origin, Vec2 dir, double tmax) const {
  double t0 = 0.0;
  double t1 = tmax;
  const double o[2] = {origin.x, origin.y};
  const double d[2] = {dir.x, dir.y};
  const double lo[2] = {min.x, min.y};
  const double hi[2] = {max.x, max.y};
  for (int k = 0; k < 2; ++k) {
    if (d[k] == 0.0) {
      if (o[k] < lo[k] || o[k] > hi[k]) {
        return std::nullopt;
      }
      continue;
    }
    double ta = (lo[k] - o[k]) / d[k];
    double tb = (hi[k] - o[k]) / d[k];
    if (ta > tb) {
      std::swap(ta, tb);
    }
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) {
      return std::nullopt;
    }
  }
  return t0;
}

bool overlaps(const Aabb2& a, const Aabb2& b) {
  return a.min.x <= b.max.x && b.min.x <= a.max.x && a.min.y <= b.max.y && b.min.y <= a.max.y;
}

bool overlaps(const Aabb3& a, const Aabb3& b) {
  return (a.min.array() <= b.max.array()).all() && (b.min.array() <= a.max.array()).all();
}

namespace {
bool inside(const Eigen::Vector3d& p, const Aabb3& box) {
  return (p.array() >= box.min.array()).all() && (p.array() <= box.max.array()).all();
}
}  // namespace

bool overlapsThesisCorner(const Aabb3& a, const Aabb3& b) {
  return inside(a.min, b) || inside(a.max, b) || inside(b.min, a) || inside(b.max, a);
}

}  // namespace fleet::geometry
