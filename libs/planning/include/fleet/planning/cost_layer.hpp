#pragma once

// Move costs for the one grid A* (astar.hpp), composed from layers: each layer scales the cost of a
// move between neighbouring cells by a factor, and a move costs its length times the product of
// the factors. Risk (prefer low collision probability), one-way lanes (a wrong-way move costs
// more) and zones (slower cells take longer) are layers; the search itself is written once.

#include <functional>
#include <memory>
#include <vector>

#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::planning {

class CostLayer {
 public:
  virtual ~CostLayer() = default;
  /// Factor on the cost of the move from `from` into its neighbour `to`. The search counts values
  /// below 1 (and NaN) as 1, so every move costs at least its length and the octile heuristic stays
  /// admissible: paths stay optimal for the layered cost.
  [[nodiscard]] virtual double factor(Cell from, Cell to) const = 0;
  [[nodiscard]] virtual const char* name() const = 0;
};

using CostLayers = std::vector<std::shared_ptr<const CostLayer>>;

/// A layer that prices entering a cell, whatever the direction: e.g. 1 + w·p for a risk map.
class EnterCellCost final : public CostLayer {
 public:
  EnterCellCost(const char* name, std::function<double(Cell)> f) : name_(name), f_(std::move(f)) {}
  [[nodiscard]] double factor(Cell /*from*/, Cell to) const override { return f_(to); }
  [[nodiscard]] const char* name() const override { return name_; }

 private:
  const char* name_;
  std::function<double(Cell)> f_;
};

}  // namespace fleet::planning
