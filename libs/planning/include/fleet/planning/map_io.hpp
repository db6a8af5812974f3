#pragma once

#include <string>
#include <string_view>

#include "fleet/core/expected.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::planning {

/// MovingAI `.map` text: header `type octile` (optional: some published maps omit it), `height H`,
/// `width W`, `map`, then H rows of W characters. As the MovingAI page says: `.`, `G` and `S`
/// (swamp, passable from regular terrain) are free; `@`, `O`, `T` are blocked, and so is `W`
/// (water: traversable, but not from terrain, so a robot on the floor never enters it). Row 0 of the file is
/// the TOP of the map, so file (x, row) becomes cell (x, H - 1 - row). Errors name `source`, the line and
/// what was expected (code "map_format").
Expected<OccupancyGrid> parseMovingAiMap(std::string_view text, const std::string& source = "<text>",
                                         double resolution = 1.0, Vec2 origin = {});
Expected<OccupancyGrid> loadMovingAiMap(const std::string& path, double resolution = 1.0, Vec2 origin = {});
std::string toMovingAiMap(const OccupancyGrid& grid);
Expected<void> saveMovingAiMap(const OccupancyGrid& grid, const std::string& path);

/// Binary (P5) or ASCII (P2) PGM image; pixel row 0 is the top of the map. A pixel is occupied when
/// its occupancy (1 - value/maxval, or value/maxval with `negate`) exceeds `occupiedThresh`;
/// everything else (including unknown) is treated as free only if below `freeThresh`, else blocked.
struct ImageMapInfo {
  std::string image;  ///< path, relative to the side file
  double resolution = 0.05;
  Vec2 origin;  ///< map-frame position of the bottom-left pixel corner
  double occupiedThresh = 0.65;
  double freeThresh = 0.196;
  bool negate = false;
};
Expected<OccupancyGrid> parsePgm(std::string_view bytes, const ImageMapInfo& info, const std::string& source);
/// Side file in JSON (ROS map_server's fields): {"image": "...", "resolution": r, "origin": [x, y, yaw],
/// "occupied_thresh": .65, "free_thresh": .196, "negate": 0}. Yaw must be 0.
Expected<OccupancyGrid> loadImageMap(const std::string& sideFilePath);

}  // namespace fleet::planning
