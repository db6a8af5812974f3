#pragma once

// Maps made with ROS tools (map_server / Nav2 map_saver): a YAML side file and a PGM or PNG image,
// read as ROS reads them, so a site mapped with ROS loads as it is. Nav2 costmap filter masks
// (keepout, speed) are maps of the same format and become zones.

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/core/pose2.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::site {

enum class MapMode { Trinary, Scale, Raw };

/// The YAML side file's fields (names as in ROS: image, resolution, origin [x, y, yaw], negate,
/// occupied_thresh, free_thresh, mode).
struct RosMapInfo {
  std::string image;  ///< as written in the YAML (relative to the YAML's folder unless absolute)
  double resolution = 0.05;
  Pose2 origin;  ///< map-frame pose of the image's lower-left pixel corner
  bool negate = false;
  double occupiedThresh = 0.65;
  double freeThresh = 0.196;
  MapMode mode = MapMode::Trinary;
};

/// A decoded 8-bit image, row 0 = top as in the file. `channels` is 1 (grey), 2 (grey + alpha),
/// 3 (RGB) or 4 (RGBA). Samples are the stored values (no gamma correction), rescaled to 0..255 with
/// rounding when the file uses another range (PGM maxval != 255, 16-bit samples): round(v * 255 / max).
struct Image {
  int width = 0;
  int height = 0;
  int channels = 1;
  std::vector<std::uint8_t> pixels;  ///< width * height * channels, row-major from the top
};

/// PGM (P2 or P5, maxval up to 65535, 16-bit big endian) or PNG (through libpng: grey, grey + alpha,
/// RGB, RGBA, palette (expanded to RGB, or RGBA with a tRNS chunk), any bit depth, interlaced or not),
/// chosen by the file's magic bytes, not its name. Errors (code "map_image") name `source` and what is
/// wrong: unknown magic, zero or more than 2^26 pixels (planning::kMaxMapCells), data shorter than the header
/// says, samples above maxval, bad CRC of a critical chunk, truncated or corrupt compressed data, missing
/// IEND.
Expected<Image> decodeImage(std::string_view bytes, const std::string& source);

/// The map as nav_msgs/OccupancyGrid holds it: one value per pixel, 0..100 occupancy or -1
/// unknown, computed from the image as Nav2's map_server does for the side file's mode;
/// row 0 = BOTTOM of the image (ROS's order). Per pixel, with `mean` the average of R, G, B
/// (a grey pixel is its grey level) and occ = (255 - mean) / 255, or mean / 255 with negate:
///  - trinary: occ > occupied_thresh -> 100, occ < free_thresh -> 0, otherwise -1 (a pixel exactly
///    on a threshold is unknown). With an alpha channel the alpha is averaged in as a fourth channel
///    (mean = (R + G + B + A) / 4), as Nav2 and ROS 1 do: transparency darkens, it is not "unknown".
///    One deliberate difference: without negate and alpha, map_saver's unknown grey (mean 205,
///    occ 0.196) stays -1 even when free_thresh is above 0.196. Nav2's map_saver writes
///    free_thresh 0.25 next to its 205 pixels, so Nav2 reloads its own unknown space as free
///    (slam_toolbox#587, navigation2#5138); ROS 1 (0.196) kept it unknown, and so do we.
///  - scale: any alpha below 255 -> -1; otherwise as trinary at both ends, and in between
///    rint(100 * (occ - free_thresh) / (occupied_thresh - free_thresh)) (Nav2's formula; ROS 1 used
///    1 + 98 * ratio).
///  - raw: round(mean) when it is 0..100, else -1 (Nav2; ROS 1 let values above 100 wrap around
///    int8). Negate and alpha are ignored, as in Nav2.
struct RosMap {
  RosMapInfo info;
  int width = 0;
  int height = 0;
  std::vector<std::int8_t> data;
};

/// Parses the YAML side file. Required: image, resolution (> 0), origin ([x, y, yaw], finite
/// numbers; yaw is wrapped to (-pi, pi]). Optional: negate (0, 1, true, false; default 0),
/// occupied_thresh (0.65), free_thresh (0.196), mode (trinary, scale, raw; default trinary).
/// Unknown or repeated keys, a missing required key, thresholds outside [0, 1] or free >= occupied,
/// an unknown mode, and text that is not a YAML mapping are errors (code "map_yaml") naming `source`
/// and the key. Never throws.
Expected<RosMapInfo> parseRosMapYaml(std::string_view text, const std::string& source);
/// Side file + image (resolved against the side file's folder). Errors: "map_yaml" for the side
/// file, "map_image" for the image (naming the image's path).
Expected<RosMap> loadRosMap(const std::string& yamlPath);
/// Same from an already decoded image (tests, masks in memory).
Expected<RosMap> rosMapFromImage(const Image& image, const RosMapInfo& info, const std::string& source);

/// Our planning grid in the same map frame. A cell is free only where the map says free: value 0 in
/// trinary and scale modes (occ < free_thresh, so the same image gives the same grid in both modes),
/// 0 <= value < 100 * free_thresh in raw mode. Occupied, in-between and unknown values, and cells off
/// the image, are blocked: a robot does not drive where nobody has looked. A Nav2 map_saver map
/// (trinary, 0 / 205 / 254 pixels) thus loads as exactly its free (254) cells.
/// With yaw == 0 the grid is the image itself (same size, origin (x, y)). Otherwise it is axis-aligned
/// at the map's resolution, covering the rotated image's bounding box (grid origin = the box's
/// lower-left corner), and each cell takes the pixel under its centre (nearest neighbour).
planning::OccupancyGrid toOccupancyGrid(const RosMap& m);

/// The ROS map's value (0..100, -1 unknown) under a map-frame point (origin yaw applied); -1
/// outside the image. Pixel edges belong to the pixel above / to the right.
std::int8_t valueAt(const RosMap& m, Vec2 p);

/// Nav2 keepout filter mask: the cells of `site` whose centres lie on a mask pixel of value 100, in
/// any mode. Nav2's keepout filter writes the mask as costs (value * 254 / 100, rounded) and only 100
/// becomes lethal; lower values are soft costs, not keepout, and unknown (-1) is skipped. The mask
/// may have its own resolution and origin; its yaw is applied (Nav2 ignores a mask's yaw; the same
/// when yaw = 0, the only yaw map_saver writes). Cells off the mask are not keepout.
std::vector<std::size_t> keepoutCells(const RosMap& mask, const planning::OccupancyGrid& site);

/// Nav2 speed filter mask, with the CostmapFilterInfo's type (1 = Percent, 2 = Absolute) and
/// coefficients, sampled at each site cell's centre: a mask value v in 1..100 gives the limit
/// base + multiplier * v, in percent of `maxSpeed` (Percent) or m/s (Absolute). As in Nav2: 0 means
/// no limit, unknown (-1, and off the mask) sets none, a percentage outside [0, 100] is ignored, and a
/// limit of 0 or below is Nav2's "no limit". One entry per cell whose limit lies in (0, maxSpeed)
/// m/s; a limit at or above `maxSpeed` (> 0) limits nothing and is left out.
enum class SpeedMaskType { Percent, Absolute };
struct SpeedCell {
  std::size_t cell = 0;
  double limit = 0.0;  ///< m/s
};
std::vector<SpeedCell> speedCells(const RosMap& mask, const planning::OccupancyGrid& site, SpeedMaskType type,
                                  double base, double multiplier, double maxSpeed);

}  // namespace fleet::site
