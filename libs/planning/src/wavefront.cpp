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

// Exact octile Dijkstra with two FIFO queues, one per move cost (1 and sqrt 2). Cells leave the
// queues in non-decreasing cost, so every key pushed with cost d + c is >= the keys already in the
// queue for c: each queue stays sorted and the smaller of the two heads is the global minimum.
// A cell reached by a straight move from the current minimum d is final at once (a cheaper
// diagonal arrival would need a parent below d - 0.41, already expanded), so straight-queue
// entries are never stale and their key is simply the cell's cost. A diagonal entry is stale only
// when a straight move later improved the cell; reading its key from the cell's cost then yields
// that final value, which is never below the straight queue's head, so taking it first (on a tie)
// is harmless and the cell's second entry is skipped. Queues therefore hold 4-byte cell indices.
// One padded cost array carries all state: +inf unreached, >= 0 tentative, sign bit set once
// expanded (-d, exact; -0 for the goal), -inf blocked (and the one-cell border), so relaxations
// "nd < cost" fail on expanded and blocked cells without further tests and are branch-free
// (conditional store plus conditional tail advance). The extra slot at the end holds +inf and is
// the queues' end sentinel. Each cell enters each queue at most once (a straight arrival is
// final; a second diagonal arrival would need a parent cheaper than the first one's, but parents
// are expanded in non-decreasing cost), so padded + 2 slots hold every entry, the sentinel and the
// speculative write past the tail.
void octileField(const OccupancyGrid& grid, std::uint32_t start, std::vector<double>& out) {
  const int w = grid.width();
  const int h = grid.height();
  const auto P = static_cast<std::ptrdiff_t>(w) + 2;
  const auto padded = static_cast<std::size_t>(P) * static_cast<std::size_t>(h + 2);
  constexpr double kBlocked = -std::numeric_limits<double>::infinity();
  thread_local std::vector<double> cost;
  thread_local std::vector<std::uint32_t> q1;
  thread_local std::vector<std::uint32_t> q2;
  cost.resize(padded + 1);
  cost[padded] = kInf;
  const auto sentinel = static_cast<std::uint32_t>(padded);
  // Only the border needs setting here: the fill below writes every interior cell.
  std::fill_n(cost.begin(), P, kBlocked);
  std::fill_n(cost.begin() + static_cast<std::ptrdiff_t>(padded) - P, P, kBlocked);
  for (int y = 1; y <= h; ++y) {
    cost[static_cast<std::size_t>(y * P)] = kBlocked;
    cost[static_cast<std::size_t>(y * P + P - 1)] = kBlocked;
  }
  if (q1.size() < padded + 2) {
    q1.resize(padded + 2);
    q2.resize(padded + 2);
  }
  const std::uint8_t* occ = grid.cells().data();
  for (int y = 0; y < h; ++y) {
    double* row = cost.data() + (y + 1) * P + 1;
    const std::uint8_t* orow = occ + static_cast<std::ptrdiff_t>(y) * w;
    for (int x = 0; x < w; ++x) {
      row[x] = orow[x] == 0 ? kInf : kBlocked;
    }
  }
  double* c = cost.data();
  std::uint32_t* a = q1.data();
  std::uint32_t* b = q2.data();
  std::size_t ha = 0, ta = 0, hb = 0, tb = 0;
  c[start] = 0.0;
  a[ta++] = start;
  a[ta] = sentinel;
  b[tb] = sentinel;
  constexpr double diag = std::numbers::sqrt2;
  for (;;) {
    const double ka = c[a[ha]];
    const double kb = c[b[hb]];
    if (ka == kInf && kb == kInf) {
      break;
    }
    // A branch, not a select: the queue heads then do not wait for this comparison.
    std::uint32_t idx;
    double d;
    if (ka <= kb) {
      idx = a[ha++];
      d = ka;
    } else {
      idx = b[hb++];
      d = kb;
    }
    if (std::signbit(d)) {
      continue;  // already expanded
    }
    const auto i = static_cast<std::ptrdiff_t>(idx);
    c[i] = -d;
    const double ce = c[i + 1], cs = c[i - P], cw = c[i - 1], cn = c[i + P];
    const double cse = c[i - P + 1], csw = c[i - P - 1], cnw = c[i + P - 1], cne = c[i + P + 1];
    const double n1 = d + 1.0;
    const double n2 = d + diag;
    // min() and an integer tail increment compile to minsd/setcc: no data-dependent branches.
    auto relax = [](double* cell, std::uint32_t* q, std::size_t& t, double cj, double nd, std::ptrdiff_t j) {
      *cell = std::min(nd, cj);
      q[t] = static_cast<std::uint32_t>(j);
      t += static_cast<std::size_t>(nd < cj);
    };
    relax(c + i + 1, a, ta, ce, n1, i + 1);
    relax(c + i - P, a, ta, cs, n1, i - P);
    relax(c + i - 1, a, ta, cw, n1, i - 1);
    relax(c + i + P, a, ta, cn, n1, i + P);
    // A diagonal needs both orthogonal cells beside it free; otherwise offer +inf, never an improvement.
    const bool fe = ce != kBlocked, fs = cs != kBlocked, fw = cw != kBlocked, fn = cn != kBlocked;
    relax(c + i - P + 1, b, tb, cse, (fe && fs) ? n2 : kInf, i - P + 1);
    relax(c + i - P - 1, b, tb, csw, (fw && fs) ? n2 : kInf, i - P - 1);
    relax(c + i + P - 1, b, tb, cnw, (fw && fn) ? n2 : kInf, i + P - 1);
    relax(c + i + P + 1, b, tb, cne, (fe && fn) ? n2 : kInf, i + P + 1);
    a[ta] = sentinel;
    b[tb] = sentinel;
  }
  for (int y = 0; y < h; ++y) {
    const double* row = c + (y + 1) * P + 1;
    double* dst = out.data() + static_cast<std::ptrdiff_t>(y) * w;
    for (int x = 0; x < w; ++x) {
      const double v = row[x];
      dst[x] = v == kBlocked ? kInf : std::abs(v);  // unreached cells keep +inf
    }
  }
}

}  // namespace

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
  if (grid.blocked(goal)) {
    f.cost.assign(grid.size(), kInf);
    return f;
  }
  const int w = grid.width();
  const int h = grid.height();
  const auto P = static_cast<std::ptrdiff_t>(w) + 2;
  const auto padded = static_cast<std::size_t>(P) * static_cast<std::size_t>(h + 2);
  const auto start = static_cast<std::uint32_t>((goal.y + 1) * P + goal.x + 1);
  if (conn == Connectivity::Eight) {
    f.cost.resize(grid.size());  // every cell is written by octileField
    octileField(grid, start, f.cost);
    return f;
  }
  // Work on a copy padded with one blocked cell all around: the inner loops then need neither
  // bounds checks nor index divisions.
  std::vector<std::uint8_t> occ(padded, 1);
  for (int y = 0; y < h; ++y) {
    std::copy_n(grid.cells().begin() + static_cast<std::ptrdiff_t>(y) * w, w, occ.begin() + (y + 1) * P + 1);
  }
  std::vector<double> cost(padded, kInf);
  f.cost.resize(grid.size());
  // The seed's pseudocode never sets d(B) = 0, re-queues B and does not exclude obstacles in
  // check(); all three are fixed here.
  cost[start] = 0.0;
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
