#pragma once

// The WMS adapter's HTTP/JSON API (docs/openapi.yaml). Listens on 127.0.0.1 unless configured
// otherwise; with tokens configured, every request but the health probe needs a bearer token that
// grants the route's scope (read, submit, operate); https with a certificate configured.

#include <atomic>
#include <functional>
#include <memory>
#include <string>

#include "access_control.hpp"
#include "audit_log.hpp"
#include "browser_session.hpp"
#include "dashboard.hpp"
#include "event_log.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/core/config.hpp"
#include "fleet/fleet/station_map.hpp"
#include "fleet/metrics/registry.hpp"
#include "gateway.hpp"
#include "http_names.hpp"
#include "token_store.hpp"
#include "webhooks.hpp"

namespace fleet::wms {

struct ApiSettings {
  std::string host = "127.0.0.1";
  int port = 8080;        // 0 = any free port
  std::string tokenFile;  // tokens with names and scopes, re-read when it changes
  std::string token;      // one token with every scope (FLEET_WMS_TOKEN); neither = no authentication
  std::string auditLog;   // empty: audit lines go to the service log
  bool allowUnauthenticated = false;  // a non-loopback host without tokens starts only with this
  TlsFiles tls;
  ServerLimits limits;
  std::size_t maxBatch = 1000;
  std::size_t maxTaskBodyBytes = 256 * 1024;  // POST /v1/tasks (a batch of max_batch small tasks fits)
  int ackTimeoutMs = 5000;
  EventLogSettings events;   // `events.*`: the durable event log (event_log.hpp)
  WebhookSettings webhooks;  // `webhooks.*` (webhooks.hpp)
};

/// Reads `http.*`, `events.*` and `webhooks.*` keys; without `token_file`, the token comes from
/// FLEET_WMS_TOKEN. A host other than loopback with no token is a problem unless `allow_unauthenticated` is
/// true.
ApiSettings readApiSettings(Config& cfg);
/// True for 127.0.0.0/8, ::1 and "localhost": only this machine can connect.
bool isLoopbackHost(const std::string& host);

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
  /// Throws ConfigError when the token file, the certificate, the audit log or the event log
  /// cannot be used. Feeds `view`'s task events into the event log until destroyed.
  HttpApi(ApiSettings settings, const StationMap& stations, TaskGateway& gateway, FleetView& view,
          const Clock& clock);
  ~HttpApi();
  HttpApi(const HttpApi&) = delete;
  HttpApi& operator=(const HttpApi&) = delete;
  /// Binds the socket; false when the address is taken. port() tells the port bound.
  bool bind();
  [[nodiscard]] int port() const { return server_.port(); }
  /// Serves until stop() (blocking).
  void serve();
  void stop();
  [[nodiscard]] const ApiCounters& counters() const { return counters_; }
  [[nodiscard]] const ServerStats& serverStats() const { return server_.stats(); }
  [[nodiscard]] const TokenStore& tokens() const { return tokens_; }
  /// The scope check every route goes through; for routes that check by themselves.
  [[nodiscard]] const AccessControl& access() const { return access_; }
  /// Counts responses by status code and times requests in `registry` (the ops port's), and
  /// writes one access-log line per request at info level. Call before serve().
  void instrument(metrics::Registry& registry);
  /// Every route served (the API's and the dashboard's), as registered.
  [[nodiscard]] std::vector<HttpServer::RouteInfo> routeTable() const { return server_.routeTable(); }
  /// Called after every response, after the API's own counting and logging (tests check each
  /// response against docs/openapi.yaml with it). Call before serve().
  void watchResponses(std::function<void(const Request&, const Response&)> watcher) {
    watcher_ = std::move(watcher);
  }
  /// The operator dashboard served with the API (dashboard.hpp).
  [[nodiscard]] Dashboard& dashboard() { return *dashboard_; }
  /// The durable log of task transitions the event stream and webhooks serve.
  [[nodiscard]] EventLog& eventLog() { return *events_; }
  [[nodiscard]] Webhooks& webhooks() { return *webhooks_; }

 private:
  void routes();
  void observe(const Request& req, const Response& res, double seconds);
  void postTasks(const Request& req, Response& res);
  void deleteTask(const Request& req, Response& res);
  /// A request on task `id` (cancel, pause, resume, change): a valid id and a reachable manager, else the
  /// 400 / 503 reply is written ("nothing was <verb>") and false returned.
  bool admitTaskRequest(const std::string& id, const char* verb, Response& res);
  /// POST /v1/tasks/{id}/pause and /resume.
  void controlTask(const Request& req, Response& res, bool pause);
  /// PATCH /v1/tasks/{id}: a waiting task's priority and deadline (http_api_change.cpp).
  void patchTask(const Request& req, Response& res);
  /// PUT and DELETE /v1/traffic/closures/{id}.
  void putClosure(const Request& req, Response& res);
  void deleteClosure(const Request& req, Response& res);
  std::string nextRequestId();
  /// /v1/metrics' event_log: the log's ids, failures and the webhooks failing.
  [[nodiscard]] nlohmann::json eventLogJson() const;

  ApiSettings settings_;
  const StationMap& stations_;
  TaskGateway& gateway_;
  FleetView& view_;
  const Clock& clock_;
  TokenStore tokens_;
  BrowserSessions sessions_;  // cookies for the dashboard's page, made from a token
  AccessControl access_{tokens_, &sessions_};
  AuditLog audit_;
  HttpServer server_;
  std::atomic<std::uint64_t> requestCounter_{0};
  std::string instance_;
  ApiCounters counters_;
  std::shared_ptr<SqliteDb> stateDb_;  // the event log and the webhook subscriptions
  std::unique_ptr<EventLog> events_;
  std::unique_ptr<Webhooks> webhooks_;
  std::unique_ptr<Dashboard> dashboard_;
  metrics::Registry* registry_ = nullptr;
  metrics::Histogram* requestSeconds_ = nullptr;
  std::function<void(const Request&, const Response&)> watcher_;
};

}  // namespace fleet::wms
