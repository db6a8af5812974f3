#include "fleet/risk/rle.hpp"

#include <limits>
#include <string>

namespace fleet::risk {

std::vector<LevelRun> encodeRle(std::span<const std::uint8_t> levels) {
  std::vector<LevelRun> runs;
  for (std::uint8_t v : levels) {
    if (!runs.empty() && runs.back().level == v &&
        runs.back().length < std::numeric_limits<std::uint32_t>::max()) {
      ++runs.back().length;
    } else {
      runs.push_back(LevelRun{v, 1});
    }
  }
  return runs;
}

Expected<std::vector<std::uint8_t>> decodeRle(std::span<const LevelRun> runs, std::size_t expectedCells,
                                              int maxLevel) {
  std::size_t total = 0;
  for (std::size_t k = 0; k < runs.size(); ++k) {
    if (runs[k].length == 0) {
      return unexpected("rle_zero_run", "run " + std::to_string(k) + " has length 0");
    }
    if (runs[k].level > maxLevel) {
      return unexpected("rle_bad_level", "run " + std::to_string(k) + " has level " +
                                             std::to_string(runs[k].level) +
                                             " above K = " + std::to_string(maxLevel));
    }
    total += runs[k].length;
    if (total > expectedCells) {
      break;  // checked below; stops a hostile sum from growing further
    }
  }
  if (total != expectedCells) {
    return unexpected("rle_length_mismatch", "runs cover " + std::to_string(total) + " cells, the grid has " +
                                                 std::to_string(expectedCells));
  }
  std::vector<std::uint8_t> out;
  out.reserve(expectedCells);
  for (const auto& r : runs) {
    out.insert(out.end(), r.length, r.level);
  }
  return out;
}

}  // namespace fleet::risk
