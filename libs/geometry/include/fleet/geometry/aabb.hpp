#pragma once

#include <Eigen/Core>
#include <optional>

#include "fleet/core/vec2.hpp"

namespace fleet::geometry {

/// Axis-aligned box in the plane, closed: touching boxes overlap.
struct Aabb2 {
  Vec2 min;
  Vec2 max;

  /// Thesis (2.1) with full side lengths (sx, sy), not half extents.
  static Aabb2 fromCenterSize(Vec2 c, Vec2 size) { return {c - size * 0.5, c + size * 0.5}; }
  [[nodiscard]] Vec2 center() const { return (min + max) * 0.5; }
  [[nodiscard]] Vec2 extent() const { return max - min; }
  [[nodiscard]] bool contains(Vec2 p) const {
    return p.x >= min.x && p.x <= max.x && p.y >= min.y && p.y <= max.y;
  }
  [[nodiscard]] Aabb2 merged(const Aabb2& o) const;
  /// Euclidean distance from p to the box (0 inside).
  [[nodiscard]] double distanceTo(Vec2 p) const;
  /// Entry parameter t >= 0 of the ray origin + t*dir (dir need not be unit) within [0, tmax], if any.
  [[nodiscard]] std::optional<double> rayEntry(Vec2 origin, Vec2 dir, double tmax) const;
};

/// Axis-aligned box in space.
struct Aabb3 {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Zero();

  /// Thesis (2.1): centre and full side lengths a0, a1, a2.
  static Aabb3 fromCenterSize(const Eigen::Vector3d& c, const Eigen::Vector3d& size) {
    return {c - 0.5 * size, c + 0.5 * size};
  }
};

/// Correct interval test: overlap on every axis (closed intervals).
bool overlaps(const Aabb2& a, const Aabb2& b);
bool overlaps(const Aabb3& a, const Aabb3& b);

/// The thesis's test (2.2), kept as the faithful reference: a collision iff a min or max corner of
/// one box lies inside the other. It misses "cross" overlaps where no corner is inside.
bool overlapsThesisCorner(const Aabb3& a, const Aabb3& b);

}  // namespace fleet::geometry
