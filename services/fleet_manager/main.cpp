// fleet_manager: stores tasks durably (SQLite in WAL mode, or PostgreSQL), assigns them to robots,
// tracks them to the end and re-assigns work when a robot is lost. On PostgreSQL any number of
// managers run against one database; the one holding the lease (manager_lease.hpp) is active, the
// others stand by. Configuration keys: docs/operator-guide.md.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <optional>
#include <thread>

#include "fleet/core/clock.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/fleet/errors.hpp"
#include "fleet/fleet/pg_connection.hpp"
#include "fleet/fleet/postgres_task_store.hpp"
#include "fleet/fleet/site_stations.hpp"
#include "fleet/service/command_line.hpp"
#include "fleet/service/common_options.hpp"
#include "fleet/service/dds_security_check.hpp"
#include "fleet/service/runtime.hpp"
#include "fleet/service/sample_edge.hpp"
#include "fleet/service/service_ops.hpp"
#include "fleet/transport/dds.hpp"
#include "fleet_manager_node.hpp"
#include "manager_lease.hpp"
#include "manager_metrics.hpp"
#include "manager_standby.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

using manager::awaitLease;
using manager::ManagerMetrics;
using manager::openStore;
using manager::pause;
using manager::Recent;

void writeMetrics(const std::string& path, const nlohmann::json& j) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp);
    out << j.dump(2) << "\n";
  }
  std::rename(tmp.c_str(), path.c_str());
}
int run(const manager::Settings& settings, const service::OpsSettings& opsSettings) {
  service::ServiceOps ops("fleet_manager");
  const bool pgStore = settings.store.backend == manager::StoreSettings::Backend::Postgres;
  ops.health().setReady("site", false);
  ops.health().setReady("task_store", false);
  if (pgStore) {
    ops.health().setReady("lease", false);
  }
  if (!ops.start(opsSettings)) {
    return service::kExitUsage;
  }
  auto& activeGauge = ops.registry().gauge(
      "fleet_manager_active",
      "1 on the active manager (the lease holder, or the only one on SQLite), 0 on a standby");
  auto& epochGauge =
      ops.registry().gauge("fleet_manager_lease_epoch", "Epoch of the lease this manager holds (0: none)");
  auto loaded = fleet::loadSiteStations(settings.stationsFile);
  if (!loaded) {
    spdlog::critical("{}", loaded.error().message);
    return 2;
  }
  WallClock wall;
  SimClock sim;
  const bool simClock = settings.clock == "sim";
  const Clock& clock = simClock ? static_cast<const Clock&>(sim) : wall;

  // Travel costs follow paths on the site's map (or its roadmap) when the stations come from a site.
  std::shared_ptr<const site::Site> site;
  if (loaded->site) {
    site = std::make_shared<const site::Site>(std::move(*loaded->site));
  }
  ops.health().setReady("site", true);
  std::optional<manager::ManagerLease> lease;
  if (pgStore) {
    lease.emplace(manager::ManagerLease::Options{
        settings.store.url, settings.store.leaseName, {}, settings.store.leaseTtlS});
    spdlog::info("fleet manager: lease '{}' as {} (ttl {} s, renewed every {} s)", settings.store.leaseName,
                 lease->options().holder, settings.store.leaseTtlS, settings.store.leaseRenewS);
  }

  transport::Participant p;
  transport::Reader<msg::Task> tasks(p);
  transport::Reader<msg::TaskStatus> statuses(p);
  transport::Reader<msg::RobotState> states(p);
  transport::Reader<msg::Clock> clockIn(p);
  transport::Writer<msg::TaskAck> acks(p);
  transport::Writer<msg::TaskEvent> events(p);
  transport::Writer<msg::TaskAssignment> assignments(p);
  // Roadmap closures from operators (the WMS adapter): the stations they close hold back their
  // tasks. Optional, as for the traffic manager, under permissions that predate the reader.
  std::optional<transport::Reader<msg::TrafficClosure>> closuresIn;
  try {
    closuresIn.emplace(p);
  } catch (const std::exception& e) {
    spdlog::warn(
        "fleet manager: run-time closures cannot be read (tasks to closed stations are assigned): {}",
        e.what());
  }
  transport::WaitSet ws(p);
  ws.attach(tasks);
  if (closuresIn) {
    ws.attach(*closuresIn);
  }
  ws.attach(statuses);
  ws.attach(states);
  service::RateLimitedLog badInput;
  validation::Rejections rejections;  // samples refused at the edge, in the metrics as "samples"
  // Every closure heard (by id, the newest), so a manager that becomes active again starts from them.
  std::map<std::string, msg::TrafficClosure> closuresHeard;
  const auto takeClosures = [&](std::vector<msg::TrafficClosure>& fresh) {
    if (closuresIn) {
      for (auto& c : closuresIn->take()) {
        if (validation::admit(c, rejections)) {
          closuresHeard[c.closure_id] = c;
          fresh.push_back(std::move(c));
        }
      }
    }
  };
  std::unique_ptr<manager::FleetManagerNode> active;  // while this manager is active
  auto metrics = [&] {
    auto j = active ? active->metricsJson() : nlohmann::json::object();
    j["active"] = active != nullptr;
    j["samples"] = rejections.toJson();
    return j;
  };
  badInput.onEach([&ops](const std::string& reason) { ops.rejected(reason).inc(); });
  ops.watchMatchedWriters("Task", [&] { return tasks.matchedWriters(); });
  ops.watchMatchedWriters("TaskStatus", [&] { return statuses.matchedWriters(); });
  ops.watchMatchedWriters("RobotState", [&] { return states.matchedWriters(); });
  ops.watchForeign([&] { return states.foreign() + statuses.foreign(); });
  ops.watchMatchedReaders("TaskAck", [&] { return acks.matchedReaders(); });
  ops.watchMatchedReaders("TaskEvent", [&] { return events.matchedReaders(); });
  ops.watchMatchedReaders("TaskAssignment", [&] { return assignments.matchedReaders(); });

  auto send = [&](manager::Outbox& out) {
    for (const auto& a : out.acks) {
      acks.write(a);
    }
    for (const auto& e : out.events) {
      events.write(e);
      logging::ScopedField taskField("task", e.task_id);
      logging::ScopedField robotField("robot", e.robot_id);
      spdlog::debug("task {} {}{}{}", e.task_id, msg::toString(e.state), e.robot_id.empty() ? "" : " robot ",
                    e.robot_id);
    }
    for (const auto& a : out.assignments) {
      assignments.write(a);
    }
    for (const auto& r : out.reconciled) {
      logging::ScopedField taskField("task", r.task);
      logging::ScopedField robotField("robot", r.robot);
      spdlog::warn("{}", r.message);
    }
    out = {};
  };
  std::optional<ManagerMetrics> pm;
  bool exitCode2 = false;
  // A lease's ttl and a poll: what arrived since the active manager's last turn, or just before.
  const auto heldWindow = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(settings.store.leaseTtlS + settings.store.leaseRenewS));
  Recent<msg::Task> heldTasks(heldWindow);
  Recent<msg::TaskStatus> heldStatuses(heldWindow);
  while (!service::stopRequested()) {
    // One activation: open the store, (PostgreSQL) wait for the lease, rebuild from the store as a
    // restarted manager does, run until a stop or until the lease is lost, then stand by again.
    bool stopped = false;
    auto store = openStore(settings, ops, stopped);
    if (!store) {
      exitCode2 = !stopped;
      break;
    }
    ops.health().setReady("task_store", true);
    if (lease) {
      if (!awaitLease(*lease, settings, ops, [&] {
            heldTasks.add(tasks.take());
            heldStatuses.add(statuses.take());
            std::vector<msg::RobotState> gone;
            (void)states.takeWithLifecycle(gone);  // robots report again at once
            (void)clockIn.take();
          })) {
        break;
      }
      static_cast<PostgresTaskStore&>(*store).fenceWith(settings.store.leaseName, lease->epoch());
      spdlog::info("fleet manager: active: lease '{}' epoch {}", settings.store.leaseName, lease->epoch());
    }
    auto created =
        manager::FleetManagerNode::create(settings, loaded->stations, clock.nowNs(), site, std::move(store));
    if (!created) {
      if (created.error().code == errc::kInvalid) {
        spdlog::critical("fleet manager: {}", created.error().message);  // the settings, not the store
        exitCode2 = true;
        break;
      }
      // The store failed while rebuilding (the database went away): try again.
      spdlog::error("fleet manager: cannot rebuild from the task store: {}", created.error().message);
      ops.health().setReady("task_store", false);
      if (lease) {
        lease->release();
      }
      if (!pause(1000ms, ops)) {
        break;
      }
      continue;
    }
    active = std::move(*created);
    auto& node = *active;
    if (lease) {
      node.setEpoch(lease->epoch());  // fences a predecessor that still sends (EpochFence)
    }
    const auto applyClosures = [&](const std::vector<msg::TrafficClosure>& cs, manager::Outbox& into) {
      for (const auto& e : node.onClosures(cs, clock.nowNs(), into)) {
        badInput.warn("closure", "closure refused: " + e);
      }
      if (!cs.empty() && !node.dispatcher().closedStations().empty()) {
        spdlog::warn("fleet manager: stations closed by roadmap closures: {} (their waiting tasks are held)",
                     node.dispatcher().closedStations().size());
      }
    };
    manager::Outbox closedOut;  // published after the recovered state
    {
      std::vector<msg::TrafficClosure> fresh;
      takeClosures(fresh);
      std::vector<msg::TrafficClosure> all;
      for (const auto& [id, c] : closuresHeard) {
        all.push_back(c);
      }
      applyClosures(all, closedOut);
    }
    ops.health().setReady("lease", true);
    activeGauge.set(1);
    epochGauge.set(lease ? static_cast<double>(lease->epoch()) : 0.0);
    pm.emplace(ops);
    node.recordAssignLatencyInto(pm->assignLatency());
    auto& loopSeconds = pm->loopSeconds();
    bool lost = false;
    {
      manager::Outbox rec = node.recovered();
      if (lease && !lease->held()) {
        rec = {};  // the lease lapsed while the node rebuilt: nothing published
      }
      spdlog::info("fleet manager: {} open tasks recovered from {}, re-publishing {} assignments",
                   node.dispatcher().openTasks().size(),
                   pgStore ? pg::redacted(settings.store.url) : settings.db, rec.assignments.size());
      send(rec);
      if (lease && !lease->held()) {
        closedOut = {};
      }
      send(closedOut);
    }
    spdlog::info("fleet manager: {} stations, tick {} s, lease {} s, reconcile {} s, clock {}",
                 node.dispatcher().stations().size(), settings.tickS, settings.leaseS, settings.reconcileS,
                 settings.clock);

    const std::int64_t tickNs = secToNs(settings.tickS);
    std::int64_t nextTick = 0;
    auto lastMetrics = std::chrono::steady_clock::now();
    auto lastLog = lastMetrics;
    manager::Outbox out;
    auto lastRenew = std::chrono::steady_clock::now();
    const auto renewEvery = std::chrono::duration<double>(settings.store.leaseRenewS);
    while (!service::stopRequested()) {
      ws.wait(20ms);
      if (lease) {
        if (std::chrono::steady_clock::now() - lastRenew >= renewEvery) {
          lastRenew = std::chrono::steady_clock::now();
          if (auto r = lease->renew(lastRenew); !r) {
            spdlog::warn("fleet manager: cannot renew the lease: {}", r.error().message);
          }
        }
        if (!lease->held()) {
          lost = true;
          break;
        }
      }
      const auto turnStart = std::chrono::steady_clock::now();
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
      for (auto& r : heldTasks.with(tasks.take())) {
        validation::Rejection why;
        if (validation::admit(r, rejections, &why)) {
          reqs.push_back(std::move(r));
        } else if (isValidId(r.request_id)) {
          // Answered at once, so the adapter need not wait for a timeout to learn it.
          const std::string id = isValidId(r.task_id) ? r.task_id : "";
          const nlohmann::json fields =
              nlohmann::json::array({{{"path", "request"}, {"reason", why.detail}}});
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
      {
        std::vector<msg::TrafficClosure> fresh;
        takeClosures(fresh);
        if (!fresh.empty()) {
          applyClosures(fresh, out);
          changed = true;
        }
      }
      for (const auto& s : service::admitted(heldStatuses.with(statuses.take()), rejections, badInput)) {
        node.onStatus(s, now, out);
        changed = true;
      }
      // Event-driven assignment: new tasks or freed robots are matched at once rather than at the
      // next periodic tick (which still expires leases and handles charging).
      if (now >= nextTick || changed) {
        node.tick(now, out);
        nextTick = now + tickNs;
      }
      if (lease && !lease->held()) {
        // Lost while assigning: nothing of this turn goes out (its store writes were fenced or
        // are the new holder's to find in the store).
        lost = true;
        break;
      }
      send(out);
      loopSeconds.observe(
          std::chrono::duration<double>(std::chrono::steady_clock::now() - turnStart).count());
      if (ops.refresh()) {
        pm->update(node);
      }
      if (!settings.metricsFile.empty() && std::chrono::steady_clock::now() - lastMetrics > 1s) {
        writeMetrics(settings.metricsFile, metrics());
        lastMetrics = std::chrono::steady_clock::now();
      }
      if (std::chrono::steady_clock::now() - lastLog > 10s) {
        spdlog::info("fleet manager: {}", metrics().dump());
        lastLog = std::chrono::steady_clock::now();
      }
    }

    if (!lost) {
      break;
    }
    spdlog::error("fleet manager: lost lease '{}' (epoch {}): stopped publishing, standing by",
                  settings.store.leaseName, lease->epoch());
    ops.health().setReady("lease", false);
    pm->clear();
    activeGauge.set(0);
    epochGauge.set(0);
    active.reset();
  }
  if (lease) {
    lease->release();
  }
  if (exitCode2) {
    return 2;
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
  service::CommonOptions common;
  std::string db;
  std::string stations;
  app.add_option("-c,--config", configPath, "JSON configuration file");
  std::string store;
  app.add_option("--db", db, "SQLite task database (overrides the config)");
  app.add_option("--store", store,
                 "sqlite:PATH or a postgresql:// URL (overrides the config's store and db; default: "
                 "$FLEET_STORE)")
      ->envname("FLEET_STORE");
  app.add_option("--stations", stations,
                 "site.json, or a scenario naming one, or a stations JSON file (overrides the config)");
  service::addCommonOptions(app, common);
  if (auto code = service::parse(app, argc, argv)) {
    return *code;
  }
  try {
    service::setupLogging("fleet_manager", common);
    service::checkDdsSecurity();  // exit 2 naming a missing certificate, key or document
    nlohmann::json overrides = nlohmann::json::object();
    Config cfg =
        configPath.empty() ? Config::fromJson(overrides, "(command line)") : Config::fromFile(configPath);
    nlohmann::json merged = cfg.json();
    if (!db.empty()) {
      merged["db"] = db;
      merged.erase("store");
    }
    if (!store.empty()) {
      merged["store"] = store;
      merged.erase("db");
    }
    if (!stations.empty()) {
      merged["stations"] = stations;
    }
    Config full = Config::fromJson(merged, configPath.empty() ? "(command line)" : configPath);
    const auto settings = manager::readSettings(full);
    full.finish();
    service::installStopHandlers();
    return run(settings, common.ops);
  } catch (const ConfigError& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("fleet manager: {}", e.what());
    return 1;
  }
}
