// fleet_manager: stores tasks durably (SQLite, WAL), assigns them to robots, tracks them to the end
// and re-assigns work when a robot is lost. Configuration keys: docs/operator-guide.md.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>

#include "fleet/core/clock.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/service/runtime.hpp"
#include "fleet/service/sample_edge.hpp"
#include "fleet/service/site_stations.hpp"
#include "fleet/transport/dds.hpp"
#include "fleet_manager_node.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

void writeMetrics(const std::string& path, const nlohmann::json& j) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    out << j.dump(2) << "\n";
  }
  std::rename(tmp.c_str(), path.c_str());
}

int run(const manager::Settings& settings) {
  auto loaded = service::loadSiteStations(settings.stationsFile);
  if (!loaded) {
    spdlog::critical("{}", loaded.error().message);
    return 2;
  }
  WallClock wall;
  SimClock sim;
  const bool simClock = settings.clock == "sim";
  const Clock& clock = simClock ? static_cast<const Clock&>(sim) : wall;

  // Travel costs follow paths on the site's map when the stations come from a site.
  std::shared_ptr<const planning::OccupancyGrid> siteMap;
  if (loaded->site) {
    siteMap = std::make_shared<const planning::OccupancyGrid>(loaded->site->drivable());
  }
  auto created =
      manager::FleetManagerNode::create(settings, std::move(loaded->stations), clock.nowNs(), siteMap);
  if (!created) {
    spdlog::critical("fleet manager: cannot open task store {}: {}", settings.db, created.error().message);
    return 2;
  }
  auto& node = **created;

  transport::Participant p;
  transport::Reader<msg::Task> tasks(p);
  transport::Reader<msg::TaskStatus> statuses(p);
  transport::Reader<msg::RobotState> states(p);
  transport::Reader<msg::Clock> clockIn(p);
  transport::Writer<msg::TaskAck> acks(p);
  transport::Writer<msg::TaskEvent> events(p);
  transport::Writer<msg::TaskAssignment> assignments(p);
  transport::WaitSet ws(p);
  ws.attach(tasks);
  ws.attach(statuses);
  ws.attach(states);
  service::RateLimitedLog badInput;
  validation::Rejections rejections;  // samples refused at the edge, in the metrics as "samples"
  auto metrics = [&] {
    auto j = node.metricsJson();
    j["samples"] = rejections.toJson();
    return j;
  };

  auto send = [&](manager::Outbox& out) {
    for (const auto& a : out.acks) {
      acks.write(a);
    }
    for (const auto& e : out.events) {
      events.write(e);
    }
    for (const auto& a : out.assignments) {
      assignments.write(a);
    }
    out = {};
  };
  {
    manager::Outbox rec = node.recovered();
    spdlog::info("fleet manager: {} open tasks recovered from {}, re-publishing {} assignments",
                 node.dispatcher().openTasks().size(), settings.db, rec.assignments.size());
    send(rec);
  }
  spdlog::info("fleet manager: {} stations, tick {} s, lease {} s, clock {}",
               node.dispatcher().stations().size(), settings.tickS, settings.leaseS, settings.clock);

  const std::int64_t tickNs = secToNs(settings.tickS);
  std::int64_t nextTick = 0;
  auto lastMetrics = std::chrono::steady_clock::now();
  auto lastLog = lastMetrics;
  manager::Outbox out;
  while (!service::stopRequested()) {
    ws.wait(20ms);
    for (const auto& c : clockIn.take()) {
      sim.set(c.sim_time_ns);
    }
    const std::int64_t now = clock.nowNs();
    std::vector<msg::RobotState> gone;
    for (const auto& s : service::admitted(states.takeWithLifecycle(gone), rejections, badInput)) {
      node.onRobotState(s, now);
    }
    // DDS liveliness: a robot whose RobotState writer is gone (agent process ended, lease lost) is
    // lost now, without waiting for the state lease.
    for (const auto& g : gone) {
      if (isValidId(g.robot_id)) {
        node.onRobotLost(g.robot_id, now, out);
      }
    }
    std::vector<msg::Task> reqs;
    for (auto& r : tasks.take()) {
      validation::Rejection why;
      if (validation::admit(r, rejections, &why)) {
        reqs.push_back(std::move(r));
      } else if (isValidId(r.request_id)) {
        // Answered at once, so the adapter need not wait for a timeout to learn it.
        const std::string id = isValidId(r.task_id) ? r.task_id : "";
        const nlohmann::json fields = nlohmann::json::array({{{"path", "request"}, {"reason", why.detail}}});
        acks.write({r.request_id, id, msg::AckResult::Invalid, msg::TaskState::Rejected,
                    fields.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), now});
      } else {
        badInput.warn("Task:" + why.reason, "refused Task (cannot be answered): " + why.detail);
      }
    }
    bool changed = !reqs.empty();
    if (!reqs.empty()) {
      node.onRequests(reqs, now, out);
    }
    for (const auto& s : service::admitted(statuses.take(), rejections, badInput)) {
      node.onStatus(s, now, out);
      changed = true;
    }
    // Event-driven assignment: new tasks or freed robots are matched at once rather than at the
    // next periodic tick (which still expires leases and handles charging).
    if (now >= nextTick || changed) {
      node.tick(now, out);
      nextTick = now + tickNs;
    }
    send(out);
    if (!settings.metricsFile.empty() && std::chrono::steady_clock::now() - lastMetrics > 1s) {
      writeMetrics(settings.metricsFile, metrics());
      lastMetrics = std::chrono::steady_clock::now();
    }
    if (std::chrono::steady_clock::now() - lastLog > 10s) {
      spdlog::info("fleet manager: {}", metrics().dump());
      lastLog = std::chrono::steady_clock::now();
    }
  }
  if (!settings.metricsFile.empty()) {
    writeMetrics(settings.metricsFile, metrics());
  }
  spdlog::info("fleet manager: stopped; {}", metrics().dump());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"fleet_manager: durable task store, assignment and tracking"};
  std::string configPath;
  std::string level = "info";
  std::string db;
  std::string stations;
  app.add_option("-c,--config", configPath, "JSON configuration file");
  app.add_option("--db", db, "SQLite task database (overrides the config)");
  app.add_option("--stations", stations,
                 "site.json, or a scenario naming one, or a stations JSON file (overrides the config)");
  app.add_option("--log-level", level, "trace, debug, info, warn, error, critical, off");
  CLI11_PARSE(app, argc, argv);
  try {
    logging::setup("fleet_manager", level);
    nlohmann::json overrides = nlohmann::json::object();
    Config cfg =
        configPath.empty() ? Config::fromJson(overrides, "(command line)") : Config::fromFile(configPath);
    nlohmann::json merged = cfg.json();
    if (!db.empty()) {
      merged["db"] = db;
    }
    if (!stations.empty()) {
      merged["stations"] = stations;
    }
    Config full = Config::fromJson(merged, configPath.empty() ? "(command line)" : configPath);
    const auto settings = manager::readSettings(full);
    full.finish();
    service::installStopHandlers();
    return run(settings);
  } catch (const ConfigError& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("fleet manager: {}", e.what());
    return 1;
  }
}
