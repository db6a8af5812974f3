#pragma once

#include <memory>

#include "fleet/planning/path.hpp"

namespace fleet::planning {

enum class OmplAlgorithm { RRTstar, PRMstar, InformedRRTstar };
enum class OmplSpace { R2, SE2 };

/// Adapter to OMPL's asymptotically optimal planners for continuous space. The robot is a disc of
/// `robotRadius` on the occupancy grid: states are valid when their cell of the inflated grid is
/// free, and a motion is valid when the straight segment crosses only free cells (exact grid
/// traversal, not sampling). The objective is path length.
struct OmplOptions {
  OmplAlgorithm algorithm = OmplAlgorithm::InformedRRTstar;
  OmplSpace space = OmplSpace::R2;
  double timeBudget = 1.0;   ///< seconds of planning (simplification time comes on top)
  double robotRadius = 0.0;  ///< metres; the grid is inflated by this radius
  double costThreshold =
      0.0;  ///< stop as soon as a path of at most this length is found (0: use the whole budget)
  /// > 0: the threshold per query is this times the straight line from start to goal (a planner
  /// built once for many queries); it then replaces costThreshold.
  double costThresholdRatio = 0.0;
  bool simplify = true;
  double simplifyTime = 0.1;
  double range = 0.0;  ///< maximum extension of RRT* variants in metres (0: OMPL's default)
};

struct OmplStats {
  double solveSeconds = 0.0;  ///< time spent in the planner
  double rawLength = 0.0;     ///< length before simplification
  double length = 0.0;        ///< length of the returned path
  bool thresholdMet = false;  ///< costThreshold was reached
};

class OmplPlanner final : public GlobalPlanner {
 public:
  explicit OmplPlanner(OmplOptions opt = {});
  /// Errors: the query errors of resolveQuery (on the inflated grid), "no_solution" when no exact
  /// path was found within the budget.
  [[nodiscard]] Expected<Path> plan(const OccupancyGrid& grid, Pose2 from, Pose2 to) override;
  [[nodiscard]] const char* name() const override;
  [[nodiscard]] const OmplStats& lastStats() const { return stats_; }
  OmplOptions& options() { return opt_; }

 private:
  OmplOptions opt_;
  OmplStats stats_;
};

}  // namespace fleet::planning
