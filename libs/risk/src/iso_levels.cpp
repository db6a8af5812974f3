#include "fleet/risk/iso_levels.hpp"

#include <algorithm>
#include <cmath>

namespace fleet::risk {

double levelUpperBound(int level, int K) {
  return static_cast<double>(level) / static_cast<double>(K);
}

int isoLevel(double p, int K) {
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

LevelGrid classifyLevels(const ProbabilityGrid& grid, int K) {
  LevelGrid out{grid.spec, K, std::vector<std::uint8_t>(grid.p.size(), 0)};
  for (std::size_t i = 0; i < grid.p.size(); ++i) {
    out.level[i] = static_cast<std::uint8_t>(isoLevel(grid.p[i], K));
  }
  return out;
}

std::vector<double> complementMap(const ProbabilityGrid& grid) {
  std::vector<double> out(grid.p.size());
  std::transform(grid.p.begin(), grid.p.end(), out.begin(), [](double p) { return 1.0 - p; });
  return out;
}

}  // namespace fleet::risk
