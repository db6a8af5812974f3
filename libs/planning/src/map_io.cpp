#include "fleet/planning/map_io.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <vector>

#include "fleet/core/bounded_file.hpp"
#include "fleet/planning/map_limits.hpp"

namespace fleet::planning {

namespace {

Unexpected<Error> formatError(const std::string& source, int line, const std::string& what) {
  std::string msg = source;
  if (line > 0) {
    msg += ':';
    msg.append(std::to_string(line));
  }
  msg.append(": ");
  msg.append(what);
  return unexpected("map_format", std::move(msg));
}

std::vector<std::string> splitLines(std::string_view text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string_view::npos) {
      end = text.size();
    }
    std::string line(text.substr(start, end - start));
    if (!line.empty() && line.back() == '\r') {
      line.pop_back();
    }
    lines.push_back(std::move(line));
    start = end + 1;
  }
  while (!lines.empty() && lines.back().empty()) {
    lines.pop_back();
  }
  return lines;
}

bool parseInt(const std::string& s, int& out) {
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return ec == std::errc{} && ptr == s.data() + s.size();
}

}  // namespace

Expected<OccupancyGrid> parseMovingAiMap(std::string_view text, const std::string& source, double resolution,
                                         Vec2 origin) {
  const auto lines = splitLines(text);
  int height = -1;
  int width = -1;
  std::size_t k = 0;
  bool sawType = false;
  for (; k < lines.size(); ++k) {
    std::istringstream ls(lines[k]);
    std::string key, value, extra;
    ls >> key;
    if (key.empty()) {
      continue;
    }
    if (key == "map") {
      break;
    }
    ls >> value;
    if (value.empty() || (ls >> extra)) {
      return formatError(source, static_cast<int>(k + 1),
                         "expected '<key> <value>' in the header, got '" + lines[k] + "'");
    }
    if (key == "type") {
      sawType = true;
    } else if (key == "height" || key == "width") {
      int v = 0;
      if (!parseInt(value, v) || v <= 0 || v > 100000) {
        return formatError(source, static_cast<int>(k + 1),
                           key + " must be a positive integer, got '" + value + "'");
      }
      (key == "height" ? height : width) = v;
    } else {
      return formatError(source, static_cast<int>(k + 1),
                         "unknown header key '" + key + "' (expected type, height, width, map)");
    }
  }
  // Some published maps omit 'type' (it is always octile); the page's own loader does not need it.
  (void)sawType;
  if (height < 0 || width < 0) {
    return formatError(source, 0, "missing 'height' or 'width' header line");
  }
  if (k >= lines.size()) {
    return formatError(source, static_cast<int>(lines.size()), "missing 'map' line before the grid rows");
  }
  if (!(resolution > 0.0) || !std::isfinite(resolution)) {
    return unexpected("map_format", source + ": resolution must be positive");
  }
  if (auto ok = checkMapSize(width, height, resolution, origin, source, "width x height"); !ok) {
    return unexpected(ok.error());
  }
  const std::size_t firstRow = k + 1;
  if (lines.size() - firstRow < static_cast<std::size_t>(height)) {
    return formatError(source, static_cast<int>(lines.size()),
                       "truncated map: header says height " + std::to_string(height) + " but only " +
                           std::to_string(lines.size() - firstRow) + " rows follow");
  }
  if (lines.size() - firstRow > static_cast<std::size_t>(height)) {
    return formatError(source, static_cast<int>(firstRow + static_cast<std::size_t>(height) + 1),
                       "extra rows after the " + std::to_string(height) + " rows the header announces");
  }
  OccupancyGrid g(width, height, resolution, origin);
  for (int row = 0; row < height; ++row) {
    const std::string& line = lines[firstRow + static_cast<std::size_t>(row)];
    const int lineNo = static_cast<int>(firstRow) + row + 1;
    if (line.size() != static_cast<std::size_t>(width)) {
      return formatError(source, lineNo,
                         "row has " + std::to_string(line.size()) + " characters, header says width " +
                             std::to_string(width));
    }
    for (int x = 0; x < width; ++x) {
      const char ch = line[static_cast<std::size_t>(x)];
      bool blocked = false;
      switch (ch) {
        case '.':
        case 'G':
        case 'S':  // swamp: "passable from regular terrain"
          break;
        case '@':
        case 'O':
        case 'T':
        case 'W':  // water: "not passable from terrain", so never entered by a robot on the floor
          blocked = true;
          break;
        default:
          return formatError(source, lineNo,
                             std::string("unknown character '") + ch + "' at column " +
                                 std::to_string(x + 1) + " (expected . G @ O T S W)");
      }
      g.setBlocked({x, height - 1 - row}, blocked);  // file row 0 is the top; our y is up
    }
  }
  return g;
}

Expected<OccupancyGrid> loadMovingAiMap(const std::string& path, double resolution, Vec2 origin) {
  auto text = readBoundedFile(path, kMapFileLimit, "map_io");
  if (!text) {
    return unexpected(text.error());
  }
  return parseMovingAiMap(*text, path, resolution, origin);
}

std::string toMovingAiMap(const OccupancyGrid& grid) {
  std::string out = "type octile\nheight " + std::to_string(grid.height()) + "\nwidth " +
                    std::to_string(grid.width()) + "\nmap\n";
  for (int row = 0; row < grid.height(); ++row) {
    for (int x = 0; x < grid.width(); ++x) {
      out += grid.blocked({x, grid.height() - 1 - row}) ? '@' : '.';
    }
    out += '\n';
  }
  return out;
}

Expected<void> saveMovingAiMap(const OccupancyGrid& grid, const std::string& path) {
  std::ofstream out(path, std::ios::binary);
  if (!out) {
    return unexpected("map_io", path + ": cannot open for writing");
  }
  out << toMovingAiMap(grid);
  if (!out) {
    return unexpected("map_io", path + ": write failed");
  }
  return {};
}

Expected<OccupancyGrid> parsePgm(std::string_view bytes, const ImageMapInfo& info,
                                 const std::string& source) {
  // Header tokens: magic, width, height, maxval; '#' comments run to the end of the line.
  std::size_t pos = 0;
  auto token = [&]() -> std::string {
    while (pos < bytes.size()) {
      if (bytes[pos] == '#') {
        while (pos < bytes.size() && bytes[pos] != '\n') {
          ++pos;
        }
      } else if (std::isspace(static_cast<unsigned char>(bytes[pos])) != 0) {
        ++pos;
      } else {
        break;
      }
    }
    const std::size_t start = pos;
    while (pos < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[pos])) == 0) {
      ++pos;
    }
    return std::string(bytes.substr(start, pos - start));
  };
  const std::string magic = token();
  if (magic != "P5" && magic != "P2") {
    return formatError(source, 1, "not a PGM image (magic '" + magic + "', expected P5 or P2)");
  }
  int w = 0, h = 0, maxval = 0;
  if (!parseInt(token(), w) || !parseInt(token(), h) || !parseInt(token(), maxval) || w <= 0 || h <= 0 ||
      maxval <= 0 || maxval > 65535) {
    return formatError(source, 0, "bad PGM header: width, height and maxval must be positive integers");
  }
  if (!(info.resolution > 0.0)) {
    return formatError(source, 0, "resolution must be positive");
  }
  if (auto ok = checkMapSize(w, h, info.resolution, info.origin, source, "image"); !ok) {
    return unexpected(ok.error());
  }
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  std::vector<int> pixels;
  pixels.reserve(n);
  if (magic == "P5") {
    ++pos;  // exactly one whitespace byte after maxval
    const std::size_t bpp = maxval > 255 ? 2 : 1;
    if (bytes.size() < pos + n * bpp) {
      return formatError(source, 0,
                         "truncated PGM data: expected " + std::to_string(n * bpp) + " bytes, found " +
                             std::to_string(bytes.size() > pos ? bytes.size() - pos : 0));
    }
    for (std::size_t k = 0; k < n; ++k) {
      const auto b0 = static_cast<unsigned char>(bytes[pos + k * bpp]);
      pixels.push_back(bpp == 2 ? (b0 << 8) | static_cast<unsigned char>(bytes[pos + k * bpp + 1]) : b0);
    }
  } else {
    for (std::size_t k = 0; k < n; ++k) {
      int v = 0;
      const std::string t = token();
      if (t.empty()) {
        return formatError(
            source, 0,
            "truncated PGM data: expected " + std::to_string(n) + " values, found " + std::to_string(k));
      }
      if (!parseInt(t, v) || v < 0 || v > maxval) {
        return formatError(source, 0, "bad pixel value '" + t + "' at index " + std::to_string(k));
      }
      pixels.push_back(v);
    }
  }
  OccupancyGrid g(w, h, info.resolution, info.origin);
  for (int row = 0; row < h; ++row) {
    for (int x = 0; x < w; ++x) {
      const double v =
          static_cast<double>(pixels[static_cast<std::size_t>(row) * static_cast<std::size_t>(w) +
                                     static_cast<std::size_t>(x)]) /
          maxval;
      const double occ = info.negate ? v : 1.0 - v;
      // Unknown (between the thresholds) is blocked: a robot should not plan through unmapped space.
      g.setBlocked({x, h - 1 - row}, occ >= info.freeThresh);
    }
  }
  return g;
}

Expected<OccupancyGrid> loadImageMap(const std::string& sideFilePath) {
  auto text = readBoundedFile(sideFilePath, kSideFileLimit, "map_io");
  if (!text) {
    return unexpected(text.error());
  }
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(*text);
  } catch (const nlohmann::json::exception& e) {  // a number beyond a double is out_of_range.406
    return unexpected("map_format", sideFilePath + ": invalid JSON: " + e.what());
  }
  ImageMapInfo info;
  auto need = [&](const char* key) -> Expected<const nlohmann::json*> {
    if (!j.is_object() || !j.contains(key)) {
      return unexpected("map_format", sideFilePath + ": missing key '" + key + "'");
    }
    return &j.at(key);
  };
  auto img = need("image");
  if (!img || !(*img)->is_string()) {
    return img ? unexpected("map_format", sideFilePath + ": key 'image' must be a string")
               : unexpected(img.error());
  }
  auto res = need("resolution");
  if (!res || !(*res)->is_number() || !((*res)->get<double>() > 0.0)) {
    return res ? unexpected("map_format", sideFilePath + ": key 'resolution' must be a positive number")
               : unexpected(res.error());
  }
  info.image = (*img)->get<std::string>();
  info.resolution = (*res)->get<double>();
  if (j.contains("origin")) {
    const auto& o = j.at("origin");
    if (!o.is_array() || o.size() < 2 || o.size() > 3 || !o[0].is_number() || !o[1].is_number()) {
      return unexpected("map_format", sideFilePath + ": key 'origin' must be [x, y] or [x, y, yaw]");
    }
    if (o.size() == 3 && (!o[2].is_number() || o[2].get<double>() != 0.0)) {
      return unexpected("map_format",
                        sideFilePath + ": key 'origin' yaw must be 0 (rotated maps are not supported)");
    }
    info.origin = {o[0].get<double>(), o[1].get<double>()};
  }
  for (const auto& [key, dst] :
       {std::pair{"occupied_thresh", &info.occupiedThresh}, std::pair{"free_thresh", &info.freeThresh}}) {
    if (j.contains(key)) {
      if (!j.at(key).is_number() || j.at(key).get<double>() < 0.0 || j.at(key).get<double>() > 1.0) {
        return unexpected("map_format", sideFilePath + ": key '" + key + "' must be a number in [0, 1]");
      }
      *dst = j.at(key).get<double>();
    }
  }
  if (j.contains("negate")) {
    const auto& ng = j.at("negate");
    if (!(ng.is_boolean() || ng.is_number_integer())) {
      return unexpected("map_format", sideFilePath + ": key 'negate' must be 0/1 or a boolean");
    }
    info.negate = ng.is_boolean() ? ng.get<bool>() : ng.get<int>() != 0;
  }
  std::filesystem::path imgPath(info.image);
  if (imgPath.is_relative()) {
    imgPath = std::filesystem::path(sideFilePath).parent_path() / imgPath;
  }
  auto bytes = readBoundedFile(imgPath.string(), kMapFileLimit, "map_io");
  if (!bytes) {
    return unexpected(bytes.error());
  }
  return parsePgm(*bytes, info, imgPath.string());
}

}  // namespace fleet::planning
