// risk_map: fuses every source's PredictedDiscs into the collision-probability iso-level map and
// publishes RiskMap at a fixed rate. See docs/operator-guide.md for the configuration keys.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <string>

#include "fleet/core/clock.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/fleet/site_stations.hpp"
#include "fleet/service/clocked_loop.hpp"
#include "fleet/service/command_line.hpp"
#include "fleet/service/common_options.hpp"
#include "fleet/service/dds_security_check.hpp"
#include "fleet/service/runtime.hpp"
#include "fleet/service/sample_edge.hpp"
#include "fleet/service/service_ops.hpp"
#include "fleet/transport/dds.hpp"
#include "risk_map_node.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

int run(const riskmap::Settings& settings, const std::string& id, const service::OpsSettings& opsSettings) {
  service::ServiceOps ops("risk_map");
  ops.health().setReady("published", false);
  if (!ops.start(opsSettings)) {
    return service::kExitUsage;
  }
  auto& fuseSeconds =
      ops.registry().histogram("risk_map_fuse_seconds", "Wall time of one fusion (one RiskMap)",
                               metrics::exponentialBuckets(1e-5, 2.0, 18));
  auto& mapsPublished = ops.registry().counter("risk_map_maps_published_total", "RiskMap samples published");
  auto& samplesAccepted =
      ops.registry().counter("risk_map_samples_accepted_total", "PredictedDiscs samples fused");
  auto& sources =
      ops.registry().gauge("risk_map_sources", "Sources (robots, people trackers) currently fused");
  auto created = riskmap::RiskMapNode::create(settings);
  if (!created) {
    spdlog::critical("risk map: {}", created.error().message);
    return 2;
  }
  auto& node = *created;
  transport::Participant p;
  transport::Reader<msg::PredictedDiscs> discs(p);
  transport::Writer<msg::RiskMap> out(p);
  transport::WaitSet ws(p);
  ws.attach(discs);
  service::ClockedLoop loop(p, ws,
                            {settings.clock == "sim", settings.lockstep, id, secToNs(1.0 / settings.rateHz)});
  service::RateLimitedLog badInput;
  validation::Rejections rejections;  // refused at the edge, before the fusion engine's own checks
  badInput.onEach([&ops](const std::string& reason) { ops.rejected(reason).inc(); });
  ops.watchMatchedWriters("PredictedDiscs", [&] { return discs.matchedWriters(); });
  ops.watchForeign([&] { return discs.foreign(); });
  ops.watchMatchedReaders("RiskMap", [&] { return out.matchedReaders(); });
  auto lastStats = std::chrono::steady_clock::now();
  std::uint64_t published = 0;
  spdlog::info("risk map: {}x{} cells at {} m, K={}, horizon {} x {} s, model {}, {} Hz, clock {}",
               settings.fusion.grid.width, settings.fusion.grid.height, settings.fusion.grid.resolution,
               settings.fusion.levels, settings.fusion.steps, settings.fusion.dt, settings.model,
               settings.rateHz, settings.clock);

  auto ingest = [&] {
    for (const auto& m : service::admitted(discs.take(), rejections, badInput)) {
      if (!loop.haveClock()) {
        continue;
      }
      auto ok = node.accept(m, loop.now());
      if (ok) {
        samplesAccepted.inc();
      } else {
        badInput.warn(ok.error().code,
                      "dropped PredictedDiscs from \"" + m.source_id + "\": " + ok.error().message);
      }
    }
  };
  auto publish = [&] {
    const auto t0 = std::chrono::steady_clock::now();
    try {
      auto map = node.fuse(loop.now());
      fuseSeconds.observe(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      out.write(map);
      ++published;
      mapsPublished.inc();
      ops.health().setReady("published", true);
    } catch (const transport::MessageError& e) {
      // A map over the IDL's bounds (a huge grid of noise): skip it, never stop the service.
      badInput.warn("risk_map_out", std::string("RiskMap not published: ") + e.what());
    }
  };

  loop.run({ingest, publish, [&] {
              if (ops.refresh()) {
                sources.set(static_cast<double>(node.sources()));
              }
              if (std::chrono::steady_clock::now() - lastStats > 10s) {
                std::string reasons;
                for (const auto& [code, n] : node.rejectedByReason()) {
                  reasons += (reasons.empty() ? " (" : ", ") + code + ": " + std::to_string(n);
                }
                if (!reasons.empty()) {
                  reasons += ")";
                }
                spdlog::info(
                    "risk map: {} sources, {} maps published, {} samples accepted, {} rejected{}, {} stale "
                    "dropped, "
                    "refused at the edge: {}",
                    node.sources(), published, node.accepted(), node.rejected(), reasons,
                    node.dropped_stale(), rejections.toJson().dump());
                lastStats = std::chrono::steady_clock::now();
              }
            }});
  spdlog::info("risk map: stopped after {} maps", published);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"risk_map: collision-probability iso-level map service"};
  std::string configPath;
  service::CommonOptions common;
  std::string id = "risk_map";
  app.add_option("-c,--config", configPath, "JSON configuration file");
  service::addCommonOptions(app, common);
  app.add_option("--id", id, "participant id in lockstep");
  if (auto code = service::parse(app, argc, argv)) {
    return *code;
  }
  try {
    service::setupLogging("risk_map", common);
    service::checkDdsSecurity();  // exit 2 naming a missing certificate, key or document
    Config cfg = configPath.empty() ? Config::fromJson(nlohmann::json::object(), "(defaults)")
                                    : Config::fromFile(configPath);
    auto settings = riskmap::readSettings(cfg);
    cfg.finish();
    if (!settings.site.empty()) {
      const auto site = fleet::loadSiteFile(settings.site);
      if (!site) {
        throw ConfigError({site.error().message});
      }
      const auto& m = site->map;
      settings.fusion.grid =
          riskmap::gridOverSite(m.origin(), m.width() * m.resolution(), m.height() * m.resolution(),
                                settings.fusion.grid.resolution);
      spdlog::info("risk map: grid {} x {} cells of {} m over site '{}'", settings.fusion.grid.width,
                   settings.fusion.grid.height, settings.fusion.grid.resolution, site->name);
    }
    service::installStopHandlers();
    return run(settings, id, common.ops);
  } catch (const ConfigError& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("risk map: {}", e.what());
    return 1;
  }
}
