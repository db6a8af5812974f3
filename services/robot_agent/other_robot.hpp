#pragma once

// Another robot as the agent last heard of it (its RobotState): where it is, where it is heading,
// and what it is doing.

#include <cstdint>
#include <string>

#include "fleet/core/vec2.hpp"

namespace fleet::agent {

struct OtherRobot {
  /// As it reports itself (RobotState.mode).
  enum class Mode { kIdle, kMoving, kWaiting, kLoading, kCharging, kBlocked, kFault };
  std::string id;
  Vec2 pos;
  Mode mode = Mode::kIdle;
  bool hasTask = false;
  Vec2 velocity;
  double theta = 0.0;
  std::int64_t waitingSinceNs = -1;  // stamp of its first state of the current wait (-1: not waiting)
  std::int64_t stampNs = 0;          // stamp of its latest state
};

/// It will most likely stand where it is for a while (loading, charging, parked, faulted, or
/// waiting for long): plans go around it rather than queue behind it.
bool standing(const OtherRobot& o);

}  // namespace fleet::agent
