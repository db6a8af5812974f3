#pragma once

// Where a disc robot can go on an occupancy grid: which cell centres it fits on, and which of
// those it can drive between. Cell connectivity alone says nothing about a robot 0.6 m wide in an
// aisle one 0.5 m cell across, so stations are checked with the robot's own radius.

#include <cstdint>
#include <vector>

#include "fleet/core/vec2.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::site {

/// Exact clearance test: the disc of `radius` at `p` overlaps no blocked cell (cells are closed
/// squares; outside the grid counts as blocked).
bool discFits(const planning::OccupancyGrid& g, Vec2 p, double radius);

/// The disc fits along the whole straight segment a→b (sampled at a quarter cell).
bool segmentFits(const planning::OccupancyGrid& g, Vec2 a, Vec2 b, double radius);

/// Free regions for a disc on a lattice of points: the cell centres, and on coarse maps (cells
/// larger than a third of the radius) also the cell edges and corners, so a 0.6 m robot is not
/// shut out of a 1 m aisle whose middle is a cell edge. Lattice points the disc fits on are joined
/// to their 4 neighbours: along such a step the distance to any grid-aligned square is smallest at
/// one of its ends (the square's edges fall on lattice lines), so the disc fits all the way.
struct DiscRegions {
  int width = 0;   ///< lattice points along x
  int height = 0;  ///< ... along y
  Vec2 first;      ///< map-frame position of point (0, 0)
  double step = 0.0;
  std::vector<std::int32_t> label;  ///< per point, 0 = the disc does not fit there
  std::vector<std::size_t> size;    ///< size[l] = points of region l (size[0] unused)

  [[nodiscard]] std::size_t count() const { return size.empty() ? 0 : size.size() - 1; }
  [[nodiscard]] Vec2 point(int i, int j) const { return first + Vec2{i * step, j * step}; }
  [[nodiscard]] double area(std::int32_t l) const {
    return static_cast<double>(size[static_cast<std::size_t>(l)]) * step * step;
  }
};
DiscRegions discRegions(const planning::OccupancyGrid& g, double radius);

/// Region a point belongs to for the disc: that of the nearest lattice point (within two steps)
/// reachable from it on a straight segment; 0 when the disc does not fit at `p` or is walled in.
std::int32_t regionOf(const planning::OccupancyGrid& g, const DiscRegions& r, Vec2 p, double radius);

/// The site's floor: of the regions the stations stand in (`stationRegions`, 0 = none), the one
/// holding most of them, the larger on a tie; 0 when no station is in any region. A station
/// elsewhere is cut off from the others.
std::int32_t floorRegion(const DiscRegions& r, const std::vector<std::int32_t>& stationRegions);

/// Plain 4-connected components of the free cells (what cell connectivity alone would say); one
/// lattice point per cell centre.
DiscRegions cellRegions(const planning::OccupancyGrid& g);

}  // namespace fleet::site
