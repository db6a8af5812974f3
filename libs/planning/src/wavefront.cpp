#include "fleet/planning/wavefront.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <numbers>
#include <queue>

namespace fleet::planning {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}

const std::vector<Cell>& neighbourOffsets(Connectivity conn) {
  static const std::vector<Cell> four{{1, 0}, {0, -1}, {-1, 0}, {0, 1}};
  static const std::vector<Cell> eight{{1, 0}, {0, -1}, {-1, 0}, {0, 1}, {1, -1}, {-1, -1}, {-1, 1}, {1, 1}};
  return conn == Connectivity::Four ? four : eight;
}

double moveCost(Cell o) {
  return (o.x != 0 && o.y != 0) ? std::numbers::sqrt2 : 1.0;
}

bool moveAllowed(const OccupancyGrid& grid, Cell from, Cell o) {
  const Cell to{from.x + o.x, from.y + o.y};
  if (grid.blocked(to)) {
    return false;
  }
  if (o.x != 0 && o.y != 0) {
    return grid.freeCell({from.x + o.x, from.y}) && grid.freeCell({from.x, from.y + o.y});
  }
  return true;
}

double DistanceField::at(Cell c) const {
  if (c.x < 0 || c.y < 0 || c.x >= width || c.y >= height) {
    return kInf;
  }
  return cost[static_cast<std::size_t>(c.y) * static_cast<std::size_t>(width) +
              static_cast<std::size_t>(c.x)];
}

bool DistanceField::reachable(Cell c) const {
  return std::isfinite(at(c));
}

DistanceField computeDistanceField(const OccupancyGrid& grid, Cell goal, Connectivity conn) {
  DistanceField f;
  f.width = grid.width();
  f.height = grid.height();
  f.goal = goal;
  f.conn = conn;
  f.cost.assign(grid.size(), kInf);
  if (grid.blocked(goal)) {
    return f;
  }
  // Work on a copy padded with one blocked cell all around: the inner loops then need neither
  // bounds checks nor index divisions.
  const int w = grid.width();
  const int h = grid.height();
  const auto P = static_cast<std::ptrdiff_t>(w) + 2;
  const auto padded = static_cast<std::size_t>(P) * static_cast<std::size_t>(h + 2);
  std::vector<std::uint8_t> occ(padded, 1);
  for (int y = 0; y < h; ++y) {
    std::copy_n(grid.cells().begin() + static_cast<std::ptrdiff_t>(y) * w, w, occ.begin() + (y + 1) * P + 1);
  }
  std::vector<double> cost(padded, kInf);
  const auto start = static_cast<std::uint32_t>((goal.y + 1) * P + goal.x + 1);
  // The seed's pseudocode never sets d(B) = 0, re-queues B and does not exclude obstacles in
  // check(); all three are fixed here.
  cost[start] = 0.0;
  if (conn == Connectivity::Four) {
    std::vector<std::uint32_t> queue;
    queue.reserve(grid.size());
    queue.push_back(start);
    const std::ptrdiff_t steps[4] = {1, -P, -1, P};
    for (std::size_t head = 0; head < queue.size(); ++head) {
      const auto i = static_cast<std::ptrdiff_t>(queue[head]);
      const double next = cost[static_cast<std::size_t>(i)] + 1.0;
      for (const std::ptrdiff_t st : steps) {
        const auto ni = static_cast<std::size_t>(i + st);
        if (occ[ni] == 0 && cost[ni] == kInf) {
          cost[ni] = next;
          queue.push_back(static_cast<std::uint32_t>(ni));
        }
      }
    }
  } else {
    // Dijkstra with a bucket queue of width 1 (Dinitz): every move costs at least 1, so relaxing a
    // cell of bucket b only reaches buckets > b and cells inside one bucket can be settled in any
    // order. Moves cost at most sqrt(2) < 2, so only buckets b+1 and b+2 receive cells while b is
    // settled: a ring of three reusable buckets suffices.
    std::array<std::vector<std::uint32_t>, 3> ring;
    for (auto& r : ring) {
      r.reserve(1024);
    }
    std::vector<std::uint8_t> done(padded, 0);
    ring[0].push_back(start);
    auto relax = [&](std::ptrdiff_t ni, double nd) {
      const auto u = static_cast<std::size_t>(ni);
      if (nd < cost[u]) {
        cost[u] = nd;
        ring[static_cast<std::size_t>(nd) % 3].push_back(static_cast<std::uint32_t>(u));
      }
    };
    constexpr double diag = std::numbers::sqrt2;
    for (std::size_t b = 0; !(ring[0].empty() && ring[1].empty() && ring[2].empty()); ++b) {
      auto& bucket = ring[b % 3];
      for (std::size_t k = 0; k < bucket.size(); ++k) {
        const std::size_t idx = bucket[k];
        if (done[idx] != 0 || static_cast<std::size_t>(cost[idx]) != b) {
          continue;  // already settled, or improved into an earlier bucket
        }
        done[idx] = 1;
        const double d = cost[idx];
        const auto i = static_cast<std::ptrdiff_t>(idx);
        const bool e = occ[static_cast<std::size_t>(i + 1)] == 0;
        const bool s = occ[static_cast<std::size_t>(i - P)] == 0;
        const bool wst = occ[static_cast<std::size_t>(i - 1)] == 0;
        const bool n = occ[static_cast<std::size_t>(i + P)] == 0;
        if (e) {
          relax(i + 1, d + 1.0);
        }
        if (s) {
          relax(i - P, d + 1.0);
        }
        if (wst) {
          relax(i - 1, d + 1.0);
        }
        if (n) {
          relax(i + P, d + 1.0);
        }
        if (e && s && occ[static_cast<std::size_t>(i - P + 1)] == 0) {
          relax(i - P + 1, d + diag);
        }
        if (wst && s && occ[static_cast<std::size_t>(i - P - 1)] == 0) {
          relax(i - P - 1, d + diag);
        }
        if (wst && n && occ[static_cast<std::size_t>(i + P - 1)] == 0) {
          relax(i + P - 1, d + diag);
        }
        if (e && n && occ[static_cast<std::size_t>(i + P + 1)] == 0) {
          relax(i + P + 1, d + diag);
        }
      }
      bucket.clear();
    }
  }
  for (int y = 0; y < h; ++y) {
    std::copy_n(cost.begin() + (y + 1) * P + 1, w, f.cost.begin() + static_cast<std::ptrdiff_t>(y) * w);
  }
  return f;
}

namespace {

// A neighbour on a steepest-descent step: its cost is lower by exactly the move cost.
bool isDescent(const OccupancyGrid& grid, const DistanceField& field, Cell c, Cell o) {
  if (!moveAllowed(grid, c, o)) {
    return false;
  }
  const double dn = field.at({c.x + o.x, c.y + o.y});
  return std::abs(dn + moveCost(o) - field.at(c)) <= 1e-9 * (1.0 + field.at(c));
}

}  // namespace

Expected<std::vector<Cell>> descend(const OccupancyGrid& grid, const DistanceField& field, Cell start) {
  if (!field.reachable(start)) {
    return unexpected("unreachable", "no path: the goal cannot be reached from (" + std::to_string(start.x) +
                                         ", " + std::to_string(start.y) + ")");
  }
  std::vector<Cell> cells{start};
  Cell cur = start;
  while (!(cur == field.goal)) {
    bool moved = false;
    for (const Cell& o : neighbourOffsets(field.conn)) {
      if (isDescent(grid, field, cur, o)) {
        cur = {cur.x + o.x, cur.y + o.y};
        cells.push_back(cur);
        moved = true;
        break;
      }
    }
    if (!moved) {
      return unexpected("no_admissible_neighbour",
                        "distance field does not match the grid (no descent step)");
    }
  }
  return cells;
}

Expected<Path> WavefrontPlanner::plan(const OccupancyGrid& grid, Pose2 from, Pose2 to) {
  const auto q = resolveQuery(grid, from, to);
  if (!q) {
    return unexpected(q.error());
  }
  const DistanceField field = computeDistanceField(grid, q->goal, conn_);
  const auto cells = descend(grid, field, q->start);
  if (!cells) {
    return unexpected(cells.error());
  }
  return cellsToPath(grid, *cells, from, to);
}

Expected<Execution> executeWaitOrDetour(const OccupancyGrid& grid, const DistanceField& field, Cell start,
                                        const CollisionPredictor& predicted, const WaitOrDetourOptions& opt) {
  if (!field.reachable(start)) {
    return unexpected("unreachable", "no path: the goal cannot be reached from the start cell");
  }
  Execution ex;
  ex.cells.push_back(start);
  std::vector<std::uint8_t> visited(grid.size(), 0);
  visited[grid.index(start)] = 1;
  Cell cur = start;
  int consecutiveWaits = 0;
  const auto& offs = neighbourOffsets(field.conn);
  auto sensed = [&](Cell c, double t) {
    const double dx = c.x - cur.x, dy = c.y - cur.y;
    return std::hypot(dx, dy) <= opt.scanRadius && predicted && predicted(c, t);
  };
  for (int step = 0; !(cur == field.goal); ++step) {
    if (step >= opt.maxSteps) {
      return unexpected("step_limit", "goal not reached within " + std::to_string(opt.maxSteps) + " steps");
    }
    // next(x, y): a steepest-descent neighbour, preferring cells not yet visited so that a detour
    // does not lead straight back (deterministic: first in neighbour order).
    Cell nextOff{0, 0};
    bool found = false;
    for (int pass = 0; pass < 2 && !found; ++pass) {
      for (const Cell& o : offs) {
        const Cell n{cur.x + o.x, cur.y + o.y};
        if (isDescent(grid, field, cur, o) && (pass == 1 || visited[grid.index(n)] == 0)) {
          nextOff = o;
          found = true;
          break;
        }
      }
    }
    if (!found) {
      return unexpected("no_admissible_neighbour", "no descent step from the current cell");
    }
    const Cell next{cur.x + nextOff.x, cur.y + nextOff.y};
    Cell chosen = next;
    double stepCost = moveCost(nextOff);
    if (sensed(next, ex.time + stepCost)) {
      const double phi1 = field.at(cur) + opt.waitCost;
      // change(x, y): the admissible neighbour with minimum d.
      double phi2 = std::numeric_limits<double>::infinity();
      Cell best{0, 0};
      for (const Cell& o : offs) {
        const Cell n{cur.x + o.x, cur.y + o.y};
        if (!moveAllowed(grid, cur, o) || visited[grid.index(n)] != 0 || !field.reachable(n) ||
            sensed(n, ex.time + moveCost(o))) {
          continue;
        }
        if (field.at(n) < phi2) {
          phi2 = field.at(n);
          best = o;
        }
      }
      const double detourCost = opt.seedComparison ? phi2 : phi2 + moveCost(best);
      if (phi1 <= detourCost) {
        ++ex.waits;
        ex.time += opt.waitCost;
        if (++consecutiveWaits > opt.maxConsecutiveWaits) {
          return unexpected("no_admissible_neighbour",
                            "the next cell stays blocked by a moving obstacle and no detour is admissible");
        }
        continue;
      }
      ++ex.detours;
      chosen = {cur.x + best.x, cur.y + best.y};
      stepCost = moveCost(best);
    }
    consecutiveWaits = 0;
    cur = chosen;
    visited[grid.index(cur)] = 1;
    ex.cells.push_back(cur);
    ++ex.moves;
    ex.time += stepCost;
  }
  return ex;
}

}  // namespace fleet::planning
