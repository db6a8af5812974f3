#pragma once

#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/planning/occupancy_grid.hpp"
#include "fleet/planning/path.hpp"
#include "fleet/planning/wavefront.hpp"

namespace fleet::planning {

struct GridPath {
  std::vector<Cell> cells;  ///< start .. goal
  double cost = 0.0;        ///< in cells (1 per orthogonal, sqrt(2) per diagonal move)
  int expanded = 0;
};

/// A* with the octile heuristic (Eight, no corner cutting) or Manhattan (Four); both admissible and
/// consistent, so the cost equals the distance field's. Ties on f prefer larger g (deeper nodes).
/// Error "unreachable" when no path exists.
Expected<GridPath> astar(const OccupancyGrid& grid, Cell start, Cell goal,
                         Connectivity conn = Connectivity::Eight);

class AStarPlanner final : public GlobalPlanner {
 public:
  explicit AStarPlanner(Connectivity conn = Connectivity::Eight) : conn_(conn) {}
  [[nodiscard]] Expected<Path> plan(const OccupancyGrid& grid, Pose2 from, Pose2 to) override;
  [[nodiscard]] const char* name() const override { return "astar"; }

 private:
  Connectivity conn_;
};

}  // namespace fleet::planning
