#pragma once

// The ops port every service opens when asked (--metrics-port): GET /metrics (Prometheus text
// 0.0.4), /livez and /readyz (Health). No authentication and nothing secret: it listens on loopback
// unless --metrics-host says otherwise, and a site exposes it to its scraper only.

#include <memory>
#include <optional>
#include <string>
#include <thread>

#include "fleet/metrics/registry.hpp"
#include "fleet/service/health.hpp"

namespace httplib {
class Server;
}

namespace fleet::service {

/// cpp-httplib's default socket options set SO_REUSEPORT, so a second process binds a port already
/// taken and the two share its connections silently. This keeps SO_REUSEADDR only: a taken port is
/// an error at bind time.
void bindExclusively(httplib::Server& server);

struct OpsSettings {
  std::string host = "127.0.0.1";
  int port = -1;  // -1: no ops port; 0: any free port
};

class OpsServer {
 public:
  OpsServer(const metrics::Registry& registry, const Health& health);
  ~OpsServer();
  OpsServer(const OpsServer&) = delete;
  OpsServer& operator=(const OpsServer&) = delete;

  /// Binds and serves on a thread of its own; the error (one line) when the port cannot be bound.
  [[nodiscard]] std::optional<std::string> start(const OpsSettings& s);
  [[nodiscard]] int port() const { return port_; }
  void stop();

 private:
  const metrics::Registry& registry_;
  const Health& health_;
  std::unique_ptr<httplib::Server> server_;
  std::thread thread_;
  int port_ = -1;
};

}  // namespace fleet::service
