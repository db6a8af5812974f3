#pragma once

// Shortest distances for a disc robot on the free map: what a robot could drive at best, not what a
// roadmap or a planner's margins allow. Used as the reference that fleet figures are measured
// against (the kinematic bound of `fleetctl loadtest`).
//
// The map is refined to cells of at most 0.1 m (an integer fraction of its own), and a cell is free
// when the disc centred on it overlaps no blocked map cell (discFits: exact clearance, no-go zones
// count as blocked when the caller passes Site::drivable()). Distances toward a goal are an
// any-angle field over those cells: Dijkstra from the goal, 8-connected without corner cutting,
// where a cell takes its neighbour's parent as its own when it sees it (Lazy Theta*: the line of
// sight is checked when the cell is settled), so a way costs its Euclidean length with bends at
// obstacle corners, not the octile length of a grid path (up to 8 % more on a diagonal), and the
// shorter of two ways round an obstacle is found by that length. docs/algorithms.md, "Kinematic
// bound", says how far off it can be.

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::site {

class DiscDistance {
 public:
  /// `map`: the free map (blocked cells are obstacles, outside the map is wall). Fields toward the
  /// last `cachedFields` goals are kept (a field is 12 bytes per refined cell). Throws
  /// std::invalid_argument on a radius that is negative or not finite, or an empty map.
  DiscDistance(const planning::OccupancyGrid& map, double radius, std::size_t cachedFields = 4);

  /// Length [m] of the shortest way for the disc from `from` to `to`; calls toward one goal share
  /// its field, so ask them together. A point whose refined cell the disc does not fit on (a robot
  /// pressed against a shelf, a station on a cell edge) joins the nearest free cell within `kSnapM`
  /// by a straight leg. Errors: "off_map" (a point outside the map or not finite), "no_room" (the
  /// disc fits nowhere within kSnapM of a point), "unreachable" (the disc cannot get from one to
  /// the other).
  [[nodiscard]] Expected<double> length(Vec2 from, Vec2 to);

  [[nodiscard]] double radius() const { return radius_; }
  [[nodiscard]] const planning::OccupancyGrid& grid() const { return *grid_; }

  static constexpr double kSnapM = 0.5;

 private:
  struct Snapped {
    planning::Cell cell;
    double leg = 0.0;  ///< straight distance from the point to the cell centre (0: its own cell)
  };
  /// Distances to one goal point: per cell, the length to it and the cell whose centre the way
  /// first heads for (kRoot: the goal point itself).
  struct Field {
    Vec2 goal;
    Vec2 root;  ///< where the field's ways end: the goal, or its snapped cell's centre
    std::vector<double> g;
    std::vector<std::int32_t> parent;
  };
  static constexpr std::int32_t kRoot = -1;

  [[nodiscard]] Expected<Snapped> snap(Vec2 p, const char* what) const;
  [[nodiscard]] const Field& field(Vec2 goal, const Snapped& at);
  [[nodiscard]] Vec2 parentPoint(const Field& f, std::int32_t parent) const;

  double radius_;
  std::shared_ptr<const planning::OccupancyGrid> grid_;
  std::size_t capacity_;
  std::vector<std::unique_ptr<Field>> fields_;  ///< most recent last
};

}  // namespace fleet::site
