#include "fleet/geometry/polygon.hpp"

namespace fleet::geometry {

bool insidePolygon(Vec2 p, std::span<const Vec2> poly) {
  if (poly.size() < 3) {
    return false;
  }
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vec2 a = poly[i];
    const Vec2 b = poly[j];
    // (a.y > p.y) != (b.y > p.y) excludes horizontal edges, so the division is by a non-zero value.
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) {
      in = !in;
    }
  }
  return in;
}

}  // namespace fleet::geometry
