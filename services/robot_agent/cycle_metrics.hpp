#pragma once

// The robot agent process's control cycle as measured: the buckets of its cycle-time histogram and
// the process part of the --metrics file.

#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fleet/metrics/histogram.hpp"

namespace fleet::agent {

/// Cycle-time buckets (seconds): 10 µs to ~1.3 s, each 2^(1/4) (~19 %) wider than the one before,
/// so a percentile estimated inside a bucket is off by less than one bucket's width: at most ~19 %
/// of its value (docs/operator-guide.md#metrics).
std::vector<double> cycleBuckets();

/// What the process achieved: cycles, the rate against the configured one, overruns (wall mode)
/// and the wall time of a cycle (all agents stepped and their outputs written), its percentiles
/// estimated from the histogram's buckets (max exact).
nlohmann::json cycleMetrics(const std::string& id, bool lockstep, std::size_t robots, unsigned threads,
                            double dt, std::uint64_t cycles, double elapsedS, std::uint64_t overruns,
                            const metrics::HistogramSnapshot& cycle);

}  // namespace fleet::agent
