#pragma once

// The ops port every service opens when asked (--metrics-port): GET /metrics (Prometheus text
// 0.0.4: the registry, then the process_* metrics of process_metrics.hpp), /livez and /readyz
// (Health). No authentication and nothing secret: it listens on loopback unless --metrics-host
// says otherwise, and a site exposes it to its scraper only.
//
// One thread serves every connection with poll(2), non-blocking: each answer is a few atomic loads
// (or the exposition text), so no client waits behind another's handler, and a slow client holds
// no thread. What a client cannot do to it:
// - trickle its request: the whole head must arrive within `headerTimeoutMs` of the connection
//   being accepted (however often bytes come), else it is closed;
// - leave an answer unread: an answer must be taken within `writeTimeoutMs`;
// - fill the connection table: beyond `maxConnections` open connections, the one that has waited
//   longest for its head is closed to make room, so a new probe is always read;
// - send a large head: beyond `maxHeaderBytes` the answer is 431.
// Every answer closes its connection (probes and scrapes open one per request anyway).

#include <atomic>
#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "fleet/metrics/registry.hpp"
#include "fleet/service/health.hpp"

namespace fleet::service {

struct OpsSettings {
  std::string host = "127.0.0.1";
  int port = -1;  // -1: no ops port; 0: any free port
};

struct OpsLimits {
  int headerTimeoutMs = 2000;
  int writeTimeoutMs = 5000;
  int maxConnections = 64;
  std::size_t maxHeaderBytes = 8192;
};

class OpsServer {
 public:
  OpsServer(const metrics::Registry& registry, const Health& health, OpsLimits limits = {});
  ~OpsServer();
  OpsServer(const OpsServer&) = delete;
  OpsServer& operator=(const OpsServer&) = delete;

  /// Binds (SO_REUSEADDR only: a port taken by another process is an error, never shared) and
  /// serves on a thread of its own; the error (one line) when the port cannot be bound.
  [[nodiscard]] std::optional<std::string> start(const OpsSettings& s);
  [[nodiscard]] int port() const { return port_; }
  void stop();
  /// Connections closed for a head too slow or an answer not taken, since start.
  [[nodiscard]] std::int64_t timedOut() const { return timedOut_.load(); }
  /// Connections closed to make room for a new one, since start.
  [[nodiscard]] std::int64_t evicted() const { return evicted_.load(); }

 private:
  struct Loop;
  void serve();
  [[nodiscard]] std::string answer(const std::string& head) const;

  const metrics::Registry& registry_;
  const Health& health_;
  OpsLimits limits_;
  int listenFd_ = -1;
  int wakeFd_[2] = {-1, -1};
  std::thread thread_;
  int port_ = -1;
  std::atomic<std::int64_t> timedOut_{0};
  std::atomic<std::int64_t> evicted_{0};
};

}  // namespace fleet::service
