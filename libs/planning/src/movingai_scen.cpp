#include "fleet/planning/movingai_scen.hpp"

#include <charconv>
#include <cmath>
#include <filesystem>

#include "fleet/core/bounded_file.hpp"

namespace fleet::planning {

namespace {

std::vector<std::string_view> split(std::string_view s, char sep) {
  std::vector<std::string_view> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = s.find(sep, start);
    out.push_back(s.substr(start, end == std::string_view::npos ? std::string_view::npos : end - start));
    if (end == std::string_view::npos) {
      return out;
    }
    start = end + 1;
  }
}

bool toInt(std::string_view s, int& out) {
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return !s.empty() && ec == std::errc{} && ptr == s.data() + s.size();
}

bool toDouble(std::string_view s, double& out) {
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  return !s.empty() && ec == std::errc{} && ptr == s.data() + s.size() && std::isfinite(out);
}

std::string fileName(std::string_view path) {
  return std::filesystem::path(std::string(path)).filename().string();
}

}  // namespace

std::string_view scenSkipName(ScenSkip reason) {
  switch (reason) {
    case ScenSkip::kColumns:
      return "columns";
    case ScenSkip::kNumber:
      return "not_a_number";
    case ScenSkip::kOtherMap:
      return "other_map";
    case ScenSkip::kMapSize:
      return "map_size";
    case ScenSkip::kOffMap:
      return "off_map";
    case ScenSkip::kBlocked:
      return "blocked";
  }
  return "unknown";
}

std::map<std::string, int> ScenFile::skippedBy() const {
  std::map<std::string, int> out;
  for (const auto& p : skipped) {
    ++out[std::string(scenSkipName(p.reason))];
  }
  return out;
}

Expected<ScenFile> parseMovingAiScen(std::string_view text, const std::string& source,
                                     const OccupancyGrid* grid, std::string_view mapName) {
  ScenFile out;
  const std::string wanted = mapName.empty() ? std::string() : fileName(mapName);
  bool sawVersion = false;
  int lineNo = 0;
  for (std::string_view line : split(text, '\n')) {
    ++lineNo;
    if (!line.empty() && line.back() == '\r') {
      line.remove_suffix(1);
    }
    if (line.find_first_not_of(" \t") == std::string_view::npos) {
      continue;
    }
    if (!sawVersion) {
      if (line != "version 1" && line != "version 1.0") {
        return unexpected("scen_format", source + ":" + std::to_string(lineNo) +
                                             ": expected 'version 1' as the first line, got '" +
                                             std::string(line.substr(0, 40)) + "'");
      }
      sawVersion = true;
      continue;
    }
    const auto skip = [&](ScenSkip reason, std::string detail) {
      out.skipped.push_back({lineNo, reason, std::move(detail)});
    };
    const auto f = split(line, '\t');
    if (f.size() != 9) {
      skip(ScenSkip::kColumns, std::to_string(f.size()) + " tab-separated fields, expected 9");
      continue;
    }
    ScenEntry e;
    e.line = lineNo;
    e.map = std::string(f[1]);
    int* ints[] = {&e.bucket, nullptr, &e.width, &e.height, &e.startX, &e.startY, &e.goalX, &e.goalY};
    bool numeric = true;
    for (std::size_t i = 0; i < 8 && numeric; ++i) {
      if (ints[i] != nullptr && !toInt(f[i], *ints[i])) {
        skip(ScenSkip::kNumber,
             "field " + std::to_string(i + 1) + " '" + std::string(f[i]) + "' is not an integer");
        numeric = false;
      }
    }
    if (!numeric) {
      continue;
    }
    if (!toDouble(f[8], e.optimal) || e.optimal < 0.0 || e.width <= 0 || e.height <= 0) {
      skip(ScenSkip::kNumber,
           "width and height must be positive and the optimal length a finite number >= 0");
      continue;
    }
    if (!wanted.empty() && fileName(e.map) != wanted) {
      skip(ScenSkip::kOtherMap, "names " + e.map + ", not " + wanted);
      continue;
    }
    const auto inside = [&](int x, int y) { return x >= 0 && y >= 0 && x < e.width && y < e.height; };
    if (!inside(e.startX, e.startY) || !inside(e.goalX, e.goalY)) {
      skip(ScenSkip::kOffMap, "start or goal outside the row's own " + std::to_string(e.width) + " x " +
                                  std::to_string(e.height));
      continue;
    }
    if (grid != nullptr) {
      if (e.width != grid->width() || e.height != grid->height()) {
        skip(ScenSkip::kMapSize, std::to_string(e.width) + " x " + std::to_string(e.height) +
                                     ", the map is " + std::to_string(grid->width()) + " x " +
                                     std::to_string(grid->height()));
        continue;
      }
      // MovingAI counts rows from the top of the file; OccupancyGrid's row 0 is the bottom.
      e.start = {e.startX, grid->height() - 1 - e.startY};
      e.goal = {e.goalX, grid->height() - 1 - e.goalY};
      if (grid->blocked(e.start) || grid->blocked(e.goal)) {
        skip(ScenSkip::kBlocked,
             std::string(grid->blocked(e.start) ? "start" : "goal") + " on a blocked cell");
        continue;
      }
    } else {
      e.start = {e.startX, e.height - 1 - e.startY};
      e.goal = {e.goalX, e.height - 1 - e.goalY};
    }
    out.entries.push_back(std::move(e));
  }
  if (!sawVersion) {
    return unexpected("scen_format", source + ": empty, expected 'version 1' as the first line");
  }
  return out;
}

Expected<ScenFile> loadMovingAiScen(const std::string& path, const OccupancyGrid* grid,
                                    std::string_view mapName) {
  auto text = readBoundedFile(path, kMapFileLimit, "scen_io");
  if (!text) {
    return unexpected(text.error());
  }
  return parseMovingAiScen(*text, path, grid, mapName);
}

}  // namespace fleet::planning
