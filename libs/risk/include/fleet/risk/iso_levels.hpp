#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include "fleet/risk/grid.hpp"

namespace fleet::risk {

/// Largest K the wire and LevelGrid (one byte per cell) carry.
inline constexpr int kMaxLevels = 255;

/// Iso-level of def. 3.6 with p_l = l/K: 0 for p ≤ 0 (and NaN), else the l in 1..K with
/// p_{l−1} < p ≤ p_l. The boundaries are compared as l/K doubles, so p = 0.3, K = 10 is level 3
/// (ceil(0.3·10) would give 4). Eq. (3.9) prints p_l = 1/l; see docs/algorithms.md.
/// Upper probability bound p_l = l/K of level l (level l ≥ 1 holds (p_{l−1}, p_l]; level 0 is {0}).
inline double levelUpperBound(int level, int K) {
  return static_cast<double>(level) / static_cast<double>(K);
}

inline int isoLevel(double p, int K) {
  if (!(p > 0.0) || K <= 0) {
    return 0;
  }
  if (p >= 1.0) {
    return K;
  }
  // ceil(p·K) is right up to one rounding step; settle it against the exact boundaries l/K.
  int l = std::clamp(static_cast<int>(std::ceil(p * static_cast<double>(K))), 1, K);
  while (l > 1 && p <= levelUpperBound(l - 1, K)) {
    --l;
  }
  while (l < K && p > levelUpperBound(l, K)) {
    ++l;
  }
  return l;
}

/// Cell levels of a probability grid: the partition S_0 … S_K of def. 3.6.
struct LevelGrid {
  GridSpec spec;
  int levels = 10;                  // K
  std::vector<std::uint8_t> level;  // row-major, values 0..K
};

LevelGrid classifyLevels(const ProbabilityGrid& grid, int K);

/// The complement map 1 − P of §3.2.3 (the "safety" the avoidance step maximises).
std::vector<double> complementMap(const ProbabilityGrid& grid);

}  // namespace fleet::risk
