#pragma once

// The standard `process_*` metrics (as Prometheus' client libraries name them), read from
// /proc/self on each scrape: CPU time, resident and virtual memory, open and allowed file
// descriptors, and the start time. Every service's ops port appends them to its /metrics.

#include <optional>
#include <string>

namespace fleet::service {

struct ProcessStats {
  double cpuSeconds = 0.0;        // user + system time
  double residentBytes = 0.0;     // resident set size
  double virtualBytes = 0.0;      // virtual memory size
  double openFds = 0.0;           // entries of /proc/self/fd
  double maxFds = 0.0;            // soft RLIMIT_NOFILE
  double startTimeSeconds = 0.0;  // since the Unix epoch
};

/// This process's figures, or nothing when /proc/self/stat or /proc/stat cannot be read or parsed
/// (no procfs: the metrics are then left out rather than reported as zero).
[[nodiscard]] std::optional<ProcessStats> readProcessStats();

/// `s` in the Prometheus text format 0.0.4 (HELP, TYPE and one sample per family).
[[nodiscard]] std::string processMetricsText(const ProcessStats& s);

/// readProcessStats() rendered, or "" when it cannot be read.
[[nodiscard]] std::string processMetricsText();

}  // namespace fleet::service
