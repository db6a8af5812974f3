#include "fleet/core/percentiles.hpp"

#include <algorithm>
#include <cmath>

namespace fleet {

Percentiles percentiles(std::vector<double> values) {
  Percentiles p;
  p.count = values.size();
  if (values.empty()) {
    return p;
  }
  std::sort(values.begin(), values.end());
  auto rank = [&](double q) {
    const auto n = values.size();
    auto k = static_cast<std::size_t>(std::ceil(q * static_cast<double>(n)));
    k = std::clamp<std::size_t>(k, 1, n);
    return values[k - 1];
  };
  p.p50 = rank(0.5);
  p.p90 = rank(0.9);
  p.p99 = rank(0.99);
  p.max = values.back();
  return p;
}

}  // namespace fleet
