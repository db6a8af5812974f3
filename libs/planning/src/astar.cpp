#include "fleet/planning/astar.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <queue>

namespace fleet::planning {

namespace {

double heuristic(Cell a, Cell b, Connectivity conn) {
  const double dx = std::abs(a.x - b.x);
  const double dy = std::abs(a.y - b.y);
  if (conn == Connectivity::Four) {
    return dx + dy;
  }
  return std::max(dx, dy) + (std::numbers::sqrt2 - 1.0) * std::min(dx, dy);
}

}  // namespace

LandmarkHeuristic LandmarkHeuristic::build(const OccupancyGrid& grid, Connectivity conn, int count) {
  LandmarkHeuristic lh;
  lh.conn_ = conn;
  lh.width_ = grid.width();
  lh.height_ = grid.height();
  // Landmarks go into the largest connected region (4-connected regions: without corner cutting a
  // diagonal move needs both orthogonal cells free, so both move sets have the same regions).
  std::size_t seed = grid.size();
  {
    std::vector<std::uint8_t> seen(grid.size(), 0);
    std::vector<std::size_t> queue;
    std::size_t bestSize = 0;
    for (std::size_t i = 0; i < grid.size(); ++i) {
      if (grid.cells()[i] != 0 || seen[i] != 0) {
        continue;
      }
      queue.assign(1, i);
      seen[i] = 1;
      for (std::size_t head = 0; head < queue.size(); ++head) {
        const Cell c = grid.cellOf(queue[head]);
        for (const Cell& o : neighbourOffsets(Connectivity::Four)) {
          const Cell n{c.x + o.x, c.y + o.y};
          if (grid.freeCell(n) && seen[grid.index(n)] == 0) {
            seen[grid.index(n)] = 1;
            queue.push_back(grid.index(n));
          }
        }
      }
      if (queue.size() > bestSize) {
        bestSize = queue.size();
        seed = i;
      }
    }
  }
  if (seed == grid.size() || count <= 0) {
    return lh;
  }
  std::vector<DistanceField> fields;
  // Farthest-first: each new landmark maximises its distance to the nearest landmark chosen so far
  // (the first one: to an arbitrary free cell).
  std::vector<double> minDist = computeDistanceField(grid, grid.cellOf(seed), conn).cost;
  for (int l = 0; l < count; ++l) {
    std::size_t best = grid.size();
    double bestD = -1.0;
    for (std::size_t i = 0; i < minDist.size(); ++i) {
      if (std::isfinite(minDist[i]) && minDist[i] > bestD) {
        bestD = minDist[i];
        best = i;
      }
    }
    if (best == grid.size() || bestD <= 0.0) {
      break;
    }
    lh.landmarks_.push_back(grid.cellOf(best));
    fields.push_back(computeDistanceField(grid, grid.cellOf(best), conn));
    for (std::size_t i = 0; i < minDist.size(); ++i) {
      minDist[i] = std::min(minDist[i], fields.back().cost[i]);
    }
  }
  lh.count_ = static_cast<int>(fields.size());
  lh.dist_.resize(grid.size() * fields.size());
  for (std::size_t i = 0; i < grid.size(); ++i) {
    for (std::size_t l = 0; l < fields.size(); ++l) {
      lh.dist_[i * fields.size() + l] = fields[l].cost[i];
    }
  }
  return lh;
}

double LandmarkHeuristic::bound(std::size_t cell, std::size_t goal) const {
  const auto k = static_cast<std::size_t>(count_);
  const double* a = dist_.data() + cell * k;
  const double* b = dist_.data() + goal * k;
  double h = 0.0;
  for (std::size_t l = 0; l < k; ++l) {
    // Cells of another component than the landmark hold +inf: that landmark says nothing.
    if (std::isfinite(a[l]) && std::isfinite(b[l])) {
      h = std::max(h, std::abs(a[l] - b[l]));
    }
  }
  return h;
}

Expected<GridPath> astar(const OccupancyGrid& grid, Cell start, Cell goal, Connectivity conn,
                         const LandmarkHeuristic* landmarks) {
  if (landmarks != nullptr &&
      (landmarks->connectivity() != conn || landmarks->count() == 0 || !landmarks->matches(grid))) {
    landmarks = nullptr;  // built for another move set: its bounds would not be admissible
  }
  if (grid.blocked(start) || grid.blocked(goal)) {
    return unexpected("unreachable", "start or goal cell is blocked or outside the map");
  }
  constexpr double inf = std::numeric_limits<double>::infinity();
  // Scratch buffers are reused across calls on the same thread: queries are many and small.
  thread_local std::vector<double> g;
  thread_local std::vector<std::uint32_t> parent;
  thread_local std::vector<std::uint32_t> stamp;
  thread_local std::vector<std::uint32_t> closed;
  thread_local std::uint32_t epoch = 0;
  if (g.size() != grid.size()) {
    g.assign(grid.size(), inf);
    parent.assign(grid.size(), 0);
    stamp.assign(grid.size(), 0);
    closed.assign(grid.size(), 0);
    epoch = 0;
  }
  if (++epoch == 0) {
    std::fill(stamp.begin(), stamp.end(), 0);
    std::fill(closed.begin(), closed.end(), 0);
    epoch = 1;
  }
  auto gOf = [&](std::size_t i) { return stamp[i] == epoch ? g[i] : inf; };
  // f is quantised to 1e-9 cells so that paths of equal length compare equal despite rounding;
  // among them the deeper node (larger g) goes first, which cuts expansions in open areas.
  // With a consistent heuristic the first time a cell leaves the queue its g is optimal, so later
  // copies are skipped by the closed mark; g in the item only breaks ties (16-byte items).
  struct Item {
    std::int64_t fq;
    float g;
    std::uint32_t idx;
    bool operator>(const Item& o) const { return fq > o.fq || (fq == o.fq && g < o.g); }
  };
  auto quant = [](double f) { return static_cast<std::int64_t>(std::llround(f * 1e9)); };
  std::vector<Item> heapStore;
  heapStore.reserve(4096);
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open(std::greater<>{}, std::move(heapStore));
  const auto si = static_cast<std::uint32_t>(grid.index(start));
  const auto gi = static_cast<std::uint32_t>(grid.index(goal));
  g[si] = 0.0;
  stamp[si] = epoch;
  parent[si] = si;
  const std::size_t goalIdx = grid.index(goal);
  auto hOf = [&](Cell c, std::size_t idx) {
    const double oct = heuristic(c, goal, conn);
    return landmarks != nullptr ? std::max(oct, landmarks->bound(idx, goalIdx)) : oct;
  };
  open.push({quant(hOf(start, si)), 0.0F, si});
  GridPath out;
  const auto& offs = neighbourOffsets(conn);
  const bool eight = conn == Connectivity::Eight;
  const int w = grid.width();
  const int h = grid.height();
  const auto W = static_cast<std::ptrdiff_t>(w);
  const std::uint8_t* occ = grid.cells().data();
  while (!open.empty()) {
    const Item it = open.top();
    open.pop();
    if (closed[it.idx] == epoch) {
      continue;
    }
    closed[it.idx] = epoch;
    const double gCur = g[it.idx];
    ++out.expanded;
    if (it.idx == gi) {
      out.cost = gCur;
      for (std::uint32_t k = gi;; k = parent[k]) {
        out.cells.push_back(grid.cellOf(k));
        if (k == si) {
          break;
        }
      }
      std::reverse(out.cells.begin(), out.cells.end());
      return out;
    }
    // Neighbour moves on the raw cell array, in neighbourOffsets order; diagonals need both
    // orthogonal cells free (no corner cutting).
    const int x = static_cast<int>(it.idx % static_cast<std::uint32_t>(w));
    const int y = static_cast<int>(it.idx / static_cast<std::uint32_t>(w));
    const auto i = static_cast<std::ptrdiff_t>(it.idx);
    const bool e = x + 1 < w && occ[i + 1] == 0;
    const bool s = y > 0 && occ[i - W] == 0;
    const bool wst = x > 0 && occ[i - 1] == 0;
    const bool n = y + 1 < h && occ[i + W] == 0;
    const bool ok[8] = {e,
                        s,
                        wst,
                        n,
                        eight && e && s && occ[i - W + 1] == 0,
                        eight && wst && s && occ[i - W - 1] == 0,
                        eight && wst && n && occ[i + W - 1] == 0,
                        eight && e && n && occ[i + W + 1] == 0};
    for (int k = 0; k < (eight ? 8 : 4); ++k) {
      if (!ok[k]) {
        continue;
      }
      const Cell o = offs[static_cast<std::size_t>(k)];
      const auto ni = static_cast<std::uint32_t>(i + o.x + o.y * W);
      const double ng = gCur + (k < 4 ? 1.0 : std::numbers::sqrt2);
      if (ng < gOf(ni)) {
        g[ni] = ng;
        stamp[ni] = epoch;
        parent[ni] = it.idx;
        open.push({quant(ng + hOf({x + o.x, y + o.y}, ni)), static_cast<float>(ng), ni});
      }
    }
  }
  return unexpected("unreachable", "no path between (" + std::to_string(start.x) + ", " +
                                       std::to_string(start.y) + ") and (" + std::to_string(goal.x) + ", " +
                                       std::to_string(goal.y) + ")");
}

Expected<Path> AStarPlanner::plan(const OccupancyGrid& grid, Pose2 from, Pose2 to) {
  const auto q = resolveQuery(grid, from, to);
  if (!q) {
    return unexpected(q.error());
  }
  const auto gp = astar(grid, q->start, q->goal, conn_, landmarks_.get());
  if (!gp) {
    return unexpected(gp.error());
  }
  return cellsToPath(grid, gp->cells, from, to);
}

}  // namespace fleet::planning
