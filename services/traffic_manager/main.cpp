// traffic_manager: plans every robot's moves together on the site's roadmap and releases each
// robot its route a few nodes at a time (TrafficRelease), from the robots' TrafficProgress. See
// docs/operator-guide.md for the configuration keys.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <fstream>
#include <optional>
#include <vector>

#include "fleet/core/clock.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/fleet/site_stations.hpp"
#include "fleet/risk/risk_lookup_of.hpp"
#include "fleet/service/clocked_loop.hpp"
#include "fleet/service/command_line.hpp"
#include "fleet/service/common_options.hpp"
#include "fleet/service/dds_security_check.hpp"
#include "fleet/service/runtime.hpp"
#include "fleet/service/sample_edge.hpp"
#include "fleet/service/service_ops.hpp"
#include "fleet/service/step_order.hpp"
#include "fleet/transport/dds.hpp"
#include "traffic_node.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

std::string cutOffText(const std::vector<std::string>& stations) {
  std::string out;
  for (const auto& st : stations)
    out += (out.empty() ? "; stations cut off: " : ", ") + st;
  return out;
}

traffic::BaseEnds fleetBaseEnds(const std::map<std::string, traffic::BaseEnds>& byRobot) {
  traffic::BaseEnds all;
  for (const auto& [robot, b] : byRobot)
    all += b;
  return all;
}

int run(const site::Site& site, const trafficmgr::Settings& settings, const std::string& id,
        const service::OpsSettings& opsSettings) {
  service::ServiceOps ops("traffic_manager");
  auto& tickSeconds =
      ops.registry().histogram("traffic_manager_tick_seconds", "Wall time of one planning tick (all robots)",
                               metrics::exponentialBuckets(1e-5, 2.0, 20));
  auto& releasesSent =
      ops.registry().counter("traffic_manager_releases_total", "TrafficRelease samples sent");
  auto& robotsKnown =
      ops.registry().gauge("traffic_manager_robots", "Robots by state in the planner", {{"state", "known"}});
  auto& robotsPlaced =
      ops.registry().gauge("traffic_manager_robots", "Robots by state in the planner", {{"state", "placed"}});
  WallClock wall;
  // The incarnation: robots tell a restarted manager's releases from the previous one's. In
  // lockstep it comes from the seed, so that two runs are byte-identical; a restarted one takes the
  // next after the robots' (TrafficNode::onProgress, before its first release).
  const auto epoch = settings.lockstep
                         ? static_cast<std::uint32_t>((settings.traffic.pibt.seed % 0x3fffffffULL) * 2 + 1)
                         : static_cast<std::uint32_t>((wall.nowNs() / 1'000'000) & 0x7fffffff) | 1U;
  trafficmgr::TrafficNode node(site, settings, epoch);
  const auto& rm = node.roadmap();
  spdlog::info(
      "traffic manager: site '{}', roadmap {} nodes, {} edges, {} stations, epoch {}, planner core {}",
      site.name, rm.graph.size(), rm.edgeCount(), rm.stations.size(), epoch,
      traffic::toString(settings.traffic.core));
  // A roadmap error (a station with no way in or out, a line whose robots cut others off) is the
  // site's: refused at start, each named by its key path, as `fleetctl site check` does, before the
  // ops port answers /livez. Warnings are said and planned with.
  std::size_t errors = 0;
  for (const auto& p : rm.problems) {
    if (p.severity == traffic::RoadmapProblem::Severity::Error) {
      spdlog::critical("traffic manager: {}: {}", settings.site, p.what);
      ++errors;
    } else {
      spdlog::warn("traffic manager: roadmap: {}", p.what);
    }
  }
  if (errors > 0) {
    spdlog::critical(
        "traffic manager: {} refused: {} roadmap error(s) (`fleetctl site check` names them too)",
        settings.site, errors);
    return service::kExitUsage;
  }
  if (!ops.start(opsSettings)) {
    return service::kExitUsage;
  }
  transport::Participant p;
  // In lockstep the reader keeps every report of a robot until it is taken (a report of the next step
  // may arrive before this one is taken; keeping the last only, it would replace this one).
  auto progressQos = transport::qos::trafficProgress();
  progressQos.depth = settings.lockstep ? 16 : progressQos.depth;
  transport::Reader<msg::TrafficProgress> progress(p, progressQos);
  transport::Writer<msg::TrafficRelease> releases(p);
  transport::Writer<msg::Roadmap> roadmapOut(p);
  // The risk map is a refinement, not a need: permissions that predate it (DDS Security) leave the
  // traffic manager planning without it, said once, instead of not starting.
  std::optional<transport::Reader<msg::RiskMap>> riskMaps;
  if (settings.riskCostS > 0.0) {
    try {
      riskMaps.emplace(p);
    } catch (const std::exception& e) {
      spdlog::warn("traffic manager: planning without the risk map (risk_cost_s ignored): {}", e.what());
    }
  }
  // Closures come from operators (the WMS adapter); like the risk map, optional under permissions
  // that predate them.
  std::optional<transport::Reader<msg::TrafficClosure>> closuresIn;
  try {
    closuresIn.emplace(p);
  } catch (const std::exception& e) {
    spdlog::warn("traffic manager: run-time closures cannot be read (none will apply): {}", e.what());
  }
  transport::WaitSet ws(p);
  ws.attach(progress);
  if (closuresIn)
    ws.attach(*closuresIn);
  service::RateLimitedLog badInput;
  validation::Rejections rejections;  // refused at the edge, before the node's roadmap checks
  badInput.onEach([&ops](const std::string& reason) { ops.rejected(reason).inc(); });
  ops.watchMatchedWriters("TrafficProgress", [&] { return progress.matchedWriters(); });
  ops.watchForeign([&] { return progress.foreign(); });
  ops.watchMatchedReaders("TrafficRelease", [&] { return releases.matchedReaders(); });
  // The roadmap is built (the node exists): what this service needs to do its job.
  ops.health().setReady("roadmap", node.roadmap().graph.size() > 0);
  service::ClockedLoop loop(p, ws,
                            {settings.clock == "sim", settings.lockstep, id, secToNs(1.0 / settings.rateHz)});
  auto lastStats = std::chrono::steady_clock::now();
  bool roadmapSent = false;

  auto logStats = [&] {
    const auto& c = node.counters();
    const traffic::BaseEnds ends = fleetBaseEnds(node.baseEnds());
    spdlog::info(
        "traffic manager: {} robots ({} placed), {} reports ({} refused), {} releases, {} steps planned, {} "
        "re-plans, {} risk updates, {} yields, {} gave back, tick {:.2f} ms (max {:.2f}), base ends reached "
        "short of the target: {} held by others, {} at the plan's end, {} with more free (late), refused at "
        "the edge: {}",
        node.robotsKnown(), node.robotsPlaced(), c.reports, c.refused, c.releases, c.plannedSteps, c.replans,
        c.riskUpdates, c.yields, c.gaveBack, c.lastTickMs, c.maxTickMs, ends.held, ends.planEnd, ends.limit,
        rejections.toJson().dump());
    // Robots standing still with somewhere to go, and why: the first thing to read when the fleet
    // is slow (a minute of its clock, sim or wall).
    for (const auto& line : node.stalled(loop.now(), 60.0))
      spdlog::warn("traffic manager: {}", line);
  };
  auto takeClosures = [&] {
    if (!closuresIn)
      return;
    for (const auto& c : service::admitted(closuresIn->take(), rejections, badInput)) {
      const auto r = node.onClosure(c);
      if (r.error) {
        badInput.warn("closure:" + c.closure_id, *r.error);
        continue;
      }
      if (!r.changed) {
        spdlog::info("traffic manager: closure '{}' reopened: it was not in force", c.closure_id);
        continue;
      }
      roadmapSent = false;  // published again with the new open flags and revision
      if (c.active) {
        spdlog::warn(
            "traffic manager: closure '{}' in force ({}): {} nodes, {} directed edges closed{}; roadmap "
            "revision {}",
            c.closure_id, c.reason.empty() ? "no reason given" : c.reason, r.nodes, r.edges,
            cutOffText(r.cutOff), node.revision());
      } else {
        spdlog::info("traffic manager: closure '{}' reopened; roadmap revision {}", c.closure_id,
                     node.revision());
      }
    }
  };
  service::StepOrder<msg::TrafficProgress> progressOrder(settings.lockstep);
  auto ingest = [&] {
    takeClosures();
    // Only the newest map matters; a map that does not decode is refused as any bad sample.
    if (auto maps = riskMaps ? riskMaps->take() : std::vector<msg::RiskMap>{};
        !maps.empty() && loop.haveClock()) {
      if (auto risk = risk::riskLookupOf(maps.back())) {
        node.onRiskMap(**risk, loop.now());
      } else {
        badInput.warn("risk_map", "RiskMap ignored: " + risk.error().message);
      }
    }
    // In lockstep a report counts from the step after the one it was made in (StepOrder).
    for (const auto& m :
         progressOrder.due(service::admitted(progress.take(), rejections, badInput), loop.now())) {
      if (!loop.haveClock())
        continue;
      if (auto problem = node.onProgress(m, loop.now())) {
        badInput.warn("progress:" + m.robot_id, *problem);
      }
    }
  };
  auto cycle = [&] {
    if (!roadmapSent) {
      roadmapOut.write(node.roadmapMessage(loop.now()));
      roadmapSent = true;
    }
    const auto t0 = std::chrono::steady_clock::now();
    const auto out = node.tick(loop.now());
    tickSeconds.observe(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    for (const auto& r : out) {
      try {
        releases.write(r);
        releasesSent.inc();
      } catch (const std::exception& e) {
        badInput.warn("release", std::string("release to \"") + r.robot_id + "\" not sent: " + e.what());
      }
    }
  };

  loop.run({ingest, cycle, [&] {
              if (ops.refresh()) {
                robotsKnown.set(static_cast<double>(node.robotsKnown()));
                robotsPlaced.set(static_cast<double>(node.robotsPlaced()));
              }
              if (std::chrono::steady_clock::now() - lastStats > 10s) {
                logStats();
                lastStats = std::chrono::steady_clock::now();
              }
            }});
  logStats();
  if (!settings.summaryFile.empty()) {
    const auto& c = node.counters();
    const auto byRobot = node.baseEnds();
    nlohmann::json ends = nlohmann::json::object();
    for (const auto& [robot, b] : byRobot)
      ends[robot] = {{"held", b.held}, {"plan_end", b.planEnd}, {"limit", b.limit}};
    const traffic::BaseEnds all = fleetBaseEnds(byRobot);
    const nlohmann::json summary = {
        {"reports", c.reports},
        {"refused_reports", c.refused},
        {"releases", c.releases},
        {"planned_steps", c.plannedSteps},
        {"replans", c.replans},
        {"yields", c.yields},
        {"gave_back", c.gaveBack},
        {"max_tick_ms", c.maxTickMs},
        {"base_ends", {{"held", all.held}, {"plan_end", all.planEnd}, {"limit", all.limit}}},
        {"base_ends_by_robot", ends}};
    std::ofstream f(settings.summaryFile);
    f << summary.dump(1) << '\n';
    if (!f)
      spdlog::error("traffic manager: could not write the summary to {}", settings.summaryFile);
  }
  spdlog::info("traffic manager: stopped");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"traffic_manager: plans all robots together on the site's roadmap and releases their routes"};
  std::string configPath;
  std::string sitePath;
  service::CommonOptions common;
  std::string id = "traffic_manager";
  app.add_option("-c,--config", configPath, "JSON configuration file");
  app.add_option("--site", sitePath, "site.json (overrides the config's \"site\")");
  service::addCommonOptions(app, common);
  app.add_option("--id", id, "participant id in lockstep");
  if (auto code = service::parse(app, argc, argv)) {
    return *code;
  }
  try {
    service::setupLogging("traffic_manager", common);
    service::checkDdsSecurity();  // exit 2 naming a missing certificate, key or document
    Config cfg = configPath.empty() ? Config::fromJson(nlohmann::json::object(), "(defaults)")
                                    : Config::fromFile(configPath);
    auto settings = trafficmgr::readSettings(cfg);
    cfg.finish();
    if (!sitePath.empty())
      settings.site = sitePath;
    if (settings.site.empty())
      throw ConfigError({"no site: give --site FILE or \"site\" in the config"});
    const auto site = fleet::loadSiteFile(settings.site);
    if (!site)
      throw ConfigError({site.error().message});
    service::installStopHandlers();
    return run(*site, settings, id, common.ops);
  } catch (const ConfigError& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("traffic manager: {}", e.what());
    return 1;
  }
}
