#pragma once

#include <memory>
#include <utility>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/planning/cost_layer.hpp"
#include "fleet/planning/occupancy_grid.hpp"
#include "fleet/planning/path.hpp"
#include "fleet/planning/wavefront.hpp"

namespace fleet::planning {

struct GridPath {
  std::vector<Cell> cells;  ///< start .. goal
  double cost = 0.0;        ///< in cells (1 per orthogonal, sqrt(2) per diagonal move)
  int expanded = 0;
};

/// Landmark ("ALT") lower bounds for A*: with exact costs d_L from a few landmark cells,
/// |d_L(goal) - d_L(n)| never exceeds the true cost from n to goal (triangle inequality on an
/// undirected grid) and is consistent. Landmarks are chosen farthest-first. Built once per map
/// (count distance fields); the heuristic used is max(octile, landmarks).
class LandmarkHeuristic {
 public:
  static LandmarkHeuristic build(const OccupancyGrid& grid, Connectivity conn, int count = 8);
  [[nodiscard]] double bound(std::size_t cell, std::size_t goal) const;
  [[nodiscard]] int count() const { return count_; }
  [[nodiscard]] Connectivity connectivity() const { return conn_; }
  [[nodiscard]] const std::vector<Cell>& landmarks() const { return landmarks_; }
  /// Built for a grid of this shape (a cheap guard against using it on another map).
  [[nodiscard]] bool matches(const OccupancyGrid& grid) const {
    return grid.width() == width_ && grid.height() == height_;
  }

 private:
  int width_ = 0;
  int height_ = 0;
  int count_ = 0;
  Connectivity conn_ = Connectivity::Eight;
  std::vector<Cell> landmarks_;
  std::vector<double> dist_;  // cell-major: dist_[cell * count_ + l]
};

/// A* with the octile heuristic (Eight, no corner cutting) or Manhattan (Four); both admissible and
/// consistent, so the cost equals the distance field's. Ties on f prefer larger g (deeper nodes).
/// Error "unreachable" when no path exists.
/// With `landmarks` (built for the same grid and connectivity) the heuristic is max(octile, ALT).
Expected<GridPath> astar(const OccupancyGrid& grid, Cell start, Cell goal,
                         Connectivity conn = Connectivity::Eight,
                         const LandmarkHeuristic* landmarks = nullptr);

/// The same search (8-connected, no corner cutting, octile heuristic) with each move's cost scaled
/// by the product of the layers' factors (each counted as at least 1, so the heuristic stays
/// admissible and the path is optimal for the layered cost). No layers: the fixed-point search
/// above, exactly. Error "unreachable" when no path exists or start or goal is blocked.
Expected<GridPath> astar(const OccupancyGrid& grid, Cell start, Cell goal, const CostLayers& layers);

/// The grid planner every service uses: plain, with landmarks, or with cost layers.
class AStarPlanner final : public GlobalPlanner {
 public:
  explicit AStarPlanner(Connectivity conn = Connectivity::Eight,
                        std::shared_ptr<const LandmarkHeuristic> landmarks = nullptr, CostLayers layers = {})
      : conn_(conn), landmarks_(std::move(landmarks)), layers_(std::move(layers)) {}
  [[nodiscard]] Expected<Path> plan(const OccupancyGrid& grid, Pose2 from, Pose2 to) override;
  [[nodiscard]] const char* name() const override { return "astar"; }

 private:
  Connectivity conn_;
  std::shared_ptr<const LandmarkHeuristic> landmarks_;  ///< used only on a grid of matching shape
  CostLayers layers_;  ///< non-empty: the layered search (8-connected; landmarks unused)
};

}  // namespace fleet::planning
