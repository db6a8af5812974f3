#pragma once

#include <cmath>

#include "fleet/core/pose2.hpp"

namespace fleet::agent {

/// Where a point lies against the axis through a pose along its heading: how far along it
/// (negative: behind) and how far beside it.
struct AxisOffset {
  double along = 0.0;
  double lateral = 0.0;
};

inline AxisOffset axisOffset(const Pose2& origin, Vec2 p) {
  const Vec2 u = origin.heading();
  const Vec2 rel = p - origin.position();
  return {rel.dot(u), std::abs(rel.x * u.y - rel.y * u.x)};
}

}  // namespace fleet::agent
