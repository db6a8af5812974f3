#include "fleet/metrics/histogram.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace fleet::metrics {

std::vector<double> exponentialBuckets(double start, double factor, int count) {
  if (!(start > 0.0) || !(factor > 1.0) || count < 1) {
    throw std::invalid_argument("exponentialBuckets: need start > 0, factor > 1, count >= 1");
  }
  std::vector<double> b;
  double v = start;
  for (int i = 0; i < count; ++i) {
    b.push_back(v);
    v *= factor;
  }
  return b;
}

std::vector<double> linearBuckets(double start, double width, int count) {
  if (!(width > 0.0) || count < 1) {
    throw std::invalid_argument("linearBuckets: need width > 0, count >= 1");
  }
  std::vector<double> b;
  for (int i = 0; i < count; ++i) {
    b.push_back(start + width * i);
  }
  return b;
}

Histogram::Histogram(std::vector<double> bounds)
    : bounds_(std::move(bounds)),
      counts_(std::make_unique<std::atomic<std::uint64_t>[]>(bounds_.size() + 1)) {
  for (std::size_t i = 0; i < bounds_.size(); ++i) {
    if (!std::isfinite(bounds_[i]) || (i > 0 && !(bounds_[i] > bounds_[i - 1]))) {
      throw std::invalid_argument("histogram bucket bounds must be finite and strictly increasing (bound " +
                                  std::to_string(i) + ")");
    }
  }
}

namespace {
void atomicAdd(std::atomic<double>& a, double d) {
  double cur = a.load(std::memory_order_relaxed);
  while (!a.compare_exchange_weak(cur, cur + d, std::memory_order_relaxed)) {
  }
}
void atomicMax(std::atomic<double>& a, double v) {
  double cur = a.load(std::memory_order_relaxed);
  while (v > cur && !a.compare_exchange_weak(cur, v, std::memory_order_relaxed)) {
  }
}
}  // namespace

void Histogram::observe(double v) {
  if (std::isnan(v)) {
    return;
  }
  // Prometheus buckets are "less than or equal": the first bound >= v.
  const auto i =
      static_cast<std::size_t>(std::lower_bound(bounds_.begin(), bounds_.end(), v) - bounds_.begin());
  counts_[i].fetch_add(1, std::memory_order_relaxed);
  atomicAdd(sum_, v);
  atomicMax(max_, v);
  count_.fetch_add(1, std::memory_order_relaxed);
}

HistogramSnapshot Histogram::snapshot() const {
  HistogramSnapshot s;
  s.bounds = bounds_;
  s.counts.resize(bounds_.size() + 1);
  // The total is the sum of the buckets read, so a scrape during updates is still self-consistent
  // (_count equals the +Inf bucket), which promtool and PromQL's histogram_quantile rely on.
  for (std::size_t i = 0; i <= bounds_.size(); ++i) {
    s.counts[i] = counts_[i].load(std::memory_order_relaxed);
    s.count += s.counts[i];
  }
  s.sum = sum_.load(std::memory_order_relaxed);
  s.max = max_.load(std::memory_order_relaxed);
  return s;
}

double HistogramSnapshot::quantile(double q) const {
  if (count == 0) {
    return 0.0;
  }
  q = std::clamp(q, 0.0, 1.0);
  const double rank = q * static_cast<double>(count);
  std::uint64_t below = 0;
  for (std::size_t i = 0; i < counts.size(); ++i) {
    if (counts[i] == 0 || static_cast<double>(below + counts[i]) < rank) {
      below += counts[i];
      continue;
    }
    if (i == bounds.size()) {
      return max;  // beyond the last bound: the largest sample is the best estimate there is
    }
    const double lo = i == 0 ? std::min(0.0, bounds[0]) : bounds[i - 1];
    const double hi = bounds[i];
    const double frac = (rank - static_cast<double>(below)) / static_cast<double>(counts[i]);
    return std::min(lo + (hi - lo) * std::clamp(frac, 0.0, 1.0), max);
  }
  return max;
}

}  // namespace fleet::metrics
