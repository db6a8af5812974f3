#pragma once

// The simulator's scanner (72 rays over 360° from -π, 8 m; a miss reads 8 m exactly) inside a
// width × height room whose corner is the origin, from the true pose: for tests of what the laser
// lines do.

#include <algorithm>
#include <cmath>
#include <vector>

#include "fleet/core/angles.hpp"
#include "fleet/core/pose2.hpp"

namespace fleet::test {

constexpr int kRoomRays = 72;
constexpr double kRoomRayStep = 2.0 * kPi / kRoomRays;

inline std::vector<float> roomRanges(const Pose2& truth, double width, double height) {
  std::vector<float> ranges;
  for (int i = 0; i < kRoomRays; ++i) {
    const double a = truth.theta - kPi + i * kRoomRayStep;
    const double c = std::cos(a);
    const double s = std::sin(a);
    double t = 8.0;
    if (c > 1e-9)
      t = std::min(t, (width - truth.x) / c);
    if (c < -1e-9)
      t = std::min(t, -truth.x / c);
    if (s > 1e-9)
      t = std::min(t, (height - truth.y) / s);
    if (s < -1e-9)
      t = std::min(t, -truth.y / s);
    ranges.push_back(static_cast<float>(t));
  }
  return ranges;
}

}  // namespace fleet::test
