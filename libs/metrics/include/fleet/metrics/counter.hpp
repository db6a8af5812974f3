#pragma once

// Counter and gauge: one atomic each, so a control thread updates them without a lock and a scrape
// reads them from another thread. Relaxed ordering: a scrape needs each value, not an order between
// them.

#include <atomic>
#include <cstdint>

namespace fleet::metrics {

/// Only goes up (Prometheus resets are process restarts).
class Counter {
 public:
  void inc(std::uint64_t n = 1) { v_.fetch_add(n, std::memory_order_relaxed); }
  [[nodiscard]] std::uint64_t value() const { return v_.load(std::memory_order_relaxed); }

 private:
  std::atomic<std::uint64_t> v_{0};
};

/// A value that goes up and down (queue length, robots in a state, matched readers).
class Gauge {
 public:
  void set(double v) { v_.store(v, std::memory_order_relaxed); }
  void add(double d);
  [[nodiscard]] double value() const { return v_.load(std::memory_order_relaxed); }

 private:
  std::atomic<double> v_{0.0};
};

}  // namespace fleet::metrics
