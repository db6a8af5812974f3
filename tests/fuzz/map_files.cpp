// The map files a site names, as bytes: the first byte picks the reader, the rest is the file.
//   0: ROS map_server side file (YAML)      -> parseRosMapYaml, then over a 16 x 12 image (map limits)
//   1: map image (PGM P2/P5 or PNG)         -> decodeImage, then rosMapFromImage + toOccupancyGrid
//   2: MovingAI .map text                   -> parseMovingAiMap
// Every reader reports bad input as an error value (its documented codes) and never throws.

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "fleet/planning/map_io.hpp"
#include "fleet/planning/map_limits.hpp"
#include "fleet/site/ros_map.hpp"
#include "fuzz_check.hpp"

using fleet::fuzz::require;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) {
    return 0;
  }
  const std::string_view bytes(reinterpret_cast<const char*>(data) + 1, size - 1);
  switch (data[0] % 3) {
    case 0: {
      const auto info = fleet::site::parseRosMapYaml(bytes, "fuzz.yaml");
      if (info) {
        require(info->resolution > 0.0, "a parsed side file has a positive resolution");
        require(info->freeThresh < info->occupiedThresh, "free_thresh < occupied_thresh");
        // The side file over a small image: a resolution or origin beyond the map limits is an
        // error, never a grid of billions of cells or kilometres.
        fleet::site::Image image{16, 12, 1, std::vector<std::uint8_t>(16 * 12, 254)};
        const auto map = fleet::site::rosMapFromImage(image, *info, "fuzz.yaml");
        if (map) {
          const auto grid = fleet::site::toOccupancyGrid(*map);
          require(static_cast<double>(grid.size()) <= fleet::planning::kMaxMapCells,
                  "a map within the cell limit");
          require(grid.width() * grid.resolution() <= fleet::planning::kMaxMapSideM + 1e-6 &&
                      grid.height() * grid.resolution() <= fleet::planning::kMaxMapSideM + 1e-6,
                  "a map within the side limit");
        } else {
          require(map.error().code == "map_size" || map.error().code == "map_yaml",
                  "a side file beyond the limits is map_size");
        }
      } else {
        require(info.error().code == "map_yaml", "side file errors are map_yaml");
      }
      break;
    }
    case 1: {
      const auto image = fleet::site::decodeImage(bytes, "fuzz.img");
      if (!image) {
        require(image.error().code == "map_image", "image errors are map_image");
        break;
      }
      require(image->pixels.size() == static_cast<std::size_t>(image->width) *
                                          static_cast<std::size_t>(image->height) *
                                          static_cast<std::size_t>(image->channels),
              "an image holds width * height * channels samples");
      // Small images only from here: a grid of 100 M cells is a legitimate map, just slow to fuzz.
      if (image->pixels.size() > (std::size_t{1} << 20)) {
        break;
      }
      fleet::site::RosMapInfo info;
      info.resolution = 0.1;
      info.origin = {1.0, -2.0, static_cast<double>(data[size - 1] % 4) * 0.5};
      info.mode = static_cast<fleet::site::MapMode>(data[size - 1] % 3);
      const auto map = fleet::site::rosMapFromImage(*image, info, "fuzz.img");
      if (map) {
        (void)fleet::site::toOccupancyGrid(*map);
      }
      break;
    }
    default: {
      const auto grid = fleet::planning::parseMovingAiMap(bytes, "fuzz.map");
      if (!grid) {
        // Malformed text, or a grid beyond the size limits (map_limits.hpp) a header may announce.
        require(grid.error().code == "map_format" || grid.error().code == "map_size",
                "MovingAI errors are map_format or map_size");
      }
      break;
    }
  }
  return 0;
}
