#pragma once

// The WMS adapter's HTTP/JSON API (docs/openapi.yaml). Listens on 127.0.0.1 unless configured
// otherwise; with a bearer token configured, every request without it gets 401.

#include <httplib.h>

#include <atomic>
#include <string>

#include "dashboard.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/core/config.hpp"
#include "fleet/fleet/station_map.hpp"
#include "fleet/metrics/registry.hpp"
#include "gateway.hpp"

namespace fleet::wms {

struct ApiSettings {
  std::string host = "127.0.0.1";
  int port = 8080;    // 0 = any free port
  std::string token;  // empty = no authentication
  std::size_t maxBodyBytes = 1 << 20;
  std::size_t maxBatch = 1000;
  int ackTimeoutMs = 5000;
  int maxInFlight = 64;  // concurrent POST/DELETE requests before 429
  int threads = 8;
};

/// Reads `http.*` keys; the token comes from `token_file` (first line) or FLEET_WMS_TOKEN.
ApiSettings readApiSettings(Config& cfg);

struct ApiCounters {
  std::atomic<std::int64_t> requests{0};
  std::atomic<std::int64_t> tasksAccepted{0};
  std::atomic<std::int64_t> tasksDuplicate{0};
  std::atomic<std::int64_t> status2xx{0};
  std::atomic<std::int64_t> status4xx{0};
  std::atomic<std::int64_t> status5xx{0};
};

class HttpApi {
 public:
  HttpApi(ApiSettings settings, const StationMap& stations, TaskGateway& gateway, FleetView& view,
          const Clock& clock);
  /// Binds the socket; false when the address is taken. port() tells the port bound.
  bool bind();
  [[nodiscard]] int port() const { return port_; }
  /// Serves until stop() (blocking).
  void serve();
  void stop();
  [[nodiscard]] const ApiCounters& counters() const { return counters_; }
  /// Counts responses by status code and times requests in `registry` (the ops port's), and
  /// writes one access-log line per request at info level. Call before serve().
  void instrument(metrics::Registry& registry);
  /// The operator dashboard served with the API (dashboard.hpp).
  [[nodiscard]] Dashboard& dashboard() { return *dashboard_; }

 private:
  void routes();
  void postTasks(const httplib::Request& req, httplib::Response& res);
  void deleteTask(const httplib::Request& req, httplib::Response& res);
  /// A request on task `id` (cancel, pause, resume): a valid id and a reachable manager, else the
  /// 400 / 503 reply is written ("nothing was <verb>") and false returned.
  bool admitTaskRequest(const std::string& id, const char* verb, httplib::Response& res);
  /// POST /v1/tasks/{id}/pause and /resume.
  void controlTask(const httplib::Request& req, httplib::Response& res, bool pause);
  std::string nextRequestId();

  ApiSettings settings_;
  const StationMap& stations_;
  TaskGateway& gateway_;
  FleetView& view_;
  const Clock& clock_;
  httplib::Server server_;
  int port_ = 0;
  std::atomic<int> inFlight_{0};
  std::atomic<std::uint64_t> requestCounter_{0};
  std::string instance_;
  ApiCounters counters_;
  std::unique_ptr<Dashboard> dashboard_;
  metrics::Registry* registry_ = nullptr;
  metrics::Histogram* requestSeconds_ = nullptr;
};

}  // namespace fleet::wms
