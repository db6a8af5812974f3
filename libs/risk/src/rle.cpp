#include "fleet/risk/rle.hpp"

#include <cstring>
#include <limits>
#include <string>

namespace fleet::risk {

std::vector<LevelRun> encodeRle(std::span<const std::uint8_t> levels) {
  std::vector<LevelRun> runs;
  constexpr std::size_t kMaxRun = std::numeric_limits<std::uint32_t>::max();
  const std::size_t n = levels.size();
  std::size_t i = 0;
  while (i < n) {
    const std::uint8_t v = levels[i];
    std::size_t j = i + 1;
    // Long runs (most of a risk map is level 0) are extended eight bytes at a time.
    const std::uint64_t pattern = 0x0101010101010101ULL * v;
    while (j + 8 <= n) {
      std::uint64_t word = 0;
      std::memcpy(&word, levels.data() + j, sizeof word);
      if (word != pattern) {
        break;
      }
      j += 8;
    }
    while (j < n && levels[j] == v) {
      ++j;
    }
    std::size_t length = j - i;
    for (; length > kMaxRun; length -= kMaxRun) {
      runs.push_back(LevelRun{v, static_cast<std::uint32_t>(kMaxRun)});
    }
    runs.push_back(LevelRun{v, static_cast<std::uint32_t>(length)});
    i = j;
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
