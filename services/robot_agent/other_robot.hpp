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
  std::int64_t stampNs = 0;  // stamp of its latest state
};

}  // namespace fleet::agent
