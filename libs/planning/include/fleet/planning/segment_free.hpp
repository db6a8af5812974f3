#pragma once

// Kept apart from the OMPL planner so that code checking straight segments (the return path) does
// not link OMPL.

#include "fleet/core/vec2.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::planning {

/// Straight segment a->b crosses only free cells of `grid` (and stays inside the map).
bool segmentFree(const OccupancyGrid& grid, Vec2 a, Vec2 b);

}  // namespace fleet::planning
