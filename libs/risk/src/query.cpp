#include "fleet/risk/query.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace fleet::risk {
namespace {

template <class Value>
CellRisk cellRisk(const GridSpec& g, int i, int j, Value v) {
  return CellRisk{i, j, Vec2{g.cellCentreX(i), g.cellCentreY(j)}, static_cast<double>(v)};
}

template <class Values>
Expected<CellRisk> riskAtImpl(const GridSpec& g, const Values& values, Vec2 p) {
  const auto cell = g.cellOf(p.x, p.y);
  if (!cell) {
    return unexpected("off_grid",
                      "point (" + std::to_string(p.x) + ", " + std::to_string(p.y) + ") is off the map");
  }
  return cellRisk(g, cell->first, cell->second, values[g.index(cell->first, cell->second)]);
}

template <class Values>
std::optional<CellRisk> segmentImpl(const GridSpec& g, const Values& values, Vec2 a, Vec2 b) {
  if (!a.isFinite() || !b.isFinite()) {
    return std::nullopt;
  }
  // Grid coordinates: cell (i, j) is [i, i+1) × [j, j+1).
  const double ax = (a.x - g.originX) / g.resolution, ay = (a.y - g.originY) / g.resolution;
  const double dx = (b.x - a.x) / g.resolution, dy = (b.y - a.y) / g.resolution;
  // Liang–Barsky clip of the parameter range [0, 1] to the grid rectangle.
  double t0 = 0.0, t1 = 1.0;
  const double W = g.width, H = g.height;
  const double pq[4][2] = {{-dx, ax}, {dx, W - ax}, {-dy, ay}, {dy, H - ay}};
  for (const auto& [p, q] : pq) {
    if (p == 0.0) {
      if (q < 0.0) {
        return std::nullopt;
      }
    } else {
      const double t = q / p;
      if (p < 0.0) {
        t0 = std::max(t0, t);
      } else {
        t1 = std::min(t1, t);
      }
    }
  }
  if (t0 > t1) {
    return std::nullopt;
  }
  const double sx = ax + dx * t0, sy = ay + dy * t0;
  int i = std::clamp(static_cast<int>(std::floor(sx)), 0, g.width - 1);
  int j = std::clamp(static_cast<int>(std::floor(sy)), 0, g.height - 1);
  const double ex = ax + dx * t1, ey = ay + dy * t1;
  const int iEnd = std::clamp(static_cast<int>(std::floor(ex)), 0, g.width - 1);
  const int jEnd = std::clamp(static_cast<int>(std::floor(ey)), 0, g.height - 1);
  // Amanatides & Woo: step to whichever cell boundary the ray crosses first.
  const int stepX = dx > 0 ? 1 : (dx < 0 ? -1 : 0);
  const int stepY = dy > 0 ? 1 : (dy < 0 ? -1 : 0);
  const double inf = std::numeric_limits<double>::infinity();
  double tMaxX = stepX > 0 ? (i + 1 - ax) / dx : (stepX < 0 ? (i - ax) / dx : inf);
  double tMaxY = stepY > 0 ? (j + 1 - ay) / dy : (stepY < 0 ? (j - ay) / dy : inf);
  const double tDeltaX = stepX != 0 ? std::abs(1.0 / dx) : inf;
  const double tDeltaY = stepY != 0 ? std::abs(1.0 / dy) : inf;
  CellRisk best = cellRisk(g, i, j, values[g.index(i, j)]);
  const int maxSteps = g.width + g.height + 4;
  for (int n = 0; n < maxSteps && !(i == iEnd && j == jEnd); ++n) {
    if (tMaxX < tMaxY) {
      if (tMaxX > t1)
        break;
      i += stepX;
      tMaxX += tDeltaX;
    } else {
      if (tMaxY > t1)
        break;
      j += stepY;
      tMaxY += tDeltaY;
    }
    if (i < 0 || j < 0 || i >= g.width || j >= g.height) {
      break;
    }
    const auto v = static_cast<double>(values[g.index(i, j)]);
    if (v > best.risk) {
      best = cellRisk(g, i, j, v);
    }
  }
  return best;
}

template <class Values>
std::optional<CellRisk> lowestImpl(const GridSpec& g, const Values& values, Vec2 c, double half) {
  if (!c.isFinite() || !(half >= 0.0)) {
    return std::nullopt;
  }
  const int i0 = std::max(0, static_cast<int>(std::ceil((c.x - half - g.originX) / g.resolution - 0.5)));
  const int i1 =
      std::min(g.width - 1, static_cast<int>(std::floor((c.x + half - g.originX) / g.resolution - 0.5)));
  const int j0 = std::max(0, static_cast<int>(std::ceil((c.y - half - g.originY) / g.resolution - 0.5)));
  const int j1 =
      std::min(g.height - 1, static_cast<int>(std::floor((c.y + half - g.originY) / g.resolution - 0.5)));
  std::optional<CellRisk> best;
  double bestD2 = 0.0;
  for (int j = j0; j <= j1; ++j) {
    for (int i = i0; i <= i1; ++i) {
      const auto v = static_cast<double>(values[g.index(i, j)]);
      const double ddx = g.cellCentreX(i) - c.x, ddy = g.cellCentreY(j) - c.y;
      const double d2 = ddx * ddx + ddy * ddy;
      if (!best || v < best->risk || (v == best->risk && d2 < bestD2)) {
        best = cellRisk(g, i, j, v);
        bestD2 = d2;
      }
    }
  }
  return best;
}

}  // namespace

Expected<CellRisk> riskAt(const ProbabilityGrid& grid, Vec2 point) {
  return riskAtImpl(grid.spec, grid.p, point);
}
Expected<CellRisk> riskAt(const LevelGrid& grid, Vec2 point) {
  return riskAtImpl(grid.spec, grid.level, point);
}
std::optional<CellRisk> maxRiskAlongSegment(const ProbabilityGrid& grid, Vec2 a, Vec2 b) {
  return segmentImpl(grid.spec, grid.p, a, b);
}
std::optional<CellRisk> maxRiskAlongSegment(const LevelGrid& grid, Vec2 a, Vec2 b) {
  return segmentImpl(grid.spec, grid.level, a, b);
}
std::optional<CellRisk> lowestRiskCell(const ProbabilityGrid& grid, Vec2 centre, double halfWidth) {
  return lowestImpl(grid.spec, grid.p, centre, halfWidth);
}
std::optional<CellRisk> lowestRiskCell(const LevelGrid& grid, Vec2 centre, double halfWidth) {
  return lowestImpl(grid.spec, grid.level, centre, halfWidth);
}

}  // namespace fleet::risk
