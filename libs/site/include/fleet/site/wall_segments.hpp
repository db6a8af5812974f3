#pragma once

// The site's walls as straight segments, for a localizer that matches the lines it sees in a range
// scan against them (docs/algorithms.md, estimation: the line map).

#include <vector>

#include "fleet/core/vec2.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::site {

/// One face of the obstacles: the straight run from `a` to `b` (map frame) between blocked cells
/// and free ones; `normal` is the unit vector out of the obstacle, into the free side a robot sees
/// the face from.
struct WallSegment {
  Vec2 a;
  Vec2 b;
  Vec2 normal;
  [[nodiscard]] double length() const { return distance(a, b); }
};

/// Every cell edge with a blocked cell on one side and a free cell on the other (off the grid counts
/// as blocked, as in OccupancyGrid::blocked) is a piece of wall; collinear pieces facing the same
/// way that touch end to end are merged into one maximal segment. Segments shorter than
/// `minLength` [m] are left out (a scan cannot fit a line to them). Order: horizontal faces by row
/// then column, then vertical faces by column then row, so the result is deterministic.
std::vector<WallSegment> wallSegments(const planning::OccupancyGrid& map, double minLength = 0.0);

}  // namespace fleet::site
