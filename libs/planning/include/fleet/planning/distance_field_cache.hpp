#pragma once

#include <cstddef>
#include <future>
#include <list>
#include <memory>
#include <mutex>
#include <unordered_map>

#include "fleet/planning/occupancy_grid.hpp"
#include "fleet/planning/wavefront.hpp"

namespace fleet::planning {

/// Travel costs for a fleet: one distance field per goal cell, computed once and shared (LRU,
/// `capacity` fields). Thread-safe; concurrent requests for the same goal wait for one computation.
class DistanceFieldCache {
 public:
  explicit DistanceFieldCache(std::shared_ptr<const OccupancyGrid> grid,
                              Connectivity conn = Connectivity::Eight, std::size_t capacity = 256);

  /// Distance field toward `goal` (all +inf if the goal is blocked).
  std::shared_ptr<const DistanceField> field(Cell goal);
  /// Cost in cells from `from` to `goal`; +inf when unreachable or outside the map.
  double travelCost(Cell from, Cell goal);
  /// Path length in metres between two map-frame points (cell to cell); +inf when unreachable.
  double travelDistance(Vec2 from, Vec2 to);

  [[nodiscard]] std::size_t computations() const;
  [[nodiscard]] const OccupancyGrid& grid() const { return *grid_; }

 private:
  using FieldPtr = std::shared_ptr<const DistanceField>;
  struct Entry {
    std::shared_future<FieldPtr> future;
    std::list<std::size_t>::iterator lru;
  };
  std::shared_ptr<const OccupancyGrid> grid_;
  Connectivity conn_;
  std::size_t capacity_;
  mutable std::mutex mu_;
  std::unordered_map<std::size_t, Entry> entries_;
  std::list<std::size_t> lru_;  // most recent first
  std::size_t computations_ = 0;
};

}  // namespace fleet::planning
