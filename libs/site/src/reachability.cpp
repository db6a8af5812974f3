#include "fleet/site/reachability.hpp"

#include <algorithm>
#include <cmath>
#include <deque>

namespace fleet::site {

namespace {

using planning::Cell;
using planning::OccupancyGrid;

// Squared distance from p to the closed square of cell c.
double squareDist2(const OccupancyGrid& g, Cell c, Vec2 p) {
  const double res = g.resolution();
  const Vec2 lo = g.origin() + Vec2{c.x * res, c.y * res};
  const double dx = std::max({lo.x - p.x, 0.0, p.x - (lo.x + res)});
  const double dy = std::max({lo.y - p.y, 0.0, p.y - (lo.y + res)});
  return dx * dx + dy * dy;
}

Cell cellContaining(const OccupancyGrid& g, Vec2 p) {
  return {static_cast<int>(std::floor((p.x - g.origin().x) / g.resolution())),
          static_cast<int>(std::floor((p.y - g.origin().y) / g.resolution()))};
}

void label(DiscRegions& r, const std::vector<std::uint8_t>& ok) {
  r.label.assign(ok.size(), 0);
  r.size.assign(1, 0);
  std::deque<int> q;
  const int w = r.width;
  for (std::size_t i = 0; i < ok.size(); ++i) {
    if (!ok[i] || r.label[i] != 0) {
      continue;
    }
    const auto id = static_cast<std::int32_t>(r.size.size());
    r.size.push_back(0);
    r.label[i] = id;
    q.push_back(static_cast<int>(i));
    while (!q.empty()) {
      const int n = q.front();
      q.pop_front();
      ++r.size.back();
      const int x = n % w;
      const int y = n / w;
      for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
        if (x + dx < 0 || y + dy < 0 || x + dx >= w || y + dy >= r.height) {
          continue;
        }
        const auto m = static_cast<std::size_t>((y + dy) * w + x + dx);
        if (ok[m] && r.label[m] == 0) {
          r.label[m] = id;
          q.push_back(static_cast<int>(m));
        }
      }
    }
  }
}

}  // namespace

bool discFits(const OccupancyGrid& g, Vec2 p, double radius) {
  if (!p.isFinite() || g.size() == 0) {
    return false;
  }
  const double res = g.resolution();
  const double r2 = radius * radius;
  // Outside the grid is wall: the disc must lie within the map's rectangle.
  const Vec2 lo = g.origin();
  const Vec2 hi = lo + Vec2{g.width() * res, g.height() * res};
  if (p.x - radius < lo.x || p.y - radius < lo.y || p.x + radius > hi.x || p.y + radius > hi.y) {
    return false;
  }
  const Cell a = cellContaining(g, p - Vec2{radius, radius});
  const Cell b = cellContaining(g, p + Vec2{radius, radius});
  for (int y = std::max(a.y, 0); y <= std::min(b.y, g.height() - 1); ++y) {
    for (int x = std::max(a.x, 0); x <= std::min(b.x, g.width() - 1); ++x) {
      // Strictly inside: touching a shelf face is not overlapping it.
      if (g.blocked({x, y}) && squareDist2(g, {x, y}, p) < r2 - 1e-12) {
        return false;
      }
    }
  }
  return true;
}

bool segmentFits(const OccupancyGrid& g, Vec2 a, Vec2 b, double radius) {
  const double len = distance(a, b);
  const int n = std::max(1, static_cast<int>(std::ceil(len / (0.25 * g.resolution()))));
  for (int i = 0; i <= n; ++i) {
    if (!discFits(g, a + (b - a) * (static_cast<double>(i) / n), radius)) {
      return false;
    }
  }
  return true;
}

DiscRegions discRegions(const OccupancyGrid& g, double radius) {
  const int sub = g.resolution() > radius / 3.0 ? 2 : 1;
  DiscRegions r;
  r.step = g.resolution() / sub;
  r.first = g.origin() + Vec2{0.5 * g.resolution(), 0.5 * g.resolution()};
  r.width = sub * (g.width() - 1) + 1;
  r.height = sub * (g.height() - 1) + 1;
  if (g.size() == 0) {
    r.width = r.height = 0;
  }
  // Only points within reach of a blocked cell or the map's edge need the exact test; mark the
  // cells near one by a separable dilation (rows, then columns), so open floor costs O(points).
  const int k = static_cast<int>(std::ceil(radius / g.resolution())) + 1;
  const int w = g.width();
  const int h = g.height();
  std::vector<std::uint8_t> nearRow(g.size(), 0);
  for (int y = 0; y < h; ++y) {
    int last = -1000000;  // last blocked x seen, scanning right
    for (int x = 0; x < w; ++x) {
      last = g.blocked({x, y}) ? x : last;
      nearRow[g.index({x, y})] = x - last <= k ? 1 : 0;
    }
    last = 1000000;
    for (int x = w - 1; x >= 0; --x) {
      last = g.blocked({x, y}) ? x : last;
      nearRow[g.index({x, y})] |= last - x <= k ? 1 : 0;
    }
  }
  std::vector<std::uint8_t> near(g.size(), 0);
  for (int x = 0; x < w; ++x) {
    int last = -1000000;
    for (int y = 0; y < h; ++y) {
      last = nearRow[g.index({x, y})] ? y : last;
      near[g.index({x, y})] = y - last <= k ? 1 : 0;
    }
    last = 1000000;
    for (int y = h - 1; y >= 0; --y) {
      last = nearRow[g.index({x, y})] ? y : last;
      near[g.index({x, y})] |= (last - y <= k || x < k || y < k || w - 1 - x < k || h - 1 - y < k) ? 1 : 0;
    }
  }
  std::vector<std::uint8_t> ok(static_cast<std::size_t>(r.width) * static_cast<std::size_t>(r.height), 0);
  for (int j = 0; j < r.height; ++j) {
    for (int i = 0; i < r.width; ++i) {
      // A cell this point lies on (its centre, or its right or top edge); far from every blocked
      // cell (the dilation covers the cell itself and its neighbours) the disc fits for sure.
      const Cell c{i / sub, j / sub};
      ok[static_cast<std::size_t>(j * r.width + i)] =
          !near[g.index(c)] || discFits(g, r.point(i, j), radius) ? 1 : 0;
    }
  }
  label(r, ok);
  return r;
}

std::int32_t regionOf(const OccupancyGrid& g, const DiscRegions& r, Vec2 p, double radius) {
  if (r.width == 0 || !discFits(g, p, radius)) {
    return 0;
  }
  const int ci = static_cast<int>(std::round((p.x - r.first.x) / r.step));
  const int cj = static_cast<int>(std::round((p.y - r.first.y) / r.step));
  std::int32_t best = 0;
  double bestD = 1e300;
  for (int j = cj - 2; j <= cj + 2; ++j) {
    for (int i = ci - 2; i <= ci + 2; ++i) {
      if (i < 0 || j < 0 || i >= r.width || j >= r.height) {
        continue;
      }
      const auto l = r.label[static_cast<std::size_t>(j * r.width + i)];
      const double d = distance(p, r.point(i, j));
      if (l != 0 && d < bestD && segmentFits(g, p, r.point(i, j), radius)) {
        bestD = d;
        best = l;
      }
    }
  }
  return best;
}

std::int32_t floorRegion(const DiscRegions& r, const std::vector<std::int32_t>& stationRegions) {
  std::vector<std::size_t> count(r.size.size(), 0);
  for (const auto l : stationRegions) {
    if (l > 0 && static_cast<std::size_t>(l) < count.size()) {
      ++count[static_cast<std::size_t>(l)];
    }
  }
  std::int32_t best = 0;
  for (std::size_t l = 1; l < count.size(); ++l) {
    const auto b = static_cast<std::size_t>(best);
    if (count[l] > 0 &&
        (best == 0 || count[l] > count[b] || (count[l] == count[b] && r.size[l] > r.size[b]))) {
      best = static_cast<std::int32_t>(l);
    }
  }
  return best;
}

DiscRegions cellRegions(const OccupancyGrid& g) {
  DiscRegions r;
  r.width = g.width();
  r.height = g.height();
  r.step = g.resolution();
  r.first = g.origin() + Vec2{0.5 * g.resolution(), 0.5 * g.resolution()};
  std::vector<std::uint8_t> ok(g.size(), 0);
  for (std::size_t i = 0; i < g.size(); ++i) {
    ok[i] = g.cells()[i] == 0 ? 1 : 0;
  }
  label(r, ok);
  return r;
}

}  // namespace fleet::site
