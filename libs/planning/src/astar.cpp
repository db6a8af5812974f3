#include "fleet/planning/astar.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace fleet::planning {

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
  // Costs are a + b*sqrt(2) cells. They are kept in 32.32 fixed point (one cell = 2^32, a diagonal
  // = round(sqrt(2) * 2^32)), so sums are exact and order-independent: equal-length paths get
  // exactly equal keys without rounding tolerances. Distinct lengths below ~2,000 cells differ by
  // > 1e-4 cell while the fixed-point error is < 2,000 * 2^-33, so the order is that of the true
  // values. The octile heuristic in the same units stays exactly consistent (each move changes it
  // by at most its own cost).
  constexpr std::int64_t kOne = std::int64_t{1} << 32;
  const auto kDiag = static_cast<std::int64_t>(std::numbers::sqrt2 * static_cast<double>(kOne) + 0.5);
  // One 16-byte record per cell (g, parent, epoch stamp) so a relaxation touches one cache line.
  // stamp == 2*epoch: reached in this query; 2*epoch + 1: closed. Scratch is reused across calls on
  // the same thread: queries are many and small.
  struct Node {
    std::int64_t g;
    std::uint32_t parent;
    std::uint32_t stamp;
  };
  thread_local std::vector<Node> nodes;
  thread_local std::uint32_t epoch = 0;
  if (nodes.size() != grid.size()) {
    nodes.assign(grid.size(), Node{0, 0, 0});
    epoch = 0;
  }
  if (++epoch >= (std::uint32_t{1} << 31)) {
    std::fill(nodes.begin(), nodes.end(), Node{0, 0, 0});
    epoch = 1;
  }
  const std::uint32_t seen = 2 * epoch;
  const std::uint32_t closedMark = 2 * epoch + 1;
  // Ties on f prefer the deeper node (larger g), which cuts expansions in open areas. With a
  // consistent heuristic the first time a cell leaves the queue its g is optimal, so later copies
  // are skipped by the closed mark.
  struct Item {
    std::int64_t f;
    std::int64_t g;
    bool operator<(const Item& o) const { return f > o.f || (f == o.f && g < o.g); }
  };
  struct HeapItem {
    Item key;
    std::uint32_t idx;
  };
  auto worse = [](const HeapItem& x, const HeapItem& y) { return x.key < y.key; };
  thread_local std::vector<HeapItem> heap;
  heap.clear();
  const auto si = static_cast<std::uint32_t>(grid.index(start));
  const auto gi = static_cast<std::uint32_t>(grid.index(goal));
  nodes[si] = {0, si, seen};
  const std::size_t goalIdx = grid.index(goal);
  const bool eight = conn == Connectivity::Eight;
  auto hOf = [&](int x, int y, std::size_t idx) {
    const std::int64_t dx = std::abs(x - goal.x);
    const std::int64_t dy = std::abs(y - goal.y);
    std::int64_t hv =
        eight ? (std::max(dx, dy) - std::min(dx, dy)) * kOne + std::min(dx, dy) * kDiag : (dx + dy) * kOne;
    if (landmarks != nullptr) {
      // Truncation keeps the landmark bound admissible.
      hv =
          std::max(hv, static_cast<std::int64_t>(landmarks->bound(idx, goalIdx) * static_cast<double>(kOne)));
    }
    return hv;
  };
  // The landmark bound comes from floating-point fields, so it differs from the fixed-point sums by
  // a fraction of 2^-32 per diagonal: f is compared at 2^-16 cell (the low 16 bits rounded away), far
  // below the 1e-4-cell gap between distinct lengths but above that noise, so equal-length paths
  // still tie and the larger-g rule applies.
  auto quant = [](std::int64_t f) { return (f + (std::int64_t{1} << 15)) >> 16; };
  heap.push_back({{quant(hOf(start.x, start.y, si)), 0}, si});
  GridPath out;
  const int w = grid.width();
  const int h = grid.height();
  const auto W = static_cast<std::ptrdiff_t>(w);
  const std::uint8_t* occ = grid.cells().data();
  // Moves in neighbourOffsets order: E, S, W, N, SE, SW, NW, NE.
  const int mdx[8] = {1, 0, -1, 0, 1, -1, -1, 1};
  const int mdy[8] = {0, -1, 0, 1, -1, -1, 1, 1};
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), worse);
    const HeapItem it = heap.back();
    heap.pop_back();
    Node& cur = nodes[it.idx];
    if (cur.stamp == closedMark) {
      continue;
    }
    cur.stamp = closedMark;
    const std::int64_t gCur = cur.g;
    ++out.expanded;
    if (it.idx == gi) {
      int straight = 0, diagonal = 0;
      for (std::uint32_t k = gi;; k = nodes[k].parent) {
        const Cell c = grid.cellOf(k);
        if (!out.cells.empty()) {
          const Cell& nx = out.cells.back();
          (nx.x != c.x && nx.y != c.y ? diagonal : straight) += 1;
        }
        out.cells.push_back(c);
        if (k == si) {
          break;
        }
      }
      std::reverse(out.cells.begin(), out.cells.end());
      out.cost = static_cast<double>(straight) + static_cast<double>(diagonal) * std::numbers::sqrt2;
      return out;
    }
    // Diagonals need both orthogonal cells free (no corner cutting).
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
      const auto ni = static_cast<std::uint32_t>(i + mdx[k] + mdy[k] * W);
      const std::int64_t ng = gCur + (k < 4 ? kOne : kDiag);
      Node& nb = nodes[ni];
      const bool known = nb.stamp == seen || nb.stamp == closedMark;
      if (!known || ng < nb.g) {
        if (nb.stamp == closedMark) {
          continue;  // consistent heuristic: a closed cell already has its optimal g
        }
        nb = {ng, it.idx, seen};
        heap.push_back({{quant(ng + hOf(x + mdx[k], y + mdy[k], ni)), ng}, ni});
        std::push_heap(heap.begin(), heap.end(), worse);
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
