#pragma once

// Small plane geometry the roadmap files share (internal).

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>
#include <vector>

#include "fleet/core/segment.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/geometry/polygon.hpp"

namespace fleet::traffic::detail {

/// "(x, y)" rounded to centimetres, for problems and log lines.
inline std::string pointText(Vec2 p) {
  std::ostringstream os;
  os << "(" << std::round(p.x * 100.0) / 100.0 << ", " << std::round(p.y * 100.0) / 100.0 << ")";
  return os.str();
}

/// Euclidean distance without std::hypot's overflow care (several times faster; roadmap
/// coordinates are metres).
inline double fastDistance(Vec2 a, Vec2 b) {
  return std::sqrt((a - b).squaredNorm());
}

using fleet::pointSegmentDistance;

inline bool segmentsCross(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  const double d1 = (b - a).cross(c - a);
  const double d2 = (b - a).cross(d - a);
  const double d3 = (d - c).cross(a - c);
  const double d4 = (d - c).cross(b - c);
  return ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0)) &&
         ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0));
}

/// Distance between segments ab and cd (0 when they cross).
inline double segmentDistance(Vec2 a, Vec2 b, Vec2 c, Vec2 d) {
  if (segmentsCross(a, b, c, d)) {
    return 0.0;
  }
  return std::min({pointSegmentDistance(a, c, d), pointSegmentDistance(b, c, d),
                   pointSegmentDistance(c, a, b), pointSegmentDistance(d, a, b)});
}

/// Distance from segment ab to the polygon's area (0 when they touch or overlap).
inline double segmentPolygonDistance(Vec2 a, Vec2 b, const std::vector<Vec2>& poly) {
  if (poly.empty()) {
    return 1e300;
  }
  if (geometry::insidePolygon(a, poly) || geometry::insidePolygon(b, poly)) {
    return 0.0;
  }
  double d = 1e300;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    d = std::min(d, segmentDistance(a, b, poly[j], poly[i]));
  }
  return d;
}

}  // namespace fleet::traffic::detail
