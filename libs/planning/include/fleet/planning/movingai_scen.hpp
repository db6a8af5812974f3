#pragma once

// MovingAI scenario files (`.scen`, https://movingai.com/benchmarks/formats.html): the benchmark's
// start/goal pairs with their optimal lengths, read with the format's rules. A bad row never stops
// the file: it is skipped with a named reason and counted, and the caller runs on the good rows.

#include <map>
#include <string>
#include <string_view>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::planning {

/// One row: `bucket  map  width  height  start-x  start-y  goal-x  goal-y  optimal-length`.
struct ScenEntry {
  int line = 0;  ///< 1-based line of the file
  int bucket = 0;
  std::string map;  ///< the map's file name as the row gives it
  int width = 0;
  int height = 0;
  int startX = 0, startY = 0;  ///< MovingAI coordinates: x the column, y the row from the TOP
  int goalX = 0, goalY = 0;
  double optimal = 0.0;  ///< octile length: 1 per straight, sqrt(2) per diagonal, no corner cutting
  Cell start;            ///< the same cells in OccupancyGrid's frame (row 0 at the bottom)
  Cell goal;
};

/// Why a row was skipped (the strings are the reasons' names in ScenFile::skippedBy).
enum class ScenSkip {
  kColumns,   ///< "columns": not 9 tab-separated fields
  kNumber,    ///< "not_a_number": a numeric field that is not one (or a negative size or length)
  kOtherMap,  ///< "other_map": names another map than the one given
  kMapSize,   ///< "map_size": width/height differ from the map's
  kOffMap,    ///< "off_map": start or goal outside the map
  kBlocked,   ///< "blocked": start or goal on a blocked cell
};
std::string_view scenSkipName(ScenSkip reason);

struct ScenProblem {
  int line = 0;
  ScenSkip reason = ScenSkip::kColumns;
  std::string detail;
};

struct ScenFile {
  int version = 1;
  std::vector<ScenEntry> entries;  ///< the good rows, in file order
  std::vector<ScenProblem> skipped;
  /// Skipped rows per reason name ("other_map": 3, ...).
  [[nodiscard]] std::map<std::string, int> skippedBy() const;
};

/// Parses a `.scen` text. The first non-empty line must be `version 1` (`version 1.0` is accepted:
/// older files write it); anything else is an error (code "scen_format", naming `source` and the
/// line), since the older versionless format orders its columns differently. With a `grid`, rows
/// are checked against it (size, start and goal on free cells inside the map); with a non-empty
/// `mapName` (a file name or a path: compared by file name), rows naming another map are skipped.
Expected<ScenFile> parseMovingAiScen(std::string_view text, const std::string& source = "<text>",
                                     const OccupancyGrid* grid = nullptr, std::string_view mapName = {});
Expected<ScenFile> loadMovingAiScen(const std::string& path, const OccupancyGrid* grid = nullptr,
                                    std::string_view mapName = {});

}  // namespace fleet::planning
