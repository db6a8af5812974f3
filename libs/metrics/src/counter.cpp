#include "fleet/metrics/counter.hpp"

namespace fleet::metrics {

void Gauge::add(double d) {
  // A compare-exchange loop rather than atomic<double>::fetch_add: the same cost here and no
  // dependence on libatomic for floating-point read-modify-write.
  double cur = v_.load(std::memory_order_relaxed);
  while (!v_.compare_exchange_weak(cur, cur + d, std::memory_order_relaxed)) {
  }
}

}  // namespace fleet::metrics
