#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "fleet/core/expected.hpp"

namespace fleet::risk {

/// `length` consecutive cells (row-major) at `level`.
struct LevelRun {
  std::uint8_t level = 0;
  std::uint32_t length = 0;
  bool operator==(const LevelRun&) const = default;
};

/// Run-length encoding of a level grid for the wire: maximal runs, row-major, runs may cross rows.
std::vector<LevelRun> encodeRle(std::span<const std::uint8_t> levels);

/// Inverse of encodeRle, checking what a remote writer could get wrong. Error codes: "rle_zero_run",
/// "rle_bad_level" (a level above maxLevel), "rle_length_mismatch" (runs do not cover expectedCells).
Expected<std::vector<std::uint8_t>> decodeRle(std::span<const LevelRun> runs, std::size_t expectedCells,
                                              int maxLevel);

}  // namespace fleet::risk
