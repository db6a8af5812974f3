#pragma once

// Nearest-rank percentiles of a sample, for reports (load test latencies, the simulator's
// order-to-motion times): each figure is one of the samples, never an interpolation.

#include <cstddef>
#include <vector>

namespace fleet {

struct Percentiles {
  std::size_t count = 0;
  double p50 = 0, p90 = 0, p99 = 0, max = 0;
};

/// The ceil(q·n)-th smallest sample for q = 0.5, 0.9, 0.99, and the largest; all 0 when empty.
Percentiles percentiles(std::vector<double> values);

}  // namespace fleet
