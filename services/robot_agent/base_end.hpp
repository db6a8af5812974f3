#pragma once

// Where a robot in reserved traffic is against the end of the base it follows: drive on, drive
// straight onto the end, or stand there. The path follower measures what is left by projecting the
// robot onto the way; the release tracker counts a node reached within its reach tolerance. The two
// disagree when the robot comes at the end from the side: projected onto the end, 0.17 m beside it,
// The robot stood and never reported the node, and the traffic manager waited on it for good (a
// robot going home, full stack, seed 2: 1,400 s, five robots behind it).

#include "fleet/core/vec2.hpp"

namespace fleet::agent {

struct BaseEndParams {
  /// Left of the way by projection [m] below which the robot is at its end ...
  double atEnd = 0.02;
  /// ... unless the end itself is further than this [m] (less than the release tracker's reach
  /// tolerance, 0.15 m, with room for the estimate's jitter): then it drives onto the end.
  double settleBeyond = 0.10;
  /// The end within this [m] and no longer ahead of the robot: there (turning round for the last
  /// centimetres would sweep the body over what was not released). At most the reach tolerance.
  double behindWithin = 0.15;
};

enum class BaseEnd {
  kDrive,   ///< more of the way ahead
  kSettle,  ///< projected onto the end but beside it: face the end and drive straight onto it
  kStand,   ///< there
};

/// `left`: what is left of the way by projection [m]; `toEnd`: from the robot to the way's end;
/// `facing`: the robot's heading as a unit vector; `finalApproach`: the follower's carrot is on the
/// end.
[[nodiscard]] BaseEnd baseEnd(double left, Vec2 toEnd, Vec2 facing, bool finalApproach,
                              const BaseEndParams& p = {});

}  // namespace fleet::agent
