#include "risk_astar.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <queue>
#include <vector>

namespace fleet::agent {

Expected<planning::GridPath> riskAstar(const planning::OccupancyGrid& grid, planning::Cell start,
                                       planning::Cell goal, const RiskCost& risk, double weight) {
  if (!grid.inside(start) || !grid.inside(goal)) {
    return unexpected("off_grid", "start or goal outside the map");
  }
  if (grid.blocked(start) || grid.blocked(goal)) {
    return unexpected("blocked", "start or goal cell is blocked");
  }
  const std::size_t n = grid.size();
  // Risk per cell, looked up lazily once (only cells the search reaches).
  std::vector<double> cellRisk(n, -1.0);
  auto riskOf = [&](planning::Cell c) {
    double& r = cellRisk[grid.index(c)];
    if (r < 0.0) {
      r = risk ? std::clamp(risk(grid.cellCenter(c)), 0.0, 1.0) : 0.0;
    }
    return r;
  };
  auto octile = [&](planning::Cell c) {
    const double dx = std::abs(c.x - goal.x);
    const double dy = std::abs(c.y - goal.y);
    return std::max(dx, dy) + (std::sqrt(2.0) - 1.0) * std::min(dx, dy);
  };
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> g(n, inf);
  std::vector<std::int64_t> parent(n, -1);
  using Item = std::pair<double, std::size_t>;  // f, cell
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  g[grid.index(start)] = 0.0;
  open.emplace(octile(start), grid.index(start));
  const std::size_t goalIdx = grid.index(goal);
  int expanded = 0;
  while (!open.empty()) {
    const auto [f, idx] = open.top();
    open.pop();
    const planning::Cell c = grid.cellOf(idx);
    if (f > g[idx] + octile(c) + 1e-9) {
      continue;  // stale entry
    }
    ++expanded;
    if (idx == goalIdx) {
      break;
    }
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if (dx == 0 && dy == 0) {
          continue;
        }
        const planning::Cell q{c.x + dx, c.y + dy};
        if (grid.blocked(q)) {
          continue;
        }
        if (dx != 0 && dy != 0 && (grid.blocked({c.x + dx, c.y}) || grid.blocked({c.x, c.y + dy}))) {
          continue;  // no corner cutting, as planning::astar
        }
        const double len = (dx != 0 && dy != 0) ? std::sqrt(2.0) : 1.0;
        const double cand = g[idx] + len * (1.0 + weight * riskOf(q));
        const std::size_t qi = grid.index(q);
        if (cand < g[qi]) {
          g[qi] = cand;
          parent[qi] = static_cast<std::int64_t>(idx);
          open.emplace(cand + octile(q), qi);
        }
      }
    }
  }
  if (!std::isfinite(g[goalIdx])) {
    return unexpected("unreachable", "no path between the cells");
  }
  planning::GridPath out;
  out.cost = g[goalIdx];
  out.expanded = expanded;
  for (std::int64_t i = static_cast<std::int64_t>(goalIdx); i >= 0; i = parent[static_cast<std::size_t>(i)]) {
    out.cells.push_back(grid.cellOf(static_cast<std::size_t>(i)));
  }
  std::reverse(out.cells.begin(), out.cells.end());
  return out;
}

Expected<planning::Path> RiskAStarPlanner::plan(const planning::OccupancyGrid& grid, Pose2 from, Pose2 to) {
  const auto s = grid.cellAt(from.position());
  const auto t = grid.cellAt(to.position());
  if (!s || !t || grid.blocked(*s) || grid.blocked(*t)) {
    planning::AStarPlanner plain;
    return plain.plan(grid, from, to);
  }
  auto gp = riskAstar(grid, *s, *t, risk_, weight_);
  if (!gp) {
    return unexpected(gp.error());
  }
  return planning::cellsToPath(grid, gp->cells, from, to);
}

}  // namespace fleet::agent
