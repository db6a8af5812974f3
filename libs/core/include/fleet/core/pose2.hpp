#pragma once

#include <cmath>

#include "fleet/core/angles.hpp"
#include "fleet/core/vec2.hpp"

namespace fleet {

/// A planar pose in the map frame: x right, y up, theta counter-clockwise in (-pi, pi].
struct Pose2 {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;

  [[nodiscard]] constexpr Vec2 position() const { return {x, y}; }
  [[nodiscard]] Vec2 heading() const { return {std::cos(theta), std::sin(theta)}; }

  /// this ∘ other: `other` expressed in this pose's frame, returned in the parent frame.
  [[nodiscard]] Pose2 compose(const Pose2& o) const {
    const double c = std::cos(theta);
    const double s = std::sin(theta);
    return {x + c * o.x - s * o.y, y + s * o.x + c * o.y, wrapAngle(theta + o.theta)};
  }
  [[nodiscard]] Pose2 inverse() const {
    const double c = std::cos(theta);
    const double s = std::sin(theta);
    return {-c * x - s * y, s * x - c * y, wrapAngle(-theta)};
  }
  /// Point given in this pose's frame, expressed in the parent frame.
  [[nodiscard]] Vec2 transform(Vec2 p) const {
    const double c = std::cos(theta);
    const double s = std::sin(theta);
    return {x + c * p.x - s * p.y, y + s * p.x + c * p.y};
  }
  [[nodiscard]] bool isFinite() const { return std::isfinite(x) && std::isfinite(y) && std::isfinite(theta); }
  constexpr bool operator==(const Pose2&) const = default;
};

inline double distance(const Pose2& a, const Pose2& b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}

}  // namespace fleet
