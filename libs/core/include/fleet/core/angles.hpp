#pragma once

#include <cmath>
#include <numbers>

namespace fleet {

inline constexpr double kPi = std::numbers::pi;

/// Wraps an angle to (-pi, pi], the convention of every message and library in the project.
inline double wrapAngle(double a) {
  if (!std::isfinite(a)) {
    return a;
  }
  a = std::remainder(a, 2.0 * kPi);  // [-pi, pi]
  if (a <= -kPi) {
    a += 2.0 * kPi;
  }
  return a;
}

/// Smallest signed difference a - b, wrapped to (-pi, pi].
inline double angleDiff(double a, double b) {
  return wrapAngle(a - b);
}

inline constexpr double deg2rad(double d) {
  return d * kPi / 180.0;
}
inline constexpr double rad2deg(double r) {
  return r * 180.0 / kPi;
}

}  // namespace fleet
