#pragma once

#include <cmath>

namespace fleet::control {

/// Body-frame velocity command of a differential-drive (unicycle) robot: v forward [m/s], omega
/// counter-clockwise [rad/s].
struct Twist {
  double v = 0.0;
  double omega = 0.0;

  [[nodiscard]] bool isFinite() const { return std::isfinite(v) && std::isfinite(omega); }
  constexpr bool operator==(const Twist&) const = default;
};

}  // namespace fleet::control
