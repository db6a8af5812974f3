// fleet_manager: stores tasks durably (SQLite in WAL mode, or PostgreSQL), assigns them to robots,
// tracks them to the end and re-assigns work when a robot is lost. On PostgreSQL any number of
// managers run against one database; the one holding the lease (manager_lease.hpp) is active, the
// others stand by. Configuration keys: docs/operator-guide.md.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdio>
#include <deque>
#include <fstream>
#include <iterator>
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
  /// A manager that stands by again reports no tasks and no robots (sums over managers count the
  /// active one only).
  void clear() {
    for (auto* g : tasks_) {
      g->set(0);
    }
    for (auto* g : robots_) {
      g->set(0);
    }
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

/// Sleeps `d` in short steps; false when a stop was requested meanwhile.
bool pause(std::chrono::milliseconds d, service::ServiceOps& ops) {
  const auto until = std::chrono::steady_clock::now() + d;
  while (std::chrono::steady_clock::now() < until) {
    if (service::stopRequested()) {
      return false;
    }
    ops.refresh();
    std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(
        100ms, std::max<std::chrono::steady_clock::duration>(until - std::chrono::steady_clock::now(), 0ms)));
  }
  return !service::stopRequested();
}

/// The task store, opened with retries: an unreachable PostgreSQL is waited for with back-off
/// (1 s doubling to 10 s; /readyz says task_store not ready). Null when the store cannot be used
/// (exit 2: a SQLite file that cannot be opened, a schema newer than the binary) or a stop was
/// requested (`stopped`).
std::unique_ptr<TaskStore> openStore(const manager::Settings& settings, service::ServiceOps& ops,
                                     bool& stopped) {
  const bool pgStore = settings.store.backend == manager::StoreSettings::Backend::Postgres;
  const std::string where = pgStore ? pg::redacted(settings.store.url) : settings.db;
  auto backoff = 1000ms;
  for (;;) {
    auto s = manager::openTaskStore(settings);
    if (s) {
      return std::move(*s);
    }
    if (!pgStore || s.error().code != errc::kStorage) {
      spdlog::critical("fleet manager: cannot open task store {}: {}", where, s.error().message);
      return nullptr;
    }
    ops.health().setReady("task_store", false);
    spdlog::warn("fleet manager: task store {} unreachable, not ready, retrying in {} s: {}", where,
                 backoff.count() / 1000.0, s.error().message);
    if (!pause(backoff, ops)) {
      stopped = true;
      return nullptr;
    }
    backoff = std::min(backoff * 2, std::chrono::milliseconds(10000));
  }
}

/// Samples a standby takes off the wire while it waits: its readers' caches must not grow, and the
/// requests and reports of the last `window` are handed to the manager once it is active (the
/// takeover gap loses none; requests are idempotent, a report already applied is refused as stale).
template <class T>
class Recent {
 public:
  explicit Recent(std::chrono::steady_clock::duration window) : window_(window) {}
  void add(std::vector<T> samples) {
    const auto now = std::chrono::steady_clock::now();
    for (auto& s : samples) {
      held_.emplace_back(now, std::move(s));
    }
    while (!held_.empty() && now - held_.front().first > window_) {
      held_.pop_front();
    }
  }
  /// The held samples, oldest first, followed by `fresh`; nothing is held afterwards.
  std::vector<T> with(std::vector<T> fresh) {
    if (held_.empty()) {
      return fresh;
    }
    std::vector<T> out;
    out.reserve(held_.size() + fresh.size());
    for (auto& [at, s] : held_) {
      out.push_back(std::move(s));
    }
    held_.clear();
    std::move(fresh.begin(), fresh.end(), std::back_inserter(out));
    return out;
  }

 private:
  std::chrono::steady_clock::duration window_;
  std::deque<std::pair<std::chrono::steady_clock::time_point, T>> held_;
};

/// Stands by until this manager holds the lease, calling `drain` on every poll; false when a stop
/// was requested.
template <class Drain>
bool awaitLease(manager::ManagerLease& lease, const manager::Settings& settings, service::ServiceOps& ops,
                Drain&& drain) {
  const auto poll = std::chrono::milliseconds(static_cast<int>(settings.store.leaseRenewS * 500));
  bool said = false;
  std::string lastError;
  for (;;) {
    auto got = lease.tryAcquire();
    if (got && *got) {
      return true;
    }
    if (!got && got.error().message != lastError) {
      lastError = got.error().message;
      spdlog::warn("fleet manager: cannot reach the lease: {}", lastError);
    } else if (got && !said) {
      said = true;
      spdlog::info("fleet manager: standing by: lease '{}' held by another manager", lease.options().name);
    }
    drain();
    if (!pause(poll, ops)) {
      return false;
    }
  }
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
                 "sqlite:PATH or a postgresql:// URL (overrides the config's store and db)");
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
