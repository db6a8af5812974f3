// Fixed-bucket histograms: bucket boundaries (le), constant memory, quantiles estimated within one
// bucket's width of the exact ones.

#include "fleet/metrics/histogram.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <stdexcept>
#include <thread>
#include <vector>

using namespace fleet::metrics;

TEST(Histogram, SamplesGoToTheFirstBucketWhoseBoundIsNotBelowThem) {
  Histogram h({1.0, 2.0, 4.0});
  h.observe(0.5);
  h.observe(1.0);  // "le": a sample equal to a bound belongs to that bound's bucket
  h.observe(1.5);
  h.observe(4.0);
  h.observe(100.0);
  const auto s = h.snapshot();
  EXPECT_EQ(s.counts, (std::vector<std::uint64_t>{2, 1, 1, 1}));
  EXPECT_EQ(s.count, 5u);
  EXPECT_DOUBLE_EQ(s.sum, 107.0);
  EXPECT_DOUBLE_EQ(s.max, 100.0);
}

TEST(Histogram, NanIsIgnoredAndBadBoundsAreRefused) {
  Histogram h({1.0});
  h.observe(std::nan(""));
  EXPECT_EQ(h.snapshot().count, 0u);
  EXPECT_THROW(Histogram({2.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(Histogram({1.0, 1.0}), std::invalid_argument);
  EXPECT_THROW(Histogram({1.0, INFINITY}), std::invalid_argument);
  EXPECT_THROW(exponentialBuckets(0.0, 2.0, 3), std::invalid_argument);
  EXPECT_THROW(exponentialBuckets(1.0, 1.0, 3), std::invalid_argument);
  EXPECT_THROW(linearBuckets(0.0, 0.0, 3), std::invalid_argument);
}

TEST(Histogram, BucketHelpersGiveTheBoundsAsked) {
  EXPECT_EQ(exponentialBuckets(0.5, 2.0, 4), (std::vector<double>{0.5, 1.0, 2.0, 4.0}));
  EXPECT_EQ(linearBuckets(1.0, 0.5, 3), (std::vector<double>{1.0, 1.5, 2.0}));
}

TEST(Histogram, QuantilesAreWithinOneBucketOfTheExactOnes) {
  // Log-normal samples like cycle times: the estimate of p50/p90/p99 must fall in the bucket of
  // the exact order statistic (an error of at most that bucket's width).
  const auto bounds = exponentialBuckets(1e-5, std::pow(2.0, 0.25), 68);
  Histogram h(bounds);
  std::mt19937 rng(3);
  std::lognormal_distribution<double> d(std::log(2e-3), 0.6);
  std::vector<double> xs(20000);
  for (auto& x : xs) {
    x = d(rng);
    h.observe(x);
  }
  std::sort(xs.begin(), xs.end());
  const auto s = h.snapshot();
  for (double q : {0.5, 0.9, 0.99}) {
    const double exact = xs[static_cast<std::size_t>(q * static_cast<double>(xs.size() - 1))];
    const double est = s.quantile(q);
    const auto b =
        static_cast<std::size_t>(std::lower_bound(bounds.begin(), bounds.end(), exact) - bounds.begin());
    const double lo = b == 0 ? 0.0 : bounds[b - 1];
    EXPECT_GE(est, lo) << "q=" << q;
    EXPECT_LE(est, bounds[b]) << "q=" << q;
    EXPECT_LT(std::abs(est - exact) / exact, std::pow(2.0, 0.25) - 1.0) << "q=" << q;
  }
  EXPECT_DOUBLE_EQ(s.quantile(1.0), xs.back());
  EXPECT_EQ(Histogram({1.0}).snapshot().quantile(0.5), 0.0);
}

TEST(Histogram, ConcurrentUpdatesLoseNoSample) {
  Histogram h(linearBuckets(1.0, 1.0, 8));
  std::vector<std::thread> ts;
  for (int t = 0; t < 4; ++t) {
    ts.emplace_back([&h, t] {
      for (int i = 0; i < 50000; ++i) {
        h.observe(static_cast<double>((i + t) % 10));
      }
    });
  }
  for (auto& t : ts) {
    t.join();
  }
  const auto s = h.snapshot();
  EXPECT_EQ(s.count, 200000u);
  EXPECT_DOUBLE_EQ(s.sum, 4.0 * 5000.0 * 45.0);
}
