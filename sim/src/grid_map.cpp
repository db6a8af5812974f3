#include "fleet/sim/grid_map.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace fleet::sim {

namespace {
// Closest point of cell (cx, cy)'s square to p.
Vec2 closestOnCell(const GridMap& map, int cx, int cy, Vec2 p) {
  const double x0 = map.origin.x + cx * map.resolution;
  const double y0 = map.origin.y + cy * map.resolution;
  return {std::clamp(p.x, x0, x0 + map.resolution), std::clamp(p.y, y0, y0 + map.resolution)};
}
}  // namespace

bool nearestBlocked(const GridMap& map, Vec2 p, double reach, double& dist, Vec2& awayDir) {
  const int x0 = map.cellX(p.x - reach);
  const int x1 = map.cellX(p.x + reach);
  const int y0 = map.cellY(p.y - reach);
  const int y1 = map.cellY(p.y + reach);
  double best = reach;
  bool found = false;
  Vec2 bestPoint;
  for (int cy = y0; cy <= y1; ++cy) {
    for (int cx = x0; cx <= x1; ++cx) {
      if (!map.blocked(cx, cy)) {
        continue;
      }
      const Vec2 q = closestOnCell(map, cx, cy, p);
      const double d = std::sqrt((p - q).squaredNorm());
      if (d < best || (!found && d <= best)) {
        best = d;
        bestPoint = q;
        found = true;
      }
    }
  }
  if (!found) {
    return false;
  }
  dist = best;
  const Vec2 away = p - bestPoint;
  if (away.squaredNorm() > 0.0) {
    awayDir = away.normalized();
  } else {
    // Centre inside a blocked cell: push towards the nearest free neighbour's centre.
    const int cx = map.cellX(p.x);
    const int cy = map.cellY(p.y);
    awayDir = {};
    for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
      if (!map.blocked(cx + dx, cy + dy)) {
        awayDir = Vec2{static_cast<double>(dx), static_cast<double>(dy)};
        break;
      }
    }
  }
  return true;
}

double discGridPenetration(const GridMap& map, Vec2 centre, double radius) {
  double d = 0.0;
  Vec2 dir;
  if (!nearestBlocked(map, centre, radius, d, dir)) {
    return 0.0;
  }
  // A centre inside a blocked cell is at least a full radius deep.
  return d <= 0.0 ? radius : std::max(0.0, radius - d);
}

Expected<GridMap> parseMovingAiMap(const std::string& text, const std::string& source, double resolution) {
  std::istringstream in(text);
  std::string line;
  int width = -1;
  int height = -1;
  int lineNo = 0;
  bool inMap = false;
  std::vector<std::string> rows;
  while (std::getline(in, line)) {
    ++lineNo;
    if (!line.empty() && line.back() == '\r') {
      line.pop_back();
    }
    if (!inMap) {
      std::istringstream ls(line);
      std::string key;
      ls >> key;
      if (key == "height") {
        ls >> height;
      } else if (key == "width") {
        ls >> width;
      } else if (key == "map") {
        inMap = true;
      } else if (key != "type" && !key.empty()) {
        return unexpected("map_format", source + ":" + std::to_string(lineNo) + ": unexpected header key '" +
                                            key + "' (expected type, height, width, map)");
      }
      continue;
    }
    if (line.empty()) {
      continue;
    }
    if (static_cast<int>(line.size()) != width) {
      return unexpected("map_format", source + ":" + std::to_string(lineNo) + ": row has " +
                                          std::to_string(line.size()) + " cells, expected width " +
                                          std::to_string(width));
    }
    rows.push_back(line);
  }
  if (width <= 0 || height <= 0) {
    return unexpected("map_format", source + ": header must give positive 'width' and 'height'");
  }
  if (static_cast<int>(rows.size()) != height) {
    return unexpected("map_format", source + ": " + std::to_string(rows.size()) +
                                        " map rows, expected height " + std::to_string(height));
  }
  GridMap m;
  m.width = width;
  m.height = height;
  m.resolution = resolution;
  m.cells.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), 0);
  for (int r = 0; r < height; ++r) {
    const int cy = height - 1 - r;
    for (int cx = 0; cx < width; ++cx) {
      const char c = rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(cx)];
      m.cells[static_cast<std::size_t>(cy) * static_cast<std::size_t>(width) + static_cast<std::size_t>(cx)] =
          (c == '.' || c == 'G') ? 0 : 1;
    }
  }
  return m;
}

GridMap makeWarehouseMap(const WarehouseLayout& p) {
  GridMap m;
  m.width = p.width;
  m.height = p.height;
  m.resolution = p.resolution;
  m.cells.assign(static_cast<std::size_t>(p.width) * static_cast<std::size_t>(p.height), 0);
  auto set = [&](int cx, int cy) {
    m.cells[static_cast<std::size_t>(cy) * static_cast<std::size_t>(p.width) + static_cast<std::size_t>(cx)] =
        1;
  };
  for (int cx = 0; cx < p.width; ++cx) {
    set(cx, 0);
    set(cx, p.height - 1);
  }
  for (int cy = 0; cy < p.height; ++cy) {
    set(0, cy);
    set(p.width - 1, cy);
  }
  const int x0 = 1 + p.margin;
  const int y0 = 1 + p.margin;
  const int x1 = p.width - 1 - p.margin;
  const int y1 = p.height - 1 - p.margin;
  for (int by = y0; by + p.shelfHeight <= y1; by += p.shelfHeight + p.aisleY) {
    for (int bx = x0; bx + p.shelfWidth <= x1; bx += p.shelfWidth + p.aisleX) {
      for (int cy = by; cy < by + p.shelfHeight; ++cy) {
        for (int cx = bx; cx < bx + p.shelfWidth; ++cx) {
          set(cx, cy);
        }
      }
    }
  }
  return m;
}

}  // namespace fleet::sim
