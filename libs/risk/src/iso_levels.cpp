#include "fleet/risk/iso_levels.hpp"

#include <algorithm>
#include <cmath>

namespace fleet::risk {

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
