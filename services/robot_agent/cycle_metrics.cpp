#include "cycle_metrics.hpp"

#include <cmath>

namespace fleet::agent {

std::vector<double> cycleBuckets() {
  return metrics::exponentialBuckets(1e-5, std::pow(2.0, 0.25), 68);
}

nlohmann::json cycleMetrics(const std::string& id, bool lockstep, std::size_t robots, unsigned threads,
                            double dt, std::uint64_t cycles, double elapsedS, std::uint64_t overruns,
                            const metrics::HistogramSnapshot& cycle) {
  return nlohmann::json{
      {"id", id},
      {"clock", lockstep ? "lockstep" : "wall"},
      {"robots", robots},
      {"threads", threads},
      {"configured_hz", dt > 0.0 ? 1.0 / dt : 0.0},
      {"cycles", cycles},
      {"elapsed_s", elapsedS},
      {"achieved_hz", elapsedS > 0.0 ? static_cast<double>(cycles) / elapsedS : 0.0},
      {"overruns", overruns},
      {"cycle_ms",
       {{"p50", cycle.quantile(0.5) * 1e3}, {"p99", cycle.quantile(0.99) * 1e3}, {"max", cycle.max * 1e3}}}};
}

}  // namespace fleet::agent
