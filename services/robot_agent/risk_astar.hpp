#pragma once

// A* on the occupancy grid with the risk map as an additive cell cost: entering a cell costs its
// step length × (1 + weight · p), p the cell's collision probability in [0, 1]. Every step still
// costs at least its length, so the octile heuristic stays admissible (optimal paths), and a path's
// cost is at most (1 + weight) × its length: the chosen path is never longer than (1 + weight) × the
// shortest one (the detour bound). With no risk anywhere it is plain A* (same cost).

#include <functional>

#include "fleet/core/expected.hpp"
#include "fleet/planning/astar.hpp"
#include "fleet/planning/path.hpp"

namespace fleet::agent {

/// Collision probability at a map point; empty = no risk (plain A*).
using RiskCost = std::function<double(Vec2)>;

/// Error "unreachable" when no path exists, "off_grid"/"blocked" for a bad start or goal cell.
Expected<planning::GridPath> riskAstar(const planning::OccupancyGrid& grid, planning::Cell start,
                                       planning::Cell goal, const RiskCost& risk, double weight);

class RiskAStarPlanner final : public planning::GlobalPlanner {
 public:
  RiskAStarPlanner(RiskCost risk, double weight) : risk_(std::move(risk)), weight_(weight) {}
  /// Start or goal on a blocked cell: falls back to plain A* (which snaps them to free cells).
  [[nodiscard]] Expected<planning::Path> plan(const planning::OccupancyGrid& grid, Pose2 from,
                                              Pose2 to) override;
  [[nodiscard]] const char* name() const override { return "risk_astar"; }

 private:
  RiskCost risk_;
  double weight_;
};

}  // namespace fleet::agent
