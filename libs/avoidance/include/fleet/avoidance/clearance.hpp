#pragma once

#include <cmath>
#include <span>
#include <vector>

#include "fleet/avoidance/local_planner.hpp"

namespace fleet::avoidance {

/// Euclidean distance without std::hypot's overflow care (hot loops; coordinates are metres).
inline double fastDistance(Vec2 a, Vec2 b) {
  return std::sqrt((a - b).squaredNorm());
}

/// Smallest distance from any point of the circular arc (exact diff-drive motion under a constant
/// twist from `start` for `duration`) to `p`. Analytic, so a rollout costs O(points), not
/// O(points × steps).
double arcPointDistance(const Pose2& start, Twist t, double duration, Vec2 p);

/// Minimum over the scan of arcPointDistance minus the robot radius (negative = collision),
/// saturated at `cap` (points farther than that from the arc's circle are skipped cheaply).
double arcClearance(const Pose2& start, Twist t, double duration, std::span<const Vec2> scan, double radius,
                    double cap);

/// Surface-to-surface clearance to the scan and the discs (at time 0) from a point.
double pointClearance(const LocalView& view, Vec2 p, double radius);

/// Keep only the scan points within `range` of `centre` (one pass per cycle so rollouts see few).
void nearbyPoints(std::span<const Vec2> scan, Vec2 centre, double range, std::vector<Vec2>& out);

}  // namespace fleet::avoidance
