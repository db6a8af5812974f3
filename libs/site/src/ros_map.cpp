#include "fleet/site/ros_map.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <set>

#include "fleet/core/bounded_file.hpp"
#include "fleet/planning/map_limits.hpp"

namespace fleet::site {

namespace {

Unexpected<Error> keyError(const std::string& source, const std::string& key, const std::string& what) {
  return unexpected("map_yaml", source + ": key '" + key + "' " + what);
}

std::string scalarText(const YAML::Node& n) {
  if (n.IsScalar()) {
    return "'" + n.Scalar() + "'";
  }
  return n.IsSequence() ? "a list" : n.IsMap() ? "a mapping" : "nothing";
}

// yaml-cpp's convert<> reports failure by return value; as<> would throw.
bool toDouble(const YAML::Node& n, double& out) {
  return n.IsScalar() && YAML::convert<double>::decode(n, out) && std::isfinite(out);
}

// Also used for maps built in code (masks, tests), so it repeats what the YAML parser checks.
Expected<void> checkInfo(const RosMapInfo& info, const std::string& source) {
  if (!std::isfinite(info.resolution) || info.resolution <= 0.0) {
    return keyError(source, "resolution", "must be a positive number of metres per pixel");
  }
  if (!info.origin.isFinite()) {
    return keyError(source, "origin", "must hold finite numbers");
  }
  for (const auto& [key, v] :
       {std::pair{"occupied_thresh", info.occupiedThresh}, std::pair{"free_thresh", info.freeThresh}}) {
    if (!(v >= 0.0 && v <= 1.0)) {
      return keyError(source, key, "must be a number in [0, 1]");
    }
  }
  if (!(info.freeThresh < info.occupiedThresh)) {
    return keyError(source, "free_thresh", "must be below occupied_thresh");
  }
  return {};
}

// The map_server value of a pixel whose averaged colour is `mean` (0..255), alpha handled by the caller.
std::int8_t interpret(double mean, const RosMapInfo& info) {
  if (info.mode == MapMode::Raw) {  // Nav2: the grey level itself, negate ignored, > 100 unknown
    const double v = std::round(mean);
    return v <= 100.0 ? static_cast<std::int8_t>(v) : std::int8_t{-1};
  }
  const double occ = info.negate ? mean / 255.0 : (255.0 - mean) / 255.0;
  if (occ > info.occupiedThresh) {
    return 100;
  }
  if (occ < info.freeThresh) {
    return 0;
  }
  if (info.mode == MapMode::Trinary) {
    return -1;
  }
  return static_cast<std::int8_t>(
      std::rint((occ - info.freeThresh) / (info.occupiedThresh - info.freeThresh) * 100.0));
}

// Pixel lookup in the map frame, with the origin's rotation computed once.
struct MapFrame {
  const RosMap& m;
  Vec2 o{m.info.origin.x, m.info.origin.y};
  double c = std::cos(m.info.origin.theta);
  double s = std::sin(m.info.origin.theta);

  [[nodiscard]] std::int8_t at(Vec2 p) const {
    const Vec2 d = p - o;
    const double u = (c * d.x + s * d.y) / m.info.resolution;
    const double v = (-s * d.x + c * d.y) / m.info.resolution;
    if (!(u >= 0.0 && v >= 0.0 && u < m.width && v < m.height)) {  // also refuses NaN
      return -1;
    }
    const int i = std::min(static_cast<int>(u), m.width - 1);
    const int j = std::min(static_cast<int>(v), m.height - 1);
    return m
        .data[static_cast<std::size_t>(j) * static_cast<std::size_t>(m.width) + static_cast<std::size_t>(i)];
  }
};

// The axis-aligned planning grid toOccupancyGrid makes of a width x height image: the image
// itself at yaw 0, else the rotated image's bounding box. Cell counts as doubles: they are checked
// against the limits before anything is allocated.
struct GridBox {
  Vec2 lo;
  double cellsX = 0.0;
  double cellsY = 0.0;
};

GridBox gridBox(const RosMapInfo& info, double width, double height) {
  const double res = info.resolution;
  if (info.origin.theta == 0.0) {
    return {info.origin.position(), width, height};
  }
  constexpr double kInf = std::numeric_limits<double>::infinity();
  Vec2 lo{kInf, kInf};
  Vec2 hi{-kInf, -kInf};
  for (const Vec2 corner :
       {Vec2{0, 0}, Vec2{width * res, 0}, Vec2{0, height * res}, Vec2{width * res, height * res}}) {
    const Vec2 p = info.origin.transform(corner);
    lo = {std::min(lo.x, p.x), std::min(lo.y, p.y)};
    hi = {std::max(hi.x, p.x), std::max(hi.y, p.y)};
  }
  // The tolerance keeps a quarter turn from growing a sliver column out of cos(pi/2) ~ 6e-17.
  auto cells = [&](double extent) { return std::max(1.0, std::ceil(extent / res - 1e-6)); };
  return {lo, cells(hi.x - lo.x), cells(hi.y - lo.y)};
}

// The map's size limits (planning::checkMapSize) on the grid it will become.
Expected<void> checkExtent(const RosMapInfo& info, int width, int height, const std::string& source,
                           const std::string& sizeKey) {
  const GridBox b = gridBox(info, width, height);
  return planning::checkMapSize(b.cellsX, b.cellsY, info.resolution, b.lo, source, sizeKey);
}

bool isFree(std::int8_t v, const RosMapInfo& info) {
  if (info.mode == MapMode::Raw) {
    return v >= 0 && v < 100.0 * info.freeThresh;
  }
  return v == 0;
}

}  // namespace

Expected<RosMapInfo> parseRosMapYaml(std::string_view text, const std::string& source) {
  try {
    const YAML::Node doc = YAML::Load(std::string(text));
    if (!doc.IsMap()) {
      const char* found = doc.IsSequence() ? "a list" : doc.IsNull() ? "nothing" : "a plain value";
      return unexpected("map_yaml",
                        source + ": expected a mapping with keys image, resolution, origin, ...; found " +
                            std::string(found));
    }
    static const std::set<std::string> kKnown{"image", "resolution",      "origin",     "negate",
                                              "mode",  "occupied_thresh", "free_thresh"};
    std::set<std::string> seen;
    for (const auto& kv : doc) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : "?";
      if (kKnown.count(key) == 0) {
        return keyError(source, key,
                        "is not a ROS map key (expected image, resolution, origin, negate, mode, "
                        "occupied_thresh, free_thresh)");
      }
      if (!seen.insert(key).second) {
        return keyError(source, key, "appears twice");
      }
    }
    for (const char* key : {"image", "resolution", "origin"}) {
      if (seen.count(key) == 0) {
        return keyError(source, key, "is missing (required)");
      }
    }
    RosMapInfo info;
    const YAML::Node image = doc["image"];
    if (!image.IsScalar() || image.Scalar().empty()) {
      return keyError(source, "image", "must be a non-empty file name");
    }
    info.image = image.Scalar();
    if (!toDouble(doc["resolution"], info.resolution) || info.resolution <= 0.0) {
      return keyError(source, "resolution",
                      "must be a positive number, found " + scalarText(doc["resolution"]));
    }
    const YAML::Node origin = doc["origin"];
    std::array<double, 3> o{};
    if (!origin.IsSequence() || origin.size() != 3) {
      return keyError(source, "origin", "must be a list of 3 numbers [x, y, yaw]");
    }
    for (std::size_t k = 0; k < 3; ++k) {
      if (!toDouble(origin[k], o[k])) {
        return keyError(
            source, "origin",
            "element " + std::to_string(k) + " must be a finite number, found " + scalarText(origin[k]));
      }
    }
    info.origin = {o[0], o[1], wrapAngle(o[2])};
    if (const YAML::Node n = doc["negate"]) {
      int i = 0;
      bool b = false;
      if (n.IsScalar() && YAML::convert<int>::decode(n, i) && (i == 0 || i == 1)) {
        info.negate = i == 1;
      } else if (n.IsScalar() && YAML::convert<bool>::decode(n, b)) {
        info.negate = b;
      } else {
        return keyError(source, "negate", "must be 0, 1, true or false, found " + scalarText(n));
      }
    }
    for (const auto& [key, dst] :
         {std::pair{"occupied_thresh", &info.occupiedThresh}, std::pair{"free_thresh", &info.freeThresh}}) {
      if (const YAML::Node n = doc[key]; n && (!toDouble(n, *dst) || *dst < 0.0 || *dst > 1.0)) {
        return keyError(source, key, "must be a number in [0, 1], found " + scalarText(n));
      }
    }
    if (const YAML::Node n = doc["mode"]) {
      const std::string m = n.IsScalar() ? n.Scalar() : "";
      if (m == "trinary") {
        info.mode = MapMode::Trinary;
      } else if (m == "scale") {
        info.mode = MapMode::Scale;
      } else if (m == "raw") {
        info.mode = MapMode::Raw;
      } else {
        return keyError(source, "mode", "must be trinary, scale or raw, found " + scalarText(n));
      }
    }
    if (auto ok = checkInfo(info, source); !ok) {
      return unexpected(ok.error());
    }
    return info;
  } catch (const YAML::Exception& e) {
    return unexpected("map_yaml", source + ":" + std::to_string(e.mark.line + 1) + ":" +
                                      std::to_string(e.mark.column + 1) + ": invalid YAML: " + e.msg);
  } catch (const std::exception& e) {  // yaml-cpp may also throw std exceptions (e.g. bad_alloc)
    return unexpected("map_yaml", source + ": cannot parse: " + e.what());
  }
}

Expected<RosMap> loadRosMap(const std::string& yamlPath) {
  auto text = readBoundedFile(yamlPath, kSideFileLimit, "map_yaml");
  if (!text) {
    return unexpected(text.error());
  }
  auto info = parseRosMapYaml(*text, yamlPath);
  if (!info) {
    return unexpected(info.error());
  }
  std::filesystem::path imagePath(info->image);
  if (imagePath.is_relative()) {
    imagePath = std::filesystem::path(yamlPath).parent_path() / imagePath;
  }
  auto bytes = readBoundedFile(imagePath.string(), kMapFileLimit, "map_image");
  if (!bytes) {
    return unexpected("map_image", bytes.error().message + " (image of " + yamlPath + ")");
  }
  auto image = decodeImage(*bytes, imagePath.string());
  if (!image) {
    return unexpected(image.error());
  }
  if (auto ok = checkExtent(*info, image->width, image->height, yamlPath,
                            "image (" + imagePath.filename().string() + ") of");
      !ok) {
    return unexpected(ok.error());
  }
  return rosMapFromImage(*image, *info, imagePath.string());
}

Expected<RosMap> rosMapFromImage(const Image& image, const RosMapInfo& info, const std::string& source) {
  if (auto ok = checkInfo(info, source); !ok) {
    return unexpected(ok.error());
  }
  const int ch = image.channels;
  if (image.width <= 0 || image.height <= 0 || ch < 1 || ch > 4 ||
      image.pixels.size() != static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) *
                                 static_cast<std::size_t>(ch)) {
    return unexpected("map_image", source + ": image size and pixel buffer disagree");
  }
  if (auto ok = checkExtent(info, image.width, image.height, source, "image"); !ok) {
    return unexpected(ok.error());
  }
  const bool colour = ch >= 3;
  const bool alpha = ch == 2 || ch == 4;
  // map_server averages R, G, B (grey counts three times) and, in trinary mode only, the alpha too.
  const bool alphaInMean = alpha && info.mode == MapMode::Trinary;
  const int weight = colour ? 1 : 3;
  const int divisor = 3 + (alphaInMean ? 1 : 0);
  std::vector<std::int8_t> lut(static_cast<std::size_t>(255 * divisor + 1));
  for (std::size_t sum = 0; sum < lut.size(); ++sum) {
    lut[sum] = interpret(static_cast<double>(sum) / divisor, info);
  }
  // map_saver writes unknown space as grey 205 (occ 0.196) and Nav2's writes free_thresh 0.25 beside
  // it, so Nav2 reloads its own unknown space as free (slam_toolbox#587, navigation2#5138). We keep it
  // unknown; ROS 1's 0.196 gave the same.
  if (info.mode == MapMode::Trinary && !info.negate && !alphaInMean && lut[3 * 205] == 0) {
    lut[3 * 205] = -1;
  }
  RosMap m{info, image.width, image.height, {}};
  m.data.resize(static_cast<std::size_t>(m.width) * static_cast<std::size_t>(m.height));
  const std::size_t w = static_cast<std::size_t>(m.width);
  for (std::size_t row = 0; row < static_cast<std::size_t>(m.height); ++row) {
    const std::uint8_t* px = image.pixels.data() + row * w * static_cast<std::size_t>(ch);
    std::int8_t* out =
        m.data.data() + (static_cast<std::size_t>(m.height) - 1 - row) * w;  // ROS rows: bottom up
    for (std::size_t x = 0; x < w; ++x, px += ch) {
      const int a = alpha ? px[ch - 1] : 255;
      if (alpha && a != 255 && info.mode == MapMode::Scale) {
        out[x] = -1;
        continue;
      }
      const int sum = (colour ? px[0] + px[1] + px[2] : weight * px[0]) + (alphaInMean ? a : 0);
      out[x] = lut[static_cast<std::size_t>(sum)];
    }
  }
  return m;
}

std::int8_t valueAt(const RosMap& m, Vec2 p) {
  return MapFrame{m}.at(p);
}

planning::OccupancyGrid toOccupancyGrid(const RosMap& m) {
  const double res = m.info.resolution;
  if (m.info.origin.theta == 0.0) {
    planning::OccupancyGrid g(m.width, m.height, res, m.info.origin.position());
    for (std::size_t k = 0; k < m.data.size(); ++k) {
      g.setBlocked(g.cellOf(k), !isFree(m.data[k], m.info));
    }
    return g;
  }
  const GridBox b = gridBox(m.info, m.width, m.height);
  planning::OccupancyGrid g(static_cast<int>(b.cellsX), static_cast<int>(b.cellsY), res, b.lo);
  const MapFrame frame{m};
  for (std::size_t k = 0; k < g.size(); ++k) {
    const planning::Cell c = g.cellOf(k);
    g.setBlocked(c, !isFree(frame.at(g.cellCenter(c)), m.info));
  }
  return g;
}

std::vector<std::size_t> keepoutCells(const RosMap& mask, const planning::OccupancyGrid& site) {
  std::vector<std::size_t> out;
  const MapFrame frame{mask};
  for (std::size_t k = 0; k < site.size(); ++k) {
    if (frame.at(site.cellCenter(site.cellOf(k))) == 100) {
      out.push_back(k);
    }
  }
  return out;
}

std::vector<SpeedCell> speedCells(const RosMap& mask, const planning::OccupancyGrid& site, SpeedMaskType type,
                                  double base, double multiplier, double maxSpeed) {
  std::vector<SpeedCell> out;
  const MapFrame frame{mask};
  for (std::size_t k = 0; k < site.size(); ++k) {
    const std::int8_t v = frame.at(site.cellCenter(site.cellOf(k)));
    if (v <= 0) {  // 0 = no limit; -1 (unknown, or off the mask) is invalid for Nav2 and changes nothing
      continue;
    }
    double limit = base + multiplier * v;
    if (type == SpeedMaskType::Percent) {
      // Nav2 ignores percentages outside [0, 100]; 0 is its "no limit" value.
      limit = limit >= 0.0 && limit <= 100.0 ? maxSpeed * limit / 100.0 : 0.0;
    }
    // 0 and negative mean no limit in Nav2; a limit at or above the top speed limits nothing.
    if (limit > 0.0 && limit < maxSpeed) {
      out.push_back({k, limit});
    }
  }
  return out;
}

}  // namespace fleet::site
