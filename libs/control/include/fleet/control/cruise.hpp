#pragma once

#include <algorithm>

#include "fleet/control/velocity_limits.hpp"

namespace fleet::control {

/// The speed the robot agent drives its paths at. Kept below the base's top speed so the stop rule's
/// gap and the docking law hold; figures that compare against "the agent at cruise" (the kinematic
/// bound of `fleetctl loadtest`, the roadmap's edge durations) take it from here.
inline constexpr double kAgentCruiseSpeed = 0.8;  // m/s

/// The free space [m] the agent's stop rule keeps to another robot in reserved traffic (0.35 m to
/// people and shelves). The roadmap's following distance is built from it (RoadmapOptions::stopGap),
/// so the two cannot drift apart: a wider gap in the agent turns every planned follow into a halt.
inline constexpr double kAgentRobotStopGap = 0.25;

/// A robot's cruise: the agent's, or the base's forward limit where that is lower.
[[nodiscard]] inline double agentCruiseSpeed(const VelocityLimits& base) {
  return std::min(kAgentCruiseSpeed, base.vMax);
}

}  // namespace fleet::control
