#pragma once

#include "fleet/control/twist.hpp"
#include "fleet/core/expected.hpp"

namespace fleet::control {

/// Speed and acceleration bounds of the base. Defaults: the seed-003 robot's 0.45 m/s top speed; the
/// other bounds are not in the seed and are our choice (see docs/algorithms.md).
struct VelocityLimits {
  double vMax = 0.45;     ///< forward speed bound [m/s], >= 0
  double vMin = -0.45;    ///< reverse speed bound [m/s], <= 0
  double omegaMax = 1.5;  ///< |omega| bound [rad/s]
  double accelMax = 0.5;  ///< |dv/dt| bound [m/s²]
  double alphaMax = 2.0;  ///< |domega/dt| bound [rad/s²]

  [[nodiscard]] Expected<void> validate() const;
};

struct LimitedTwist {
  Twist twist;
  bool rejected = false;   ///< the request was NaN/inf and was replaced by a stop request
  bool saturated = false;  ///< a speed or acceleration bound changed the request
};

/// Clamps `desired` to the speed bounds (scaling v and omega together so the path curvature is kept),
/// then moves from `previous` toward it by at most accel·dt and alpha·dt. A non-finite request is
/// replaced by (0, 0) — a controlled stop within the deceleration bounds — and flagged so the caller
/// can count it. A non-finite `previous` is treated as standing still; dt <= 0 or non-finite keeps
/// `previous` (clamped to the speed bounds).
LimitedTwist applyLimits(const VelocityLimits& limits, Twist desired, Twist previous, double dt);

}  // namespace fleet::control
