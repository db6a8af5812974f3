#pragma once

// Distance from a point to a segment, shared by the roadmap's geometry, the local planners'
// clearance and the agent's rejoin rule.

#include <algorithm>
#include <cmath>

#include "fleet/core/vec2.hpp"

namespace fleet {

/// Distance from p to the segment a-b (to a when a == b). No std::hypot: its overflow care is
/// several times slower, and coordinates here are metres.
inline double pointSegmentDistance(Vec2 p, Vec2 a, Vec2 b) {
  const Vec2 ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0.0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return std::sqrt((p - (a + ab * t)).squaredNorm());
}

}  // namespace fleet
