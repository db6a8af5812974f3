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
#include "fleet/fleet/errors.hpp"
#include "fleet/service/command_line.hpp"
#include "fleet/service/common_options.hpp"
#include "fleet/service/dds_security_check.hpp"
#include "fleet/service/runtime.hpp"
#include "fleet/service/sample_edge.hpp"
#include "fleet/service/service_ops.hpp"
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

/// The manager's Prometheus metrics, mirrored from the node once a second (the node counts in plain
/// integers on the loop's thread; the registry's counters advance by the difference).
class ManagerMetrics {
 public:
  explicit ManagerMetrics(service::ServiceOps& ops) : r_(ops.registry()) {
    for (const char* outcome : {"done", "failed", "cancelled", "requeued"}) {
      outcomes_.push_back({&r_.counter("fleet_manager_tasks_total",
                                       "Tasks that reached an outcome (requeued: given back to the queue)",
                                       {{"outcome", outcome}})});
    }
    for (const char* result : {"stored", "duplicate", "rejected"}) {
      requests_.push_back({&r_.counter("fleet_manager_task_requests_total",
                                       "Task requests received over DDS, by result", {{"result", result}})});
    }
    for (const char* action : {"requeued", "stale_report"}) {
      reconciled_.push_back({&r_.counter(
          "fleet_manager_reconciled_total",
          "Robots whose reported task disagreed with the store for reconcile_s: their task requeued, or "
          "a stale report logged",
          {{"action", action}})});
    }
    for (const char* state : {"queued", "active"}) {
      tasks_.push_back(
          &r_.gauge("fleet_manager_tasks", "Open tasks: queued (waiting) or active", {{"state", state}}));
    }
    for (const char* state : {"idle", "busy", "lost", "fault"}) {
      robots_.push_back(
          &r_.gauge("fleet_manager_robots", "Robots known to the manager, by state", {{"state", state}}));
    }
  }
  metrics::Histogram& assignLatency() {
    return r_.histogram("fleet_manager_assign_latency_seconds",
                        "Time from queued to assigned, per assignment",
                        manager::FleetManagerNode::assignLatencyBuckets());
  }
  metrics::Histogram& loopSeconds() {
    return r_.histogram("fleet_manager_loop_seconds",
                        "Wall time of one turn of the manager's loop (work only)",
                        metrics::exponentialBuckets(1e-5, 2.0, 18));
  }
  void update(const manager::FleetManagerNode& node) {
    const auto& c = node.dispatcher().counters();
    const auto& m = node.metrics();
    outcomes_[0].to(c.done);
    outcomes_[1].to(c.failed);
    outcomes_[2].to(c.cancelled);
    outcomes_[3].to(c.requeued);
    requests_[0].to(m.stored);
    requests_[1].to(m.duplicates);
    requests_[2].to(m.rejected);
    reconciled_[0].to(m.reconciledRequeued);
    reconciled_[1].to(m.reconciledStale);
    tasks_[0]->set(static_cast<double>(node.dispatcher().waitingCount()));
    tasks_[1]->set(static_cast<double>(node.dispatcher().activeCount()));
    double idle = 0;
    double busy = 0;
    double lost = 0;
    double fault = 0;
    for (const auto& r : node.dispatcher().robots().all()) {
      (r.lost ? lost : (r.fault ? fault : (r.taskId.empty() ? idle : busy))) += 1.0;
    }
    robots_[0]->set(idle);
    robots_[1]->set(busy);
    robots_[2]->set(lost);
    robots_[3]->set(fault);
  }

 private:
  /// A counter following a cumulative count kept elsewhere.
  struct Mirrored {
    metrics::Counter* counter;
    std::int64_t last = 0;
    void to(std::int64_t now) {
      if (now > last) {
        counter->inc(static_cast<std::uint64_t>(now - last));
        last = now;
      }
    }
  };
  metrics::Registry& r_;
  std::vector<Mirrored> outcomes_;
  std::vector<Mirrored> requests_;
  std::vector<Mirrored> reconciled_;
  std::vector<metrics::Gauge*> tasks_;
  std::vector<metrics::Gauge*> robots_;
};

int run(const manager::Settings& settings, const service::OpsSettings& opsSettings) {
  service::ServiceOps ops("fleet_manager");
  ops.health().setReady("site", false);
  ops.health().setReady("task_store", false);
  if (!ops.start(opsSettings)) {
    return service::kExitUsage;
  }
  auto loaded = service::loadSiteStations(settings.stationsFile);
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
  auto created =
      manager::FleetManagerNode::create(settings, std::move(loaded->stations), clock.nowNs(), site);
  if (!created) {
    if (created.error().code == errc::kInvalid) {
      spdlog::critical("fleet manager: {}", created.error().message);  // the settings, not the store
    } else {
      spdlog::critical("fleet manager: cannot open task store {}: {}", settings.db, created.error().message);
    }
    return 2;
  }
  auto& node = **created;
  ops.health().setReady("site", true);
  ops.health().setReady("task_store", true);
  ManagerMetrics pm(ops);
  node.recordAssignLatencyInto(pm.assignLatency());
  auto& loopSeconds = pm.loopSeconds();

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
  {
    manager::Outbox rec = node.recovered();
    spdlog::info("fleet manager: {} open tasks recovered from {}, re-publishing {} assignments",
                 node.dispatcher().openTasks().size(), settings.db, rec.assignments.size());
    send(rec);
  }
  spdlog::info("fleet manager: {} stations, tick {} s, lease {} s, reconcile {} s, clock {}",
               node.dispatcher().stations().size(), settings.tickS, settings.leaseS, settings.reconcileS,
               settings.clock);

  const std::int64_t tickNs = secToNs(settings.tickS);
  std::int64_t nextTick = 0;
  auto lastMetrics = std::chrono::steady_clock::now();
  auto lastLog = lastMetrics;
  manager::Outbox out;
  while (!service::stopRequested()) {
    ws.wait(20ms);
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
    loopSeconds.observe(std::chrono::duration<double>(std::chrono::steady_clock::now() - turnStart).count());
    if (ops.refresh()) {
      pm.update(node);
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
  app.add_option("--db", db, "SQLite task database (overrides the config)");
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
