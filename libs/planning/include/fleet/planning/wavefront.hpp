#pragma once

#include <functional>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/planning/occupancy_grid.hpp"
#include "fleet/planning/path.hpp"

namespace fleet::planning {

enum class Connectivity { Four, Eight };

/// Neighbour offsets in the fixed order used for deterministic tie-breaking. Four: east, south,
/// west, north (the seed's Hx/Hy order read as (row, column)); Eight adds SE, SW, NW, NE.
const std::vector<Cell>& neighbourOffsets(Connectivity conn);
/// Move cost in cells: 1 orthogonal, sqrt(2) diagonal.
double moveCost(Cell offset);
/// A diagonal move is allowed only when both orthogonal cells beside it are free (no corner cutting).
bool moveAllowed(const OccupancyGrid& grid, Cell from, Cell offset);

/// Cost-to-goal of every cell ("oil spill" from the goal, seed 004 phase 1). Four: breadth-first
/// step counts, exactly the seed's matrix d. Eight: Dijkstra with octile costs. Blocked and
/// unreachable cells hold +inf.
struct DistanceField {
  int width = 0;
  int height = 0;
  Cell goal;
  Connectivity conn = Connectivity::Four;
  std::vector<double> cost;

  [[nodiscard]] double at(Cell c) const;
  [[nodiscard]] bool reachable(Cell c) const;
};
DistanceField computeDistanceField(const OccupancyGrid& grid, Cell goal, Connectivity conn);

/// Seed 004 phase 2: from `start`, step to a neighbour whose cost is lower by exactly the move cost
/// (the first in neighbour order). Error "unreachable" when d(start) is infinite.
Expected<std::vector<Cell>> descend(const OccupancyGrid& grid, const DistanceField& field, Cell start);

/// Wavefront planner behind the GlobalPlanner interface.
class WavefrontPlanner final : public GlobalPlanner {
 public:
  explicit WavefrontPlanner(Connectivity conn = Connectivity::Eight) : conn_(conn) {}
  [[nodiscard]] Expected<Path> plan(const OccupancyGrid& grid, Pose2 from, Pose2 to) override;
  [[nodiscard]] const char* name() const override { return "wavefront"; }

 private:
  Connectivity conn_;
};

/// Seed 004's reaction to moving obstacles. Before each step the robot asks whether a collision is
/// predicted in the next cell (only cells within `scanRadius` cells are sensed). If so it compares
/// waiting, phi1 = d(x) + waitCost, with detouring through the best admissible neighbour (free, not
/// visited, no predicted collision): phi2 = min d(n). With `seedComparison` the rule is the printed
/// phi1 <= phi2 -> wait; by default phi2 + move cost is used so both sides count the remaining time
/// from the same cell (they differ only on ties). Waiting advances time by waitCost and re-checks.
struct WaitOrDetourOptions {
  double waitCost = 6.0;  ///< Delta c, in units of one orthogonal move (the paper's default 6)
  double scanRadius = 3.0;
  bool seedComparison = false;
  int maxSteps = 1000000;
  int maxConsecutiveWaits = 1000;  ///< waiting this often in a row with nowhere to go is an error
};
/// Predicted collision: would the robot meet a moving obstacle in `cell` if it entered at `time`?
using CollisionPredictor = std::function<bool(Cell cell, double time)>;
struct Execution {
  std::vector<Cell> cells;  ///< visited cells, start first (waits do not repeat cells)
  int moves = 0;
  int waits = 0;
  int detours = 0;
  double time = 0.0;  ///< elapsed time in move units (moves + waits * waitCost)
};
/// Errors: "unreachable" (d(start) = inf), "no_admissible_neighbour" (the next cell stays predicted
/// to collide and no neighbour is admissible for maxConsecutiveWaits waits), "step_limit".
Expected<Execution> executeWaitOrDetour(const OccupancyGrid& grid, const DistanceField& field, Cell start,
                                        const CollisionPredictor& predicted,
                                        const WaitOrDetourOptions& opt = {});

}  // namespace fleet::planning
