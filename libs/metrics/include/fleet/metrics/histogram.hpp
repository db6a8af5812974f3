#pragma once

// Fixed-bucket histogram: the bucket bounds are chosen once, so memory is constant and a sample
// costs a binary search over the bounds plus two relaxed atomic additions, whatever the number of
// samples so far. Quantiles are estimated from the buckets (linear inside the bucket), so their error
// is at most the width of the bucket the quantile falls in.

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

namespace fleet::metrics {

/// Upper bounds start, start*factor, ... (count of them), as Prometheus' ExponentialBuckets.
[[nodiscard]] std::vector<double> exponentialBuckets(double start, double factor, int count);
/// Upper bounds start, start+width, ... (count of them).
[[nodiscard]] std::vector<double> linearBuckets(double start, double width, int count);

/// A histogram's counts at one moment: per bucket (not cumulative; the last is +Inf), sum, count.
struct HistogramSnapshot {
  std::vector<double> bounds;
  std::vector<std::uint64_t> counts;  // bounds.size() + 1 entries
  double sum = 0.0;
  std::uint64_t count = 0;
  double max = 0.0;  // the largest sample (0 when empty)
  /// Estimated q-quantile (0 <= q <= 1): linear interpolation inside the bucket it falls in; in the
  /// +Inf bucket the largest sample. 0 when empty.
  [[nodiscard]] double quantile(double q) const;
};

class Histogram {
 public:
  /// `bounds`: strictly increasing finite upper bounds (+Inf is implicit). Throws
  /// std::invalid_argument otherwise.
  explicit Histogram(std::vector<double> bounds);
  /// Records one sample; NaN is ignored (it belongs to no bucket).
  void observe(double v);
  [[nodiscard]] HistogramSnapshot snapshot() const;
  [[nodiscard]] std::span<const double> bounds() const { return bounds_; }

 private:
  std::vector<double> bounds_;
  std::unique_ptr<std::atomic<std::uint64_t>[]> counts_;
  std::atomic<double> sum_{0.0};
  std::atomic<double> max_{0.0};
  std::atomic<std::uint64_t> count_{0};
};

}  // namespace fleet::metrics
