#include "fleet/planning/lane_map.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <queue>
#include <string>

namespace fleet::planning {

LaneMap LaneMap::derive(const OccupancyGrid& raw, const LaneParams& p) {
  LaneMap m;
  m.width_ = raw.width();
  m.height_ = raw.height();
  m.factor_ = std::max(1.0, p.wrong_way_factor);
  m.dir_.assign(raw.size(), LaneDir{});
  const int w = raw.width();
  const int h = raw.height();
  // Free runs through every cell along x and along y: length and first cell.
  std::vector<int> hrun(raw.size(), 0), hstart(raw.size(), 0), vrun(raw.size(), 0), vstart(raw.size(), 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w;) {
      if (raw.blocked({x, y})) {
        ++x;
        continue;
      }
      int e = x;
      while (e < w && raw.freeCell({e, y})) {
        ++e;
      }
      for (int k = x; k < e; ++k) {
        hrun[raw.index({k, y})] = e - x;
        hstart[raw.index({k, y})] = x;
      }
      x = e;
    }
  }
  for (int x = 0; x < w; ++x) {
    for (int y = 0; y < h;) {
      if (raw.blocked({x, y})) {
        ++y;
        continue;
      }
      int e = y;
      while (e < h && raw.freeCell({x, e})) {
        ++e;
      }
      for (int k = y; k < e; ++k) {
        vrun[raw.index({x, k})] = e - y;
        vstart[raw.index({x, k})] = y;
      }
      y = e;
    }
  }
  const int narrow = static_cast<int>(std::floor(p.max_aisle_width / raw.resolution() + 1e-9));
  // An aisle is named by the line of its near wall, so every segment of one aisle line (cut by
  // cross aisles) gets the same direction; neighbouring lines alternate, which gives every block
  // of shelves a loop around it.
  std::map<int, std::vector<std::size_t>> vertical;    // key: first free x across the aisle
  std::map<int, std::vector<std::size_t>> horizontal;  // key: first free y across the aisle
  for (std::size_t i = 0; i < raw.size(); ++i) {
    if (hrun[i] == 0) {
      continue;
    }
    if (hrun[i] < narrow && vrun[i] >= p.min_aspect * hrun[i]) {
      vertical[hstart[i]].push_back(i);
    } else if (vrun[i] < narrow && hrun[i] >= p.min_aspect * vrun[i]) {
      horizontal[vstart[i]].push_back(i);
    }
  }
  int k = 0;
  for (const auto& [key, cells] : vertical) {
    const auto d = static_cast<std::int8_t>(k++ % 2 == 0 ? 1 : -1);
    for (auto i : cells) {
      m.dir_[i] = {0, d};
    }
  }
  k = 0;
  for (const auto& [key, cells] : horizontal) {
    const auto d = static_cast<std::int8_t>(k++ % 2 == 0 ? 1 : -1);
    for (auto i : cells) {
      m.dir_[i] = {d, 0};
    }
  }
  // Wider corridors (the bands along the walls) get two lanes, keep right: heading +x the right
  // hand is -y, so the lower half runs +x and the upper half -x; heading +y the right hand is +x.
  // Robots meeting in a band pass side by side instead of nose to nose.
  const int twoLane = static_cast<int>(std::floor(p.max_two_lane_width / raw.resolution() + 1e-9));
  for (std::size_t i = 0; i < raw.size(); ++i) {
    if (hrun[i] == 0 || m.dir_[i] != LaneDir{}) {
      continue;
    }
    const Cell c = raw.cellOf(i);
    if (hrun[i] >= narrow && hrun[i] <= twoLane && vrun[i] >= p.min_aspect * hrun[i]) {
      const bool rightHalf = 2 * (c.x - hstart[i]) >= hrun[i];
      m.dir_[i] = {0, static_cast<std::int8_t>(rightHalf ? 1 : -1)};
    } else if (vrun[i] >= narrow && vrun[i] <= twoLane && hrun[i] >= p.min_aspect * vrun[i]) {
      const bool upperHalf = 2 * (c.y - vstart[i]) >= vrun[i];
      m.dir_[i] = {static_cast<std::int8_t>(upperHalf ? -1 : 1), 0};
    }
  }
  return m;
}

LaneDir LaneMap::at(Cell c) const {
  if (c.x < 0 || c.y < 0 || c.x >= width_ || c.y >= height_) {
    return {};
  }
  return dir_[static_cast<std::size_t>(c.y) * static_cast<std::size_t>(width_) +
              static_cast<std::size_t>(c.x)];
}

bool LaneMap::againstLane(Cell a, Cell b) const {
  const int dx = b.x - a.x;
  const int dy = b.y - a.y;
  for (const Cell c : {a, b}) {
    const LaneDir d = at(c);
    if ((d.dx != 0 && dx * d.dx < 0) || (d.dy != 0 && dy * d.dy < 0)) {
      return true;
    }
  }
  return false;
}

std::size_t LaneMap::oneWayCells() const {
  return static_cast<std::size_t>(
      std::count_if(dir_.begin(), dir_.end(), [](LaneDir d) { return d.dx != 0 || d.dy != 0; }));
}

Expected<std::vector<Cell>> laneAstar(const OccupancyGrid& grid, const LaneMap& lanes, Cell start, Cell goal,
                                      const CellCostFactor& factor) {
  if (!lanes.matches(grid)) {
    return unexpected("lane_map_mismatch", "lane map was derived from a map of another size");
  }
  if (grid.blocked(start) || grid.blocked(goal)) {
    return unexpected("unreachable", "start or goal cell is blocked or outside the map");
  }
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> g(grid.size(), inf);
  std::vector<std::int32_t> parent(grid.size(), -1);
  std::vector<std::uint8_t> closed(grid.size(), 0);
  auto h = [&](Cell c) {
    const double dx = std::abs(c.x - goal.x);
    const double dy = std::abs(c.y - goal.y);
    return std::max(dx, dy) - std::min(dx, dy) + std::min(dx, dy) * std::numbers::sqrt2;
  };
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  const std::size_t si = grid.index(start);
  const std::size_t gi = grid.index(goal);
  g[si] = 0.0;
  open.emplace(h(start), si);
  constexpr int mdx[8] = {1, 0, -1, 0, 1, -1, -1, 1};
  constexpr int mdy[8] = {0, -1, 0, 1, -1, -1, 1, 1};
  while (!open.empty()) {
    const auto [f, idx] = open.top();
    open.pop();
    if (closed[idx] != 0) {
      continue;
    }
    closed[idx] = 1;
    const Cell c = grid.cellOf(idx);
    if (idx == gi) {
      std::vector<Cell> cells;
      for (auto k = static_cast<std::int32_t>(idx); k >= 0; k = parent[static_cast<std::size_t>(k)]) {
        cells.push_back(grid.cellOf(static_cast<std::size_t>(k)));
      }
      std::reverse(cells.begin(), cells.end());
      return cells;
    }
    for (int m = 0; m < 8; ++m) {
      const Cell n{c.x + mdx[m], c.y + mdy[m]};
      if (grid.blocked(n)) {
        continue;
      }
      if (m >= 4 && (grid.blocked({c.x + mdx[m], c.y}) || grid.blocked({c.x, c.y + mdy[m]}))) {
        continue;  // no corner cutting
      }
      const double len = m < 4 ? 1.0 : std::numbers::sqrt2;
      const double extra = factor ? std::max(1.0, factor(n)) : 1.0;
      const double ng = g[idx] + len * extra * (lanes.againstLane(c, n) ? lanes.wrongWayFactor() : 1.0);
      const std::size_t ni = grid.index(n);
      if (ng < g[ni]) {
        g[ni] = ng;
        parent[ni] = static_cast<std::int32_t>(idx);
        open.emplace(ng + h(n), ni);
      }
    }
  }
  return unexpected("unreachable", "no path between (" + std::to_string(start.x) + ", " +
                                       std::to_string(start.y) + ") and (" + std::to_string(goal.x) + ", " +
                                       std::to_string(goal.y) + ")");
}

Expected<Path> LanePlanner::plan(const OccupancyGrid& grid, Pose2 from, Pose2 to) {
  const auto q = resolveQuery(grid, from, to);
  if (!q) {
    return unexpected(q.error());
  }
  if (!lanes_) {
    return unexpected("no_lanes", "lane planner has no lane map");
  }
  const auto cells = laneAstar(grid, *lanes_, q->start, q->goal, factor_);
  if (!cells) {
    return unexpected(cells.error());
  }
  return cellsToPath(grid, *cells, from, to);
}

}  // namespace fleet::planning
