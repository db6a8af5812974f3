#include "fleet/traffic/grid_map.hpp"

#include "fleet/core/bounded_file.hpp"
#include "fleet/planning/map_io.hpp"

namespace fleet::traffic {

namespace {

Unexpected<Error> pdError(const std::string& source, std::size_t line, const std::string& what) {
  return unexpected("map_format", source + ":" + std::to_string(line) + ": " + what);
}

}  // namespace

Expected<GridMap> parseGridMap(std::string_view text, const std::string& source) {
  // One parser for MovingAI files in the project: planning's, whose errors already name the line.
  auto grid = planning::parseMovingAiMap(text, source);
  if (!grid) {
    return unexpected(grid.error());
  }
  GridMap m;
  m.source = source;
  m.width = grid->width();
  m.height = grid->height();
  m.nodeAt.assign(static_cast<std::size_t>(m.width) * static_cast<std::size_t>(m.height), kNoNode);
  const auto freeAt = [&](int x, int y) { return grid->freeCell({x, m.height - 1 - y}); };
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      if (!freeAt(x, y)) {
        continue;
      }
      const NodeId v = m.graph.addNode(Vec2{x + 0.5, m.height - 1 - y + 0.5});
      m.nodeAt[static_cast<std::size_t>(y) * static_cast<std::size_t>(m.width) +
               static_cast<std::size_t>(x)] = v;
      m.cellOf.push_back({x, y});
    }
  }
  constexpr int kDx[4] = {1, 0, -1, 0};
  constexpr int kDy[4] = {0, -1, 0, 1};
  for (std::size_t v = 0; v < m.cellOf.size(); ++v) {
    const GridCell c = m.cellOf[v];
    for (int k = 0; k < 4; ++k) {
      const NodeId u = m.node(c.x + kDx[k], c.y + kDy[k]);
      if (u != kNoNode) {
        m.graph.addEdge(static_cast<NodeId>(v), u, 1.0);
      }
    }
  }
  return m;
}

Expected<GridMap> loadGridMap(const std::string& path) {
  auto text = readBoundedFile(path, kMapFileLimit, "map_io");
  if (!text) {
    return unexpected(text.error());
  }
  return parseGridMap(*text, path);
}

Expected<PickupDelivery> parsePickupDelivery(std::string_view text, const GridMap& map,
                                             const std::string& source) {
  PickupDelivery pd;
  std::size_t start = 0;
  int row = 0;
  std::size_t lineNo = 0;
  while (start < text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) {
      end = text.size();
    }
    std::string_view line = text.substr(start, end - start);
    start = end + 1;
    ++lineNo;
    if (!line.empty() && line.back() == '\r') {
      line.remove_suffix(1);
    }
    if (line.empty()) {
      // Blank lines only at the end (an editor's trailing newline); anywhere else they shift rows.
      if (text.find_first_not_of("\r\n", start) == std::string_view::npos) {
        break;
      }
      return pdError(source, lineNo, "empty row inside the grid");
    }
    if (row >= map.height) {
      return pdError(source, lineNo, "more rows than the map's height " + std::to_string(map.height));
    }
    if (line.size() != static_cast<std::size_t>(map.width)) {
      return pdError(source, lineNo,
                     "row has " + std::to_string(line.size()) + " characters, the map's width is " +
                         std::to_string(map.width));
    }
    for (int x = 0; x < map.width; ++x) {
      const char ch = line[static_cast<std::size_t>(x)];
      const bool pickup = ch == 'p' || ch == 's' || ch == 'a';
      const bool delivery = ch == 'd' || ch == 's' || ch == 'a';
      const bool endpoint = ch == 'e' || ch == 'a';
      if (!pickup && !delivery && !endpoint) {
        if (std::string_view(".@OTWGS").find(ch) == std::string_view::npos) {
          return pdError(source, lineNo,
                         std::string("unknown character '") + ch + "' at column " + std::to_string(x + 1) +
                             " (expected p d s e a, or a map character)");
        }
        continue;
      }
      const NodeId v = map.node(x, row);
      if (v == kNoNode) {
        return pdError(source, lineNo,
                       std::string("'") + ch + "' at column " + std::to_string(x + 1) +
                           " marks a cell that is blocked in " + map.source);
      }
      if (pickup) {
        pd.pickups.push_back(v);
      }
      if (delivery) {
        pd.deliveries.push_back(v);
      }
      if (endpoint) {
        pd.endpoints.push_back(v);
      }
    }
    ++row;
  }
  if (row != map.height) {
    return pdError(source, lineNo,
                   "has " + std::to_string(row) + " rows, the map's height is " + std::to_string(map.height));
  }
  if (pd.pickups.empty() || pd.deliveries.empty()) {
    return pdError(source, lineNo, "no pickup (p, s, a) or no delivery (d, s, a) cell");
  }
  return pd;
}

Expected<PickupDelivery> loadPickupDelivery(const std::string& path, const GridMap& map) {
  auto text = readBoundedFile(path, kMapFileLimit, "map_io");
  if (!text) {
    return unexpected(text.error());
  }
  return parsePickupDelivery(*text, map, path);
}

std::string warehouseMapText(const WarehouseLayout& l) {
  // The published family puts 2.5 cells of floor per shelf column left and right of the blocks
  // (25 for 10 columns, 50 for 20) and one aisle's width above and below them.
  const int marginX = l.columns * 5 / 2;
  const int marginY = l.aisle;
  const int blocksW = l.columns * l.shelfWidth + (l.columns - 1) * l.aisle;
  const int blocksH = l.rows * l.shelfHeight + (l.rows - 1) * l.aisle;
  const int width = 2 + 2 * marginX + blocksW;
  const int height = 2 + 2 * marginY + blocksH;
  std::string out =
      "type octile\nheight " + std::to_string(height) + "\nwidth " + std::to_string(width) + "\nmap\n";
  out.reserve(out.size() + static_cast<std::size_t>((width + 1) * height));
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const bool border = x == 0 || y == 0 || x == width - 1 || y == height - 1;
      const int ix = x - 1 - marginX;
      const int iy = y - 1 - marginY;
      const bool shelf = ix >= 0 && iy >= 0 && ix < blocksW && iy < blocksH &&
                         ix % (l.shelfWidth + l.aisle) < l.shelfWidth &&
                         iy % (l.shelfHeight + l.aisle) < l.shelfHeight;
      out += (border || shelf) ? 'T' : '.';
    }
    out += '\n';
  }
  return out;
}

}  // namespace fleet::traffic
