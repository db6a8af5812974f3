// The WMS adapter's settings (http_api.hpp): `http.*` read and checked, with `events.*` and
// `webhooks.*` (status_routes.hpp).

#include <arpa/inet.h>

#include <cstdlib>

#include "http_api.hpp"
#include "status_routes.hpp"

namespace fleet::wms {

ApiSettings readApiSettings(Config& cfg) {
  ApiSettings s;
  auto& l = s.limits;
  auto h = cfg.child("http");
  h.rejectUnknownKeys({"host", "port", "token_file", "audit_log", "tls_certificate", "tls_key",
                       "max_body_bytes", "max_task_body_bytes", "max_batch", "ack_timeout_ms",
                       "max_in_flight", "threads", "max_connections", "max_streams", "backlog",
                       "request_timeout_ms", "rate_per_client", "rate_burst", "allow_unauthenticated"});
  s.host = h.string("host", s.host);
  s.port = static_cast<int>(h.integer("port", s.port, {0, 65535}));
  l.maxBodyBytes = static_cast<std::size_t>(
      h.integer("max_body_bytes", static_cast<std::int64_t>(l.maxBodyBytes), {1024, 256.0 * 1024 * 1024}));
  s.maxTaskBodyBytes = static_cast<std::size_t>(h.integer(
      "max_task_body_bytes", static_cast<std::int64_t>(s.maxTaskBodyBytes), {1024, 256.0 * 1024 * 1024}));
  s.maxBatch =
      static_cast<std::size_t>(h.integer("max_batch", static_cast<std::int64_t>(s.maxBatch), {1, 100000}));
  s.ackTimeoutMs = static_cast<int>(h.integer("ack_timeout_ms", s.ackTimeoutMs, {1, 600000}));
  l.threads = static_cast<int>(h.integer("threads", l.threads, {1, 256}));
  // Beyond the workers a request would only wait: by default it is refused (429) instead.
  l.maxInFlight = static_cast<int>(h.integer("max_in_flight", l.threads, {1, 100000}));
  l.maxConnections = static_cast<int>(h.integer("max_connections", l.maxConnections, {1, 100000}));
  l.maxStreams = static_cast<int>(h.integer("max_streams", l.maxStreams, {0, 100000}));
  l.backlog = static_cast<int>(h.integer("backlog", l.backlog, {1, 65535}));
  l.requestTimeoutMs = static_cast<int>(h.integer("request_timeout_ms", l.requestTimeoutMs, {100, 600000}));
  l.ratePerClient = h.number("rate_per_client", l.ratePerClient, {0, 1e6});
  l.rateBurst = static_cast<int>(h.integer("rate_burst", l.rateBurst, {1, 1000000}));
  s.auditLog = h.string("audit_log", "");
  s.tls.certificateFile = h.string("tls_certificate", "");
  s.tls.privateKeyFile = h.string("tls_key", "");
  if (s.tls.certificateFile.empty() != s.tls.privateKeyFile.empty()) {
    h.problem("tls_key", "https needs both tls_certificate and tls_key");
  }
  // The deployments of deploy/ require https (FLEET_WMS_TLS=required); their dev overlays say off.
  if (const char* tls = std::getenv("FLEET_WMS_TLS"); tls != nullptr && *tls != '\0') {
    const std::string mode = tls;
    if (mode != "required" && mode != "off") {
      h.problem("tls_certificate", "FLEET_WMS_TLS=\"" + mode + "\": expected required or off");
    } else if (mode == "required" && s.tls.certificateFile.empty() && s.tls.privateKeyFile.empty()) {
      h.problem(
          "tls_certificate",
          "FLEET_WMS_TLS=required, but no certificate is configured: set tls_certificate and tls_key "
          "(scripts/dds-security https DIR wms-adapter HOST ..., docs/operator-guide.md#security), or for "
          "development only set FLEET_WMS_TLS=off (the dev overlays of deploy/)");
    }
  }
  s.tokenFile = h.string("token_file", "");
  if (!s.tokenFile.empty()) {
    if (auto t = TokenStore::fromFile(s.tokenFile); !t) {
      h.problem("token_file", t.error().message);
    }
  } else if (const char* env = std::getenv("FLEET_WMS_TOKEN"); env != nullptr) {
    s.token = env;
  }
  s.allowUnauthenticated = h.boolean("allow_unauthenticated", false);
  readStatusSettings(cfg, s.events, s.webhooks);
  if (s.tokenFile.empty() && s.token.empty() && !isLoopbackHost(s.host) && !s.allowUnauthenticated) {
    h.problem("host", "\"" + s.host +
                          "\" is reachable from other machines and no token is configured (token_file or "
                          "FLEET_WMS_TOKEN): anyone could submit tasks. Configure tokens, listen on "
                          "127.0.0.1, or set \"allow_unauthenticated\": true");
  }
  return s;
}

bool isLoopbackHost(const std::string& host) {
  if (host == "localhost" || host == "::1") {
    return true;
  }
  in_addr a{};
  return inet_pton(AF_INET, host.c_str(), &a) == 1 && (ntohl(a.s_addr) >> 24) == 127;
}

}  // namespace fleet::wms
