#pragma once

// The size a map may have, checked where maps are loaded or generated (MovingAI .map, PGM and ROS
// maps, generated warehouses, inline rows) before anything is allocated for it: every later step
// (inflation by the robot's radius, clearance fields, roadmap lattices, risk grids) scales with the
// map's cells or its metres, so an absurd resolution or size must stop here, with the file and key.

#include <string>

#include "fleet/core/expected.hpp"
#include "fleet/core/vec2.hpp"

namespace fleet::planning {

/// At most 2^26 (67,108,864) cells: 8192 x 8192, or 3.3 km x 3.3 km at 5 cm.
inline constexpr double kMaxMapCells = 67108864.0;
/// At most 2 km along each side.
inline constexpr double kMaxMapSideM = 2000.0;
/// Cells at least 1 mm wide: a robot's disc is then at most a few thousand cells across.
inline constexpr double kMinMapResolution = 0.001;
/// The map's origin within 1000 km of the map frame's origin (the world's coordinates are bounded).
inline constexpr double kMaxMapOriginM = 1e6;

/// Checks a map of `width` x `height` cells of `resolution` m with its lower-left corner at
/// `origin`. An error (code "map_size") reads "<source>: <key>: <value> makes the map ... (limit
/// ...)", with `sizeKey` naming where the cell counts come from ("width/height", "image") and
/// `resolutionKey` / `originKey` the keys holding those (an empty key or source leaves that part out).
Expected<void> checkMapSize(double width, double height, double resolution, Vec2 origin,
                            const std::string& source, const std::string& sizeKey,
                            const std::string& resolutionKey = "resolution",
                            const std::string& originKey = "origin");

}  // namespace fleet::planning
