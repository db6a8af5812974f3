#pragma once

// The kinematic bound of a transport task: the least time any robot of that size could
// take for it — the shortest way for its disc on the free map from where it was when the task was
// assigned to the pickup, and from the pickup to the drop-off, at the agent's cruise speed, plus the
// load and unload dwell. Fleet figures are stated against it: mean task time ÷ mean bound ("× the
// kinematic bound"), and a lone robot's ideal rate 3,600 ÷ mean bound tasks/h, against which the
// fleet's rate per robot gives its efficiency η.

#include <cstddef>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::ctl {

struct BoundTask {
  Vec2 start;  ///< the robot when the task was assigned to it
  Vec2 pickup;
  Vec2 dropoff;
  double radius = 0.3;  ///< m: the robot's disc
  double cruise = 0.8;  ///< m/s
  double dwellS = 0.0;  ///< load + unload
};

struct KinematicBound {
  double toPickupM = 0.0;
  double toDropoffM = 0.0;
  double driveS = 0.0;
  double dwellS = 0.0;
  [[nodiscard]] double seconds() const { return driveS + dwellS; }
};

/// The bound of each task, in order. Legs toward one station share a distance field (they are
/// computed grouped by goal, so a map of a million cells and a hundred stations costs one field per
/// station). A task whose station or start the disc cannot reach gets the error of that leg
/// ("unreachable", "no_room", "off_map") with the leg named; "bad_task" for a cruise ≤ 0, a negative
/// dwell or radius, or anything not finite. Nothing throws on bad input.
std::vector<Expected<KinematicBound>> kinematicBounds(const planning::OccupancyGrid& freeMap,
                                                      const std::vector<BoundTask>& tasks);

/// Task times against their bounds: mean task time ÷ mean bound.
struct BoundFigures {
  std::size_t tasks = 0;  ///< tasks with both a time and a bound
  double meanTaskS = 0.0;
  double meanBoundS = 0.0;
  double timeOverBound = 0.0;  ///< mean task time ÷ mean bound
};

/// `taskS` and `boundS` pair up (tasks without a bound are left out by the caller); zeros when there
/// is nothing to average.
BoundFigures boundFigures(const std::vector<double>& taskS, const std::vector<double>& boundS);

}  // namespace fleet::ctl
