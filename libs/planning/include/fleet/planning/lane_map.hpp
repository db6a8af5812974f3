#pragma once

// Traffic lanes for a warehouse map: narrow aisles become one-way, adjacent aisles in alternating
// directions, so two robots never meet head-on in an aisle too narrow to pass (the common rule of
// industrial AGV layouts). Wider corridors (bands along the walls) get two lanes, keep right;
// intersections and open areas stay free in every direction.

#include <cstdint>
#include <memory>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/planning/cost_layer.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::planning {

struct LaneParams {
  /// A corridor narrower than this [m] is a narrow aisle (one-way). The default lets two robots of
  /// 0.3 m radius pass each other with margin in anything at least 2 m wide.
  double max_aisle_width = 2.0;
  /// Corridors from max_aisle_width up to this width [m] get two lanes (keep right).
  double max_two_lane_width = 8.0;
  /// ... provided the aisle or corridor runs at least this many times its width along its length.
  double min_aspect = 2.0;
  /// A move against a lane costs this many times its length: a legal detour is taken unless it is
  /// more than this much longer (dead ends, a goal just behind the robot).
  double wrong_way_factor = 10.0;
};

/// Direction of travel allowed in a cell: {0, 0} two-way, {±1, 0} a horizontal one-way aisle,
/// {0, ±1} a vertical one.
struct LaneDir {
  std::int8_t dx = 0;
  std::int8_t dy = 0;
  constexpr bool operator==(const LaneDir&) const = default;
};

class LaneMap {
 public:
  LaneMap() = default;
  /// Lanes of `raw` (the map itself, not inflated: aisle widths are measured between obstacles).
  static LaneMap derive(const OccupancyGrid& raw, const LaneParams& p = {});

  [[nodiscard]] LaneDir at(Cell c) const;
  /// True when the move from `a` to the neighbouring cell `b` goes against the lane of either cell.
  [[nodiscard]] bool againstLane(Cell a, Cell b) const;
  [[nodiscard]] double wrongWayFactor() const { return factor_; }
  [[nodiscard]] int width() const { return width_; }
  [[nodiscard]] int height() const { return height_; }
  [[nodiscard]] bool matches(const OccupancyGrid& g) const {
    return g.width() == width_ && g.height() == height_;
  }
  /// Number of cells that are part of a one-way aisle.
  [[nodiscard]] std::size_t oneWayCells() const;

 private:
  int width_ = 0;
  int height_ = 0;
  double factor_ = 10.0;
  std::vector<LaneDir> dir_;
};

/// The lanes as a cost layer of the grid A* (astar.hpp): a move against the lane of either cell
/// costs `wrongWayFactor` times its length, so a legal detour is taken unless it is that much longer.
class LaneCost final : public CostLayer {
 public:
  explicit LaneCost(std::shared_ptr<const LaneMap> lanes) : lanes_(std::move(lanes)) {}
  [[nodiscard]] double factor(Cell from, Cell to) const override {
    return lanes_->againstLane(from, to) ? lanes_->wrongWayFactor() : 1.0;
  }
  [[nodiscard]] const char* name() const override { return "lanes"; }

 private:
  std::shared_ptr<const LaneMap> lanes_;
};

}  // namespace fleet::planning
