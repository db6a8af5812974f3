#include <algorithm>
#include <cmath>

#include "fleet/fleet/allocator.hpp"

namespace fleet {
namespace {

/// Classic O(n²m) Hungarian method for n ≤ m on a dense matrix of finite costs (1-based inside):
/// row potentials u, column potentials v, Dijkstra-like growth of one alternating tree per row.
std::vector<int> hungarianRowsLeCols(const std::vector<double>& a, std::size_t n, std::size_t m) {
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> u(n + 1, 0.0), v(m + 1, 0.0), minv(m + 1);
  std::vector<std::size_t> p(m + 1, 0), way(m + 1, 0);
  std::vector<char> used(m + 1);
  for (std::size_t i = 1; i <= n; ++i) {
    p[0] = i;
    std::size_t j0 = 0;
    std::fill(minv.begin(), minv.end(), inf);
    std::fill(used.begin(), used.end(), 0);
    do {
      used[j0] = 1;
      const std::size_t i0 = p[j0];
      double delta = inf;
      std::size_t j1 = 0;
      const double* row = &a[(i0 - 1) * m];
      for (std::size_t j = 1; j <= m; ++j) {
        if (used[j] != 0) {
          continue;
        }
        const double cur = row[j - 1] - u[i0] - v[j];
        if (cur < minv[j]) {
          minv[j] = cur;
          way[j] = j0;
        }
        if (minv[j] < delta) {
          delta = minv[j];
          j1 = j;
        }
      }
      for (std::size_t j = 0; j <= m; ++j) {
        if (used[j] != 0) {
          u[p[j]] += delta;
          v[j] -= delta;
        } else {
          minv[j] -= delta;
        }
      }
      j0 = j1;
    } while (p[j0] != 0);
    do {
      const std::size_t j1 = way[j0];
      p[j0] = p[j1];
      j0 = j1;
    } while (j0 != 0);
  }
  std::vector<int> rowToCol(n, -1);
  for (std::size_t j = 1; j <= m; ++j) {
    if (p[j] != 0) {
      rowToCol[p[j] - 1] = static_cast<int>(j - 1);
    }
  }
  return rowToCol;
}

}  // namespace

std::vector<int> solveHungarian(const CostMatrix& c) {
  const std::size_t k = std::min(c.rows, c.cols);
  if (k == 0) {
    return std::vector<int>(c.rows, -1);
  }
  // Forbidden pairs become one "big M" that outweighs any sum of k finite costs, so the optimum
  // first maximises the number of allowed pairs, then minimises their cost; M pairs are dropped.
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();
  for (double x : c.v) {
    if (std::isfinite(x)) {
      lo = std::min(lo, x);
      hi = std::max(hi, x);
    }
  }
  if (!std::isfinite(lo)) {
    return std::vector<int>(c.rows, -1);
  }
  const double big = (hi - lo + 1.0) * static_cast<double>(k + 1);
  const bool transpose = c.rows > c.cols;
  const std::size_t n = transpose ? c.cols : c.rows;
  const std::size_t m = transpose ? c.rows : c.cols;
  std::vector<double> a(n * m);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = 0; j < m; ++j) {
      const double x = transpose ? c.at(j, i) : c.at(i, j);
      a[i * m + j] = std::isfinite(x) ? x - lo : big;
    }
  }
  const auto sol = hungarianRowsLeCols(a, n, m);
  std::vector<int> rowToCol(c.rows, -1);
  for (std::size_t i = 0; i < n; ++i) {
    if (sol[i] < 0) {
      continue;
    }
    const auto j = static_cast<std::size_t>(sol[i]);
    const std::size_t r = transpose ? j : i;
    const std::size_t col = transpose ? i : j;
    if (std::isfinite(c.at(r, col))) {
      rowToCol[r] = static_cast<int>(col);
    }
  }
  return rowToCol;
}

std::vector<Assignment> HungarianAllocator::assign(std::span<const Task> tasks,
                                                   std::span<const RobotInfo> robots,
                                                   const TravelModel& travel, std::int64_t nowNs) const {
  CostMatrix travelS;
  const CostMatrix c = effectiveCosts(tasks, robots, travel, p_, nowNs, &travelS);
  const auto rowToCol = solveHungarian(c);
  std::vector<Assignment> out;
  for (std::size_t i = 0; i < rowToCol.size(); ++i) {
    if (rowToCol[i] >= 0) {
      const auto j = static_cast<std::size_t>(rowToCol[i]);
      out.push_back({i, j, pairCost(tasks[i], travelS.at(i, j), p_, nowNs), travelS.at(i, j)});
    }
  }
  return out;
}

}  // namespace fleet
