#pragma once

// The map's walls and shelves near the robot as points (a local costmap's static layer): a scan's
// rays are 26 cm apart at 3 m, and a shelf corner between two of them is there all the same.

#include <vector>

#include "fleet/core/vec2.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::agent {

/// Points every ~0.1 m along the faces of `map`'s obstacles that are turned towards `here`, closer
/// than `range` (map frame).
std::vector<Vec2> mapFaces(const planning::OccupancyGrid& map, Vec2 here, double range);

}  // namespace fleet::agent
