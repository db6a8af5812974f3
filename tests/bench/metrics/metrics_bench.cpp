// The cost of metrics on a control thread: a histogram sample, a counter increment, a scrape of a
// service-sized registry; beside the robot agent's former cycle-time percentiles (copy and sort
// every sample so far at each write: here after one day at 10 Hz).

#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "fleet/metrics/registry.hpp"

using namespace fleet::metrics;

namespace {
std::vector<double> samples(std::size_t n) {
  std::mt19937 rng(1);
  std::lognormal_distribution<double> d(std::log(2e-3), 0.6);
  std::vector<double> xs(n);
  for (auto& x : xs) {
    x = d(rng);
  }
  return xs;
}
}  // namespace

static void BM_HistogramObserve(benchmark::State& st) {
  Histogram h(exponentialBuckets(1e-5, std::pow(2.0, 0.25), 68));
  const auto xs = samples(4096);
  std::size_t i = 0;
  for (auto _ : st) {
    h.observe(xs[i++ & 4095]);
  }
  st.SetItemsProcessed(st.iterations());
}
BENCHMARK(BM_HistogramObserve);

static void BM_CounterInc(benchmark::State& st) {
  Counter c;
  for (auto _ : st) {
    c.inc();
  }
  benchmark::DoNotOptimize(c.value());
}
BENCHMARK(BM_CounterInc);

static void BM_HistogramPercentiles(benchmark::State& st) {
  Histogram h(exponentialBuckets(1e-5, std::pow(2.0, 0.25), 68));
  for (double x : samples(864000)) {
    h.observe(x);
  }
  for (auto _ : st) {
    const auto s = h.snapshot();
    benchmark::DoNotOptimize(s.quantile(0.5) + s.quantile(0.99));
  }
}
BENCHMARK(BM_HistogramPercentiles);

/// What the agent did before: copy every sample so far and sort them, per metrics write.
static void BM_SortedPercentilesOneDay(benchmark::State& st) {
  const auto xs = samples(864000);  // one day at 10 Hz
  for (auto _ : st) {
    auto copy = xs;
    std::sort(copy.begin(), copy.end());
    benchmark::DoNotOptimize(copy[copy.size() / 2] + copy[copy.size() * 99 / 100]);
  }
  st.SetLabel("864000 samples");
}
BENCHMARK(BM_SortedPercentilesOneDay)->Unit(benchmark::kMillisecond);

/// A scrape of a registry the size of the fleet manager's (about 60 series with buckets).
static void BM_Exposition(benchmark::State& st) {
  Registry r;
  for (const char* o : {"done", "failed", "cancelled", "requeued"}) {
    r.counter("x_tasks_total", "Tasks", {{"outcome", o}}).inc(7);
  }
  for (int i = 0; i < 6; ++i) {
    r.gauge("x_matched", "Matched", {{"topic", "T" + std::to_string(i)}}).set(i);
  }
  r.histogram("x_latency_seconds", "Latency", exponentialBuckets(0.01, 2.0, 16)).observe(0.3);
  r.histogram("x_loop_seconds", "Loop", exponentialBuckets(1e-5, 2.0, 18)).observe(1e-4);
  std::size_t bytes = 0;
  for (auto _ : st) {
    bytes = r.exposition().size();
    benchmark::DoNotOptimize(bytes);
  }
  st.SetLabel(std::to_string(bytes) + " bytes");
}
BENCHMARK(BM_Exposition)->Unit(benchmark::kMicrosecond);

BENCHMARK_MAIN();
