#pragma once

// What every service process shares: stop on SIGINT/SIGTERM, rate-limited warnings for bad input,
// and the clock (wall, or the simulator's Clock topic).

#include <atomic>
#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <string>
#include <unordered_map>

namespace fleet::service {

/// Installs SIGINT/SIGTERM handlers that set the stop flag (once per process).
void installStopHandlers();
[[nodiscard]] bool stopRequested();
void requestStop();

/// Logs at most one line per key per interval, with the number of suppressed occurrences.
/// Counts every occurrence, so dropped-input counters stay exact even when the log is quiet.
class RateLimitedLog {
 public:
  explicit RateLimitedLog(std::chrono::milliseconds interval = std::chrono::seconds(5))
      : interval_(interval) {}
  void warn(const std::string& key, const std::string& message);
  /// Called with the key of every warning, logged or suppressed (e.g. to count rejected samples
  /// by reason in the metrics). Set before use from several threads.
  void onEach(std::function<void(const std::string&)> f) { onEach_ = std::move(f); }
  [[nodiscard]] std::uint64_t count(const std::string& key) const;
  [[nodiscard]] std::uint64_t total() const;

 private:
  struct Entry {
    std::chrono::steady_clock::time_point last{};
    std::uint64_t suppressed = 0;
    std::uint64_t count = 0;
  };
  std::chrono::milliseconds interval_;
  std::function<void(const std::string&)> onEach_;
  mutable std::mutex m_;
  std::unordered_map<std::string, Entry> entries_;
};

}  // namespace fleet::service
