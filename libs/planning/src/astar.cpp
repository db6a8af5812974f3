#include "fleet/planning/astar.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <queue>

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
  // Costs are a + b*sqrt(2) cells. They are kept in fixed point with `frac` fractional bits (one
  // cell = 2^frac, a diagonal = round(sqrt(2) * 2^frac)), so sums are exact and order-independent:
  // equal-length paths get exactly equal keys without rounding tolerances. The octile heuristic in
  // the same units stays exactly consistent (each move changes it by at most its own cost). frac
  // is 32 unless the grid is so large that a path through every cell (< 1.5 * cells) would not fit
  // in the 52 bits of g kept per cell; the fixed-point error (< diagonals * 2^-(frac+1)) is far
  // below the gap between distinct lengths of realistic paths (~1e-4 cell for 2,000 diagonals).
  int cellBits = 0;
  while ((std::uint64_t{3} * grid.size()) >> cellBits != 0) {
    ++cellBits;
  }
  const int frac = std::min(32, 51 - cellBits);
  const std::int64_t kOne = std::int64_t{1} << frac;
  const auto kDiag = static_cast<std::int64_t>(std::numbers::sqrt2 * static_cast<double>(kOne) + 0.5);
  // One 8-byte word per cell: a 12-bit query stamp above a 52-bit g.
  // stamp == 2*epoch: reached in this query; 2*epoch + 1: closed. No parent is stored: with exact
  // costs the path is recovered by stepping back to a neighbour whose g plus the move cost equals
  // the current g. Scratch is reused across calls on the same thread: queries are many and small.
  constexpr int kStampShift = 52;
  constexpr std::uint64_t kGMask = (std::uint64_t{1} << kStampShift) - 1;
  thread_local std::vector<std::uint64_t> nodes;
  thread_local std::uint32_t epoch = 0;
  if (nodes.size() != grid.size()) {
    nodes.assign(grid.size(), 0);
    epoch = 0;
  }
  if (++epoch >= (std::uint32_t{1} << 11)) {
    std::fill(nodes.begin(), nodes.end(), 0);
    epoch = 1;
  }
  const std::uint64_t seen = std::uint64_t{2} * epoch;
  const std::uint64_t closedMark = seen + 1;
  auto stampOf = [&](std::size_t k) { return nodes[k] >> kStampShift; };
  auto gOf = [&](std::size_t k) { return static_cast<std::int64_t>(nodes[k] & kGMask); };
  auto setNode = [&](std::size_t k, std::int64_t g, std::uint64_t st) {
    nodes[k] = (st << kStampShift) | static_cast<std::uint64_t>(g);
  };
  // Heap key (one 64-bit compare): f rounded to 2^-16 cell in the high 40 bits, then the
  // complement of g in 2^-8 cell (24 bits, saturating beyond 65,536 cells) so that ties on f go to
  // the deeper node, which cuts expansions in open areas. With a consistent heuristic the first
  // time a cell leaves the queue its g is optimal; later copies are skipped by the closed mark. The
  // landmark bound comes from floating-point fields and differs from the fixed-point sums by a
  // fraction of 2^-frac per move: rounding f to 2^-16 keeps equal-length paths tied while distinct
  // lengths stay > 1e-4 cell apart.
  struct HeapItem {
    std::uint64_t key;
    std::uint32_t idx;
  };
  auto worse = [](const HeapItem& x, const HeapItem& y) { return x.key > y.key; };
  const int fShift = frac - 16;
  const int gShift = frac - 8;
  auto item = [&](std::int64_t f, std::int64_t g, std::uint32_t idx) {
    const auto fq = static_cast<std::uint64_t>((f + (std::int64_t{1} << (fShift - 1))) >> fShift);
    const auto gq = std::min<std::uint64_t>(static_cast<std::uint64_t>(g >> gShift), 0xFFFFFF);
    return HeapItem{(fq << 24) | (0xFFFFFF - gq), idx};
  };
  thread_local std::vector<HeapItem> heap;
  heap.clear();
  const auto si = static_cast<std::uint32_t>(grid.index(start));
  const auto gi = static_cast<std::uint32_t>(grid.index(goal));
  setNode(si, 0, seen);
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
  heap.push_back(item(hOf(start.x, start.y, si), 0, si));
  GridPath out;
  const int w = grid.width();
  const int h = grid.height();
  const auto W = static_cast<std::ptrdiff_t>(w);
  const std::uint8_t* occ = grid.cells().data();
  // Moves in neighbourOffsets order: E, S, W, N, SE, SW, NW, NE.
  const int mdx[8] = {1, 0, -1, 0, 1, -1, -1, 1};
  const int mdy[8] = {0, -1, 0, 1, -1, -1, 1, 1};
  auto allowedMoves = [&](std::ptrdiff_t i, int x, int y, bool* ok) {
    // Diagonals need both orthogonal cells free (no corner cutting).
    const bool e = x + 1 < w && occ[i + 1] == 0;
    const bool s = y > 0 && occ[i - W] == 0;
    const bool wst = x > 0 && occ[i - 1] == 0;
    const bool n = y + 1 < h && occ[i + W] == 0;
    ok[0] = e;
    ok[1] = s;
    ok[2] = wst;
    ok[3] = n;
    ok[4] = eight && e && s && occ[i - W + 1] == 0;
    ok[5] = eight && wst && s && occ[i - W - 1] == 0;
    ok[6] = eight && wst && n && occ[i + W - 1] == 0;
    ok[7] = eight && e && n && occ[i + W + 1] == 0;
  };
  const int moves = eight ? 8 : 4;
  while (!heap.empty()) {
    std::pop_heap(heap.begin(), heap.end(), worse);
    const std::uint32_t idx = heap.back().idx;
    heap.pop_back();
    if (stampOf(idx) == closedMark) {
      continue;
    }
    const std::int64_t gCur = gOf(idx);
    setNode(idx, gCur, closedMark);
    ++out.expanded;
    const int x = static_cast<int>(idx % static_cast<std::uint32_t>(w));
    const int y = static_cast<int>(idx / static_cast<std::uint32_t>(w));
    const auto i = static_cast<std::ptrdiff_t>(idx);
    bool ok[8];
    if (idx == gi) {
      // Walk back along exact predecessors (moves are symmetric, so the allowed moves out of a
      // cell are the allowed moves into it). Closed cells' g are optimal; a reached cell's g is
      // the cost of a real path through a closed parent, so the walk always continues.
      int straight = 0, diagonal = 0;
      Cell c{x, y};
      std::size_t k = idx;
      out.cells.push_back(c);
      while (k != si) {
        allowedMoves(static_cast<std::ptrdiff_t>(k), c.x, c.y, ok);
        const std::int64_t gk = gOf(k);
        bool stepped = false;
        for (int m = 0; m < moves && !stepped; ++m) {
          if (!ok[m]) {
            continue;
          }
          const auto pk = static_cast<std::size_t>(static_cast<std::ptrdiff_t>(k) + mdx[m] + mdy[m] * W);
          const std::uint64_t st = stampOf(pk);
          if ((st == seen || st == closedMark) && gOf(pk) + (m < 4 ? kOne : kDiag) == gk) {
            k = pk;
            c = {c.x + mdx[m], c.y + mdy[m]};
            (m < 4 ? straight : diagonal) += 1;
            stepped = true;
          }
        }
        out.cells.push_back(c);
        if (!stepped) {
          return unexpected("internal", "A* path reconstruction failed");
        }
      }
      std::reverse(out.cells.begin(), out.cells.end());
      out.cost = static_cast<double>(straight) + static_cast<double>(diagonal) * std::numbers::sqrt2;
      return out;
    }
    allowedMoves(i, x, y, ok);
    for (int k = 0; k < moves; ++k) {
      if (!ok[k]) {
        continue;
      }
      const auto ni = static_cast<std::uint32_t>(i + mdx[k] + mdy[k] * W);
      const std::int64_t ng = gCur + (k < 4 ? kOne : kDiag);
      const std::uint64_t st = stampOf(ni);
      if (st == closedMark || (st == seen && gOf(ni) <= ng)) {
        continue;  // closed: optimal already (consistent heuristic); or no improvement
      }
      setNode(ni, ng, seen);
      heap.push_back(item(ng + hOf(x + mdx[k], y + mdy[k], ni), ng, ni));
      std::push_heap(heap.begin(), heap.end(), worse);
    }
  }
  return unexpected("unreachable", "no path between (" + std::to_string(start.x) + ", " +
                                       std::to_string(start.y) + ") and (" + std::to_string(goal.x) + ", " +
                                       std::to_string(goal.y) + ")");
}

Expected<GridPath> astar(const OccupancyGrid& grid, Cell start, Cell goal, const CostLayers& layers) {
  if (layers.empty()) {
    return astar(grid, start, goal, Connectivity::Eight);
  }
  if (grid.blocked(start) || grid.blocked(goal)) {
    return unexpected("unreachable", "start or goal cell is blocked or outside the map");
  }
  // Costs are products of arbitrary factors, so the fixed-point keys of the plain search do not
  // apply: doubles, a binary heap with lazy deletion, and parents kept per cell.
  const std::size_t n = grid.size();
  auto octile = [&](Cell c) {
    const double dx = std::abs(c.x - goal.x);
    const double dy = std::abs(c.y - goal.y);
    return std::max(dx, dy) + (std::numbers::sqrt2 - 1.0) * std::min(dx, dy);
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
    const Cell c = grid.cellOf(idx);
    if (f > g[idx] + octile(c) + 1e-9) {
      continue;  // superseded by a cheaper entry
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
        const Cell q{c.x + dx, c.y + dy};
        if (grid.blocked(q)) {
          continue;
        }
        if (dx != 0 && dy != 0 && (grid.blocked({c.x + dx, c.y}) || grid.blocked({c.x, c.y + dy}))) {
          continue;  // no corner cutting
        }
        double factor = 1.0;
        for (const auto& layer : layers) {
          factor *= std::max(1.0, layer->factor(c, q));  // NaN -> 1 too (max keeps the first)
        }
        const double len = (dx != 0 && dy != 0) ? std::numbers::sqrt2 : 1.0;
        const double cand = g[idx] + len * factor;
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
  GridPath out;
  out.cost = g[goalIdx];
  out.expanded = expanded;
  for (auto i = static_cast<std::int64_t>(goalIdx); i >= 0; i = parent[static_cast<std::size_t>(i)]) {
    out.cells.push_back(grid.cellOf(static_cast<std::size_t>(i)));
  }
  std::reverse(out.cells.begin(), out.cells.end());
  return out;
}

Expected<Path> AStarPlanner::plan(const OccupancyGrid& grid, Pose2 from, Pose2 to) {
  const auto q = resolveQuery(grid, from, to);
  if (!q) {
    return unexpected(q.error());
  }
  const auto gp = layers_.empty() ? astar(grid, q->start, q->goal, conn_, landmarks_.get())
                                  : astar(grid, q->start, q->goal, layers_);
  if (!gp) {
    return unexpected(gp.error());
  }
  return cellsToPath(grid, gp->cells, from, to);
}

}  // namespace fleet::planning
