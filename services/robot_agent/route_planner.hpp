#pragma once

// Where the agent's global paths come from. The planner is chosen once, by name, when the agent is
// built (makeGlobalPlanner); cost layers compose what the search weighs: the site's rules (one-way
// lanes) in every search, the risk map as a preference only in the first try. A request walks a
// fallback chain instead of failing when robots that stand still box the robot in.

#include <memory>
#include <string>

#include "fleet/core/expected.hpp"
#include "fleet/planning/cost_layer.hpp"
#include "fleet/planning/lane_map.hpp"
#include "fleet/planning/occupancy_grid.hpp"
#include "fleet/planning/path.hpp"
#include "fleet/risk/risk_lookup.hpp"

namespace fleet::agent {

struct RouteOptions {
  /// "astar" (the one grid A*, with cost layers), "wavefront" or "ompl" (Informed RRT*, 50 ms per
  /// plan; stops at the first path within 1.2× the straight line). Wavefront and OMPL take no layers.
  std::string planner = "astar";
  /// One-way aisles (shared by every agent of a process); set, the planner is the layered A*
  /// whatever `planner` says, as lanes are a rule every path keeps.
  std::shared_ptr<const planning::LaneMap> lanes;
  /// Risk as a cell cost: entering a cell costs its step × (1 + riskWeight · p), so a path is at
  /// most (1 + riskWeight)× the shortest one.
  double riskWeight = 1.0;
  double radius = 0.3;  ///< the robot's disc, for opening a goal that lies in the planning margin
  /// More rules every path keeps (the site's one-way and speed-limit zones, site/zone_costs.hpp);
  /// set, the planner is the layered A* as with lanes.
  planning::CostLayers rules;
};

/// The global planner called `kind` with `layers` (only "astar" takes layers). Error
/// "unknown_planner" naming the kinds there are.
Expected<std::unique_ptr<planning::GlobalPlanner>> makeGlobalPlanner(const std::string& kind,
                                                                     planning::CostLayers layers);

/// The robot's disc at `p` is clear of `raw`'s obstacles (its centre and eight points on its rim).
[[nodiscard]] bool bodyFits(const planning::OccupancyGrid& raw, Vec2 p, double radius);

/// A station closer to a wall than the planning margin (parking places along a wall) lies in a
/// blocked cell of the planning grid `g`: opens just that cell when the robot fits on `goal`, so a
/// path keeps its margin up to the last cell and then steps onto the station (the raw map's paths
/// hug walls and shelf corners that the stop rule will not let the robot pass).
void openGoal(planning::OccupancyGrid& g, const planning::OccupancyGrid& raw, Vec2 goal, double radius);

class RoutePlanner {
 public:
  /// `grid` is the map inflated for planning, `raw` the map itself (same frame). Throws
  /// std::invalid_argument for an unknown planner or a lane map of another size.
  RoutePlanner(RouteOptions opt, std::shared_ptr<const planning::OccupancyGrid> grid,
               std::shared_ptr<const planning::OccupancyGrid> raw);

  /// The newest risk map (null: none); the first try of every later route weighs it.
  void setRisk(std::shared_ptr<const risk::RiskLookup> risk);

  /// The first path of: on `around` (the planning grid with standing robots blocked) weighing
  /// risk; on the planning grid alone with the goal's cell opened when the robot fits there
  /// (standing robots box it in: wait them out); on the raw map (a start or goal hugging a shelf).
  [[nodiscard]] Expected<planning::Path> route(const planning::OccupancyGrid& around, Pose2 from, Pose2 to);
  /// A way on `detour` only (the cells round an obstacle blocked), no fallback: without one the
  /// caller keeps its path.
  [[nodiscard]] Expected<planning::Path> detour(const planning::OccupancyGrid& detour, Pose2 from, Pose2 to);

  [[nodiscard]] const char* plannerName() const { return rules_->name(); }

 private:
  RouteOptions opt_;
  std::shared_ptr<const planning::OccupancyGrid> grid_;
  std::shared_ptr<const planning::OccupancyGrid> raw_;
  planning::CostLayers ruleLayers_;
  bool layered_ = false;                            // the planner is the A* (the only one that takes layers)
  std::unique_ptr<planning::GlobalPlanner> rules_;  // the site's rules only
  std::unique_ptr<planning::GlobalPlanner> preferred_;  // ... and the risk map (null: same as rules_)
};

}  // namespace fleet::agent
