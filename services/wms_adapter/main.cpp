// wms_adapter: the HTTP/JSON API a warehouse management system pushes tasks to. A 2xx means the
// fleet manager has stored the task durably. API: docs/openapi.yaml.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <fstream>
#include <thread>

#include "dds_gateway.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/service/runtime.hpp"
#include "fleet/service/site_stations.hpp"
#include "http_api.hpp"

using namespace fleet;

int main(int argc, char** argv) {
  CLI::App app{"wms_adapter: HTTP/JSON task intake for the fleet"};
  std::string configPath;
  std::string level = "info";
  std::string stationsPath;
  int port = -1;
  app.add_option("-c,--config", configPath, "JSON configuration file");
  app.add_option("--stations", stationsPath,
                 "site.json, or a scenario naming one, or a stations JSON file (overrides the config)");
  app.add_option("--port", port, "HTTP port (overrides the config; 0 = any free port)");
  app.add_option("--log-level", level, "trace, debug, info, warn, error, critical, off");
  CLI11_PARSE(app, argc, argv);
  try {
    logging::setup("wms_adapter", level);
    Config cfg = configPath.empty() ? Config::fromJson(nlohmann::json::object(), "(command line)")
                                    : Config::fromFile(configPath);
    cfg.rejectUnknownKeys({"http", "stations"});
    auto api = wms::readApiSettings(cfg);
    if (port >= 0) {
      api.port = port;
    }
    if (stationsPath.empty()) {
      stationsPath = cfg.requireString("stations");
    }
    cfg.finish();
    auto stations = service::loadStationMap(stationsPath);
    if (!stations) {
      throw ConfigError({stations.error().message});
    }
    service::installStopHandlers();
    transport::Participant participant;
    wms::FleetView view;
    wms::DdsGateway gateway(participant, view);
    WallClock clock;
    wms::HttpApi http(api, *stations, gateway, view, clock);
    if (!http.bind()) {
      spdlog::critical("wms adapter: cannot listen on {}:{}", api.host, api.port);
      return 1;
    }
    spdlog::info("wms adapter: listening on http://{}:{} ({} stations, auth {})", api.host, http.port(),
                 stations->size(), api.token.empty() ? "off" : "bearer token");
    std::thread server([&] { http.serve(); });
    while (!service::stopRequested()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
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
