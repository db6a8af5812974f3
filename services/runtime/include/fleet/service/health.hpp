#pragma once

// Liveness and readiness of a service, answered on its ops port (/livez, /readyz).
// Liveness: the main loop turned recently (beat()); nothing else is consulted, so a dependency
// being down never gets a healthy process restarted. Readiness: live, and every named condition
// the service registered (DDS matched, database open, site loaded) holds. The answers name the
// conditions only, never configuration or secrets.

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <string>

namespace fleet::service {

struct ProbeAnswer {
  bool ok = false;
  std::string text;  // one line per failed condition, or "ok"
};

class Health {
 public:
  /// Not live when the loop has not turned for `stallAfter`.
  explicit Health(std::chrono::milliseconds stallAfter = std::chrono::seconds(10));
  /// The main loop turned (lock-free; call it every turn).
  void beat();
  /// Sets a readiness condition (registered on first use, not ready until set true).
  void setReady(const std::string& condition, bool ok);
  [[nodiscard]] ProbeAnswer liveness() const;
  [[nodiscard]] ProbeAnswer readiness() const;

 private:
  std::chrono::milliseconds stallAfter_;
  std::atomic<std::int64_t> lastBeatNs_;
  mutable std::mutex m_;
  std::map<std::string, bool> conditions_;
};

}  // namespace fleet::service
