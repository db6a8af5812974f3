// wms_adapter: the HTTP/JSON API a warehouse management system pushes tasks to. A 2xx means the
// fleet manager has stored the task durably. API: docs/openapi.yaml.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <fstream>
#include <map>
#include <thread>

#include "dds_gateway.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/fleet/pg_connection.hpp"
#include "fleet/fleet/site_stations.hpp"
#include "fleet/service/command_line.hpp"
#include "fleet/service/common_options.hpp"
#include "fleet/service/dds_security_check.hpp"
#include "fleet/service/runtime.hpp"
#include "fleet/service/service_ops.hpp"
#include "http_api.hpp"
#include "postgres_event_store.hpp"

using namespace fleet;

namespace {

/// The shared event log's database (adapter replicas, events.log a postgresql:// URL), tried until
/// it answers: 1 s doubling to 10 s, one line per try naming the URL without its password; not
/// ready meanwhile (the API is not served). A malformed URL stops the start (exit 2). False when
/// stopped while waiting.
bool waitForEventDatabase(const std::string& url) {
  if (auto ok = fleet::pg::checkUrl(url); !ok) {
    throw fleet::ConfigError({"events.log: " + ok.error().message});
  }
  for (double wait = 1.0;; wait = std::min(10.0, wait * 2)) {
    fleet::pg::Connection probe(url);
    const auto ok = probe.ensure();
    if (ok) {
      spdlog::info("wms adapter: event log on {} (shared by the adapters on it)", fleet::pg::redacted(url));
      return true;
    }
    spdlog::warn("wms adapter: events.log {}: {}; trying again in {:.0f} s", fleet::pg::redacted(url),
                 ok.error().message, wait);
    for (int k = 0; k < static_cast<int>(wait * 10); ++k) {
      if (fleet::service::stopRequested()) {
        return false;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
  }
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"wms_adapter: HTTP/JSON task intake for the fleet"};
  std::string configPath;
  service::CommonOptions common;
  std::string stationsPath;
  int port = -1;
  std::string eventsLog;
  app.add_option("-c,--config", configPath, "JSON configuration file");
  app.add_option("--stations", stationsPath,
                 "site.json, or a scenario naming one, or a stations JSON file (overrides the config)");
  app.add_option("--port", port, "HTTP port (overrides the config; 0 = any free port)");
  app.add_option("--events-log", eventsLog,
                 "SQLite file of the event log and the webhook subscriptions (overrides the config's "
                 "events.log; on a writable volume, event ids and webhooks survive a restart), or a "
                 "postgresql:// URL that adapter replicas share; default: $FLEET_EVENTS_LOG")
      ->envname("FLEET_EVENTS_LOG");
  service::addCommonOptions(app, common);
  if (auto code = service::parse(app, argc, argv)) {
    return *code;
  }
  try {
    service::setupLogging("wms_adapter", common);
    service::checkDdsSecurity();  // exit 2 naming a missing certificate, key or document
    Config cfg = configPath.empty() ? Config::fromJson(nlohmann::json::object(), "(command line)")
                                    : Config::fromFile(configPath);
    cfg.rejectUnknownKeys({"http", "stations", "events", "webhooks"});
    auto api = wms::readApiSettings(cfg);
    if (port >= 0) {
      api.port = port;
    }
    if (!eventsLog.empty()) {
      api.events.path = eventsLog;
    }
    if (stationsPath.empty()) {
      stationsPath = cfg.requireString("stations");
    }
    cfg.finish();
    auto stations = fleet::loadStationMap(stationsPath);
    if (!stations) {
      throw ConfigError({stations.error().message});
    }
    service::installStopHandlers();
    service::ServiceOps ops("wms_adapter");
    ops.health().setReady("fleet_manager", false);
    if (!ops.start(common.ops)) {
      return service::kExitUsage;
    }
    if (wms::isPostgresUrl(api.events.path) && !waitForEventDatabase(api.events.path)) {
      return 0;  // stopped while waiting
    }
    transport::Participant participant;
    wms::FleetView view;
    wms::DdsGateway gateway(participant, view);
    WallClock clock;
    wms::HttpApi http(api, *stations, gateway, view, clock);
    http.instrument(ops.registry());
    http.dashboard().setSite(wms::sitePictureOf(stationsPath));
    if (!http.bind()) {
      spdlog::critical("wms adapter: cannot listen on {}:{}", api.host, api.port);
      return service::kExitUsage;
    }
    spdlog::info("wms adapter: listening on {}://{}:{} ({} stations, auth {}, audit to {})",
                 api.tls.enabled() ? "https" : "http", api.host, http.port(), stations->size(),
                 !http.tokens().enabled() ? "off"
                 : api.tokenFile.empty()  ? "one bearer token (FLEET_WMS_TOKEN)"
                                          : "bearer tokens from " + api.tokenFile,
                 api.auditLog.empty() ? "the service log" : api.auditLog);
    if (!http.tokens().enabled() && api.allowUnauthenticated) {
      spdlog::warn(
          "wms adapter: authentication is OFF on {}:{} (http.allow_unauthenticated): anyone who "
          "reaches this port can submit, cancel and pause tasks",
          api.host, http.port());
    }
    spdlog::info("wms adapter: dashboard at {}://{}:{}/dashboard/", api.tls.enabled() ? "https" : "http",
                 api.host, http.port());
    std::thread server([&] { http.serve(); });
    auto& managerOnline = ops.registry().gauge("wms_adapter_fleet_manager_online",
                                               "1 when the fleet manager answers over DDS, else 0");
    auto& tasksAccepted = ops.registry().counter(
        "wms_adapter_tasks_total", "Tasks posted through the API, by result", {{"result", "accepted"}});
    auto& tasksDuplicate = ops.registry().counter(
        "wms_adapter_tasks_total", "Tasks posted through the API, by result", {{"result", "duplicate"}});
    std::int64_t accepted = 0;
    std::int64_t duplicate = 0;
    // DDS samples refused at the edge (libs/validation) as wms_adapter_rejected_samples_total, by
    // topic as the other services' are (ServiceOps::rejected keeps the key's part before ':').
    std::map<std::string, std::uint64_t> refusedSeen;
    auto exportRefused = [&] {
      const auto j = view.rejections().toJson();
      if (!j.contains("rejected")) {
        return;
      }
      for (const auto& [topic, reasons] : j["rejected"].items()) {
        for (const auto& [reason, n] : reasons.items()) {
          const std::string key = topic + ":" + reason;
          const auto now = n.get<std::uint64_t>();
          auto& seen = refusedSeen[key];
          if (now > seen) {
            ops.rejected(key).inc(now - seen);
            seen = now;
          }
        }
      }
    };
    while (!service::stopRequested()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      if (ops.refresh()) {
        // Readiness is the manager being reachable: without it no task can be stored. Liveness
        // (this loop turning) never depends on it.
        const bool up = gateway.managerOnline();
        ops.health().setReady("fleet_manager", up);
        managerOnline.set(up ? 1.0 : 0.0);
        const auto a = http.counters().tasksAccepted.load();
        const auto d = http.counters().tasksDuplicate.load();
        tasksAccepted.inc(static_cast<std::uint64_t>(a - accepted));
        tasksDuplicate.inc(static_cast<std::uint64_t>(d - duplicate));
        accepted = a;
        duplicate = d;
        exportRefused();
      }
    }
    http.stop();
    server.join();
    spdlog::info("wms adapter: stopped after {} requests", http.counters().requests.load());
    return 0;
  } catch (const ConfigError& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("wms adapter: {}", e.what());
    return 1;
  }
}
