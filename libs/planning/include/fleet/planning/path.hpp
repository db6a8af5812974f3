#pragma once

#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/core/pose2.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::planning {

/// A planned path in the map frame. poses.front() is the start, poses.back() the goal pose; every
/// intermediate pose faces the next one.
struct Path {
  std::vector<Pose2> poses;
  [[nodiscard]] double length() const;
  [[nodiscard]] bool empty() const { return poses.empty(); }
};

/// Global planners share one interface (DESIGN.md §5); each algorithm is one implementation.
class GlobalPlanner {
 public:
  virtual ~GlobalPlanner() = default;
  [[nodiscard]] virtual Expected<Path> plan(const OccupancyGrid& grid, Pose2 from, Pose2 to) = 0;
  [[nodiscard]] virtual const char* name() const = 0;
};

/// Start and goal cells of a query, with typed errors (codes "out_of_map", "start_blocked",
/// "goal_blocked", "invalid_pose").
struct CellQuery {
  Cell start;
  Cell goal;
};
Expected<CellQuery> resolveQuery(const OccupancyGrid& grid, Pose2 from, Pose2 to);

/// Cell sequence -> Path: the exact start and goal poses, cell centres in between, collinear runs
/// merged, headings toward the next pose.
Path cellsToPath(const OccupancyGrid& grid, const std::vector<Cell>& cells, Pose2 from, Pose2 to);

}  // namespace fleet::planning
