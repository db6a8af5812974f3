#include "fleet_manager_node.hpp"

#include "fleet/fleet/task_wire.hpp"
#include "fleet/traffic/roadmap_config.hpp"

#include <algorithm>
#include <cstdio>
#include <fstream>

#include "fleet/core/clock.hpp"
#include "fleet/fleet/errors.hpp"
#include "fleet/fleet/pg_connection.hpp"
#include "fleet/fleet/postgres_task_store.hpp"
#include "fleet/fleet/sqlite_task_store.hpp"
#include "fleet/planning/map_io.hpp"
#include "fleet/traffic/roadmap_travel.hpp"
#include "manager_acks.hpp"
#include "task_goals.hpp"

namespace fleet::manager {

using acks::ack;
using acks::fieldsJson;

Settings readSettings(Config& cfg) {
  Settings s;
  cfg.rejectUnknownKeys({"db",
                         "store",
                         "lease",
                         "stations",
                         "sync",
                         "tick_s",
                         "lease_s",
                         "reconcile_s",
                         "max_attempts",
                         "station_capacity",
                         "station_load",
                         "robot_fail_limit",
                         "robot_hold_s",
                         "battery_threshold",
                         "charge_until",
                         "charge_max_s",
                         "nominal_speed",
                         "clock",
                         "metrics_file",
                         "map",
                         "travel_cost",
                         "roadmap"});
  s.travelCost = cfg.string("travel_cost", s.travelCost, {"path", "straight", "roadmap"});
  s.roadmap = traffic::readRoadmapOptions(cfg.child("roadmap"));
  auto map = cfg.child("map");
  map.rejectUnknownKeys({"file", "resolution", "origin_x", "origin_y"});
  s.mapFile = map.string("file", "");
  s.mapResolution = map.number("resolution", 1.0, {0.0, 100.0, true});
  s.mapOriginX = map.number("origin_x", 0.0, {-1e6, 1e6});
  s.mapOriginY = map.number("origin_y", 0.0, {-1e6, 1e6});
  s.db = cfg.string("db", s.db);
  if (cfg.find("store") != nullptr) {
    if (cfg.find("db") != nullptr) {
      cfg.problem("store", "give either store or db (db is store \"sqlite:PATH\")");
    }
    const std::string store = cfg.string("store", "");
    if (store.starts_with("sqlite:") && store.size() > 7) {
      s.db = store.substr(7);
    } else if (store.starts_with("postgresql://") || store.starts_with("postgres://")) {
      s.store.backend = StoreSettings::Backend::Postgres;
      s.store.url = store;
      if (auto ok = pg::checkUrl(store); !ok) {
        cfg.problem("store", ok.error().message);
      }
    } else {
      cfg.problem("store", "must be \"sqlite:PATH\" or a \"postgresql://...\" URL");
    }
  }
  auto lease = cfg.child("lease");
  lease.rejectUnknownKeys({"ttl_s", "renew_s", "name"});
  s.store.leaseTtlS = lease.number("ttl_s", s.store.leaseTtlS, {0.5, 60.0});
  s.store.leaseRenewS = lease.number("renew_s", s.store.leaseRenewS, {0.05, 30.0});
  if (s.store.leaseRenewS * 2 > s.store.leaseTtlS) {
    lease.problem("renew_s", "must be at most half of ttl_s (a renewal may be late once)");
  }
  s.store.leaseName = lease.string("name", s.store.leaseName);
  s.stationsFile = cfg.requireString("stations");
  s.syncFull = cfg.string("sync", "full", {"full", "normal"}) == "full";
  s.tickS = cfg.number("tick_s", s.tickS, {0.0, 60.0, true});
  s.leaseS = cfg.number("lease_s", s.leaseS, {0.0, 3600.0, true});
  s.reconcileS = cfg.number("reconcile_s", s.reconcileS, {0.0, 3600.0});
  s.maxAttempts = static_cast<int>(cfg.integer("max_attempts", s.maxAttempts, {1, 100}));
  s.robotFailLimit = static_cast<int>(cfg.integer("robot_fail_limit", s.robotFailLimit, {0, 1000}));
  s.robotHoldS = cfg.number("robot_hold_s", s.robotHoldS, {0.0, 86400.0});
  if (const auto* cap = cfg.find("station_capacity"); cap != nullptr && cap->is_string()) {
    // "queue": each station takes as many active tasks as its line on the roadmap holds.
    s.stationCapacityFromLines = cfg.string("station_capacity", "queue", {"queue"}) == "queue";
  } else {
    s.stationCapacity = static_cast<int>(cfg.integer("station_capacity", s.stationCapacity, {0, 1000}));
  }
  {
    static constexpr const char* kLoads[] = {"task", "phase", "arrival"};
    const std::string load =
        cfg.string("station_load", kLoads[static_cast<int>(s.stationLoad)], {"task", "phase", "arrival"});
    for (int i = 0; i < 3; ++i) {
      if (load == kLoads[i]) {
        s.stationLoad = static_cast<StationLoad>(i);
      }
    }
  }
  s.batteryThreshold = cfg.number("battery_threshold", s.batteryThreshold, {0.0, 1.0});
  s.chargeUntil = cfg.number("charge_until", s.chargeUntil, {0.0, 1.0});
  if (s.chargeUntil <= s.batteryThreshold) {
    // Released below (or at) the threshold, a robot would be sent back to charge at once.
    char what[96];
    std::snprintf(what, sizeof what, "must be greater than battery_threshold (%g), got %g",
                  s.batteryThreshold, s.chargeUntil);
    cfg.problem("charge_until", what);
  }
  s.chargeMaxS = cfg.number("charge_max_s", s.chargeMaxS, {0.0, 86400.0, true});
  s.nominalSpeed = cfg.number("nominal_speed", s.nominalSpeed, {0.0, 20.0, true});
  s.clock = cfg.string("clock", "wall", {"wall", "sim"});
  s.metricsFile = cfg.string("metrics_file", "");
  return s;
}

TravelModel makeTravelModel(const StationMap& stations, std::shared_ptr<planning::DistanceFieldCache> cache,
                            double speed) {
  // Stations are copied in: the model outlives the caller's map.
  return [stations, cache, speed](const Task& t) -> RobotTravel {
    std::vector<Vec2> stops;
    for (const auto* name : taskStops(t)) {
      if (const Station* s = stations.find(*name)) {
        stops.push_back(s->pose.position());
      }
    }
    if (stops.empty()) {
      return [](const RobotInfo&) { return 0.0; };  // a charge/park task the dispatcher resolves
    }
    double rest = 0.0;  // the legs between stops do not depend on the robot
    for (std::size_t i = 1; i < stops.size(); ++i) {
      rest += cache ? cache->travelDistance(stops[i - 1], stops[i]) : distance(stops[i - 1], stops[i]);
    }
    if (!cache) {
      return [first = stops[0], rest, speed](const RobotInfo& r) {
        return (distance(r.pose.position(), first) + rest) / speed;
      };
    }
    const auto goal = cache->grid().cellAt(stops[0]);
    if (!goal) {
      return [](const RobotInfo&) { return kInfeasible; };
    }
    auto field = cache->field(*goal);
    const double res = cache->grid().resolution();
    return [field, cache, rest, speed, res](const RobotInfo& r) {
      const auto c = cache->grid().cellAt(r.pose.position());
      const double cells = c ? field->at(*c) : kInfeasible;
      return (cells * res + rest) / speed;
    };
  };
}

TravelModel makeRoadmapTravelModel(const StationMap& stations,
                                   std::shared_ptr<const traffic::RoadmapTravel> roads) {
  return [stations, roads](const Task& t) -> RobotTravel {
    auto stops = taskStops(t);
    std::erase_if(stops, [&](const std::string* name) { return stations.find(*name) == nullptr; });
    if (stops.empty()) {
      return [](const RobotInfo&) { return 0.0; };  // a charge/park task the dispatcher resolves
    }
    double rest = 0.0;
    for (std::size_t i = 1; i < stops.size(); ++i) {
      rest += roads->between(*stops[i - 1], *stops[i]).value_or(kInfeasible);
    }
    return [roads, first = *stops[0], rest](const RobotInfo& r) {
      return roads->toStation(r.pose.position(), first).value_or(kInfeasible) + rest;
    };
  };
}

Expected<std::unique_ptr<TaskStore>> openTaskStore(const Settings& s) {
  if (s.store.backend == StoreSettings::Backend::Postgres) {
    auto pgs = PostgresTaskStore::open({s.store.url});
    if (!pgs) {
      return unexpected(pgs.error());
    }
    return std::unique_ptr<TaskStore>(std::move(*pgs));
  }
  SqliteTaskStoreOptions opts;
  opts.path = s.db;
  opts.sync = s.syncFull ? SqliteTaskStoreOptions::Sync::Full : SqliteTaskStoreOptions::Sync::Normal;
  auto sq = SqliteTaskStore::open(opts);
  if (!sq) {
    return unexpected(sq.error());
  }
  return std::unique_ptr<TaskStore>(std::move(*sq));
}

Expected<std::unique_ptr<FleetManagerNode>> FleetManagerNode::create(const Settings& s, StationMap stations,
                                                                     std::int64_t nowNs,
                                                                     std::shared_ptr<const site::Site> site,
                                                                     std::unique_ptr<TaskStore> opened) {
  auto store = opened ? Expected<std::unique_ptr<TaskStore>>(std::move(opened)) : openTaskStore(s);
  if (!store) {
    return unexpected(store.error());
  }
  std::unique_ptr<FleetManagerNode> n(new FleetManagerNode());
  n->settings_ = s;
  n->site_ = site;
  n->reconciler_ = TaskReconciler(secToNs(s.reconcileS));
  n->store_ = std::move(*store);
  DispatcherConfig dc;
  dc.maxAttempts = s.maxAttempts;
  dc.stationCapacity = static_cast<std::size_t>(s.stationCapacity);
  std::shared_ptr<const traffic::RoadmapTravel> roads;
  const bool byArrival = s.stationLoad == StationLoad::Arrival;
  if (s.travelCost == "roadmap" || s.stationCapacityFromLines || byArrival) {
    if (!site) {
      return unexpected(
          Error{errc::kInvalid, std::string(s.travelCost == "roadmap" ? "travel_cost \"roadmap\""
                                            : byArrival               ? "station_load \"arrival\""
                                                                      : "station_capacity \"queue\"") +
                                    " needs a site (stations from a site file or a scenario naming one)"});
    }
    roads = std::make_shared<const traffic::RoadmapTravel>(
        std::make_shared<const traffic::Roadmap>(traffic::buildRoadmap(*site, s.roadmap)));
  }
  if (s.stationCapacityFromLines) {
    // Stations without a line (parking places, a dock the disc does not fit) keep stationCapacity.
    for (const auto& st : roads->roadmap().stations) {
      if (const std::size_t line = roads->lineCapacity(st.name); line > 0) {
        dc.stationCapacities[st.name] = line;
      }
    }
  }
  dc.stationLoad = s.stationLoad;
  // The lines' places are scaled by the admission governor (admission_governor.hpp) when admission
  // counts them by task or phase; by predicted arrival they are places in time, not scaled.
  n->governed_ = s.stationCapacityFromLines && !byArrival;
  if (roads) {
    // Admission by predicted arrival, and the queue wait in every assignment's cost (whenever the
    // roadmap is built: reserved traffic's lines, roadmap travel cost, or arrival).
    // Unknown stations (not on the roadmap, or without a dock) are never reached: +infinity.
    const auto orNever = [](std::optional<double> v) { return v.value_or(kInfeasible); };
    dc.stationTimes.toStation = [roads, orNever](Vec2 from, const std::string& name) {
      return orNever(roads->toStation(from, name));
    };
    dc.stationTimes.between = [roads, orNever](const std::string& a, const std::string& b) {
      return orNever(roads->between(a, b));
    };
    dc.stationTimes.dockMove = [roads](const std::string& name) { return roads->dockMoveSeconds(name); };
  }
  dc.robotFailLimit = s.robotFailLimit;
  dc.robotHoldNs = secToNs(s.robotHoldS);
  dc.leaseNs = secToNs(s.leaseS);
  dc.policy.batteryThreshold = s.batteryThreshold;
  dc.chargeUntil = s.chargeUntil;
  std::shared_ptr<planning::DistanceFieldCache> cache;
  if (s.travelCost == "straight") {
    // straight lines: no cache
  } else if (!s.mapFile.empty()) {
    auto grid = planning::loadMovingAiMap(s.mapFile, s.mapResolution, {s.mapOriginX, s.mapOriginY});
    if (!grid) {
      return unexpected(grid.error());
    }
    cache = std::make_shared<planning::DistanceFieldCache>(
        std::make_shared<const planning::OccupancyGrid>(std::move(*grid)));
  } else if (site && s.travelCost == "path") {
    cache = std::make_shared<planning::DistanceFieldCache>(
        std::make_shared<const planning::OccupancyGrid>(site->drivable()));
  }
  auto travel = s.travelCost == "roadmap" ? makeRoadmapTravelModel(stations, roads)
                                          : makeTravelModel(stations, cache, s.nominalSpeed);
  n->dispatcher_ = std::make_unique<Dispatcher>(*n->store_, std::move(stations), std::move(travel), dc);
  auto rec = n->dispatcher_->recover(nowNs);
  if (!rec) {
    return unexpected(rec.error());
  }
  for (const auto& [id, r] : n->dispatcher_->openTasks()) {
    // The previous incarnation's events are gone with its writer. The revision counts the task's
    // transitions, as the event seq did, so an adapter that kept running sees no step back.
    const auto seq = static_cast<std::uint32_t>(r.revision);
    n->eventSeq_[id] = seq;
    n->recovered_.events.push_back({id, r.state, r.robotId, r.reason.substr(0, 255), nowNs, seq,
                                    r.stationChosen ? r.task.station : std::string()});
  }
  // After the announcements: an order that cannot be rebuilt (its station left the site) fails
  // its task, and that event must follow the task's state with the next seq.
  n->publish(std::move(*rec), nowNs, n->recovered_);
  return n;
}

std::uint32_t FleetManagerNode::nextRevision(const std::string& robot, std::int64_t nowNs) {
  // Unique across restarts of the manager: start from the clock in ms, then count.
  auto& rev = revisions_[robot];
  rev = std::max<std::uint32_t>(rev + 1, static_cast<std::uint32_t>((nowNs / 1'000'000) % 2'000'000'000));
  return rev;
}

Expected<msg::TaskAssignment> FleetManagerNode::toAssignment(const AssignmentOrder& o, std::int64_t nowNs) {
  msg::TaskAssignment a;
  a.robot_id = o.robotId;
  a.task_id = o.task.id;
  a.stamp_ns = nowNs;
  a.paused = o.paused;
  a.priority = o.task.priority;
  a.epoch = epoch_;
  auto goals = taskGoals(o.task, dispatcher_->stations(), settings_.chargeMaxS);
  if (!goals) {
    return unexpected(errc::kInternal,
                      "internal error: " + goals.error().message + "; no order sent to robot " + o.robotId);
  }
  a.goals = std::move(*goals);
  a.revision = nextRevision(o.robotId, nowNs);
  return a;
}

std::vector<std::string> FleetManagerNode::onClosures(const std::vector<msg::TrafficClosure>& closures,
                                                      std::int64_t nowNs, Outbox& out) {
  std::vector<std::string> errors;
  if (closures.empty() || !site_) {
    return errors;
  }
  if (!closures_) {
    // Reachability only: no flow guidance (route costs), which would cost seconds here on a large
    // site, inside the handling of a message.
    traffic::RoadmapOptions reach = settings_.roadmap;
    reach.guidance = 0.0;
    closures_ = std::make_unique<ClosedStations>(traffic::buildRoadmap(*site_, reach));
  }
  for (const auto& c : closures) {
    if (auto e = closures_->apply(c)) {
      errors.push_back(std::move(*e));
    }
  }
  auto closed = closures_->closed();
  if (closed != dispatcher_->closedStations()) {
    publish(dispatcher_->setClosedStations(std::move(closed), nowNs), nowNs, out);
  }
  return errors;
}

void FleetManagerNode::setEpoch(std::int64_t epoch) {
  epoch_ = epoch;
  for (auto& e : recovered_.events) {
    e.epoch = epoch;
  }
  for (auto& a : recovered_.assignments) {
    a.epoch = epoch;
  }
}

void FleetManagerNode::publish(DispatchResult r, std::int64_t nowNs, Outbox& out) {
  for (const auto& e : r.events) {
    auto& seq = eventSeq_[e.taskId];
    out.events.push_back({e.taskId, e.state, e.robotId, e.reason.substr(0, 255), e.stampNs, ++seq, e.station,
                          e.changed, e.priority, e.deadlineNs, e.etaNs, epoch_});
    if (e.state == TaskState::Queued || e.state == TaskState::Assigned) {
      trackSteps(e.taskId);
    }
    stampStep(out.events.back());
    if (e.state == TaskState::Queued || e.state == TaskState::Requeued) {
      // Kept from the first event: a waiting task's later events (paused, why it waits) do not
      // restart its wait.
      queuedAt_.try_emplace(e.taskId, e.stampNs);
    } else if (e.state == TaskState::Assigned) {
      auto it = queuedAt_.find(e.taskId);
      if (it != queuedAt_.end()) {
        assignLatency_->observe(static_cast<double>(e.stampNs - it->second) / 1e9);
        queuedAt_.erase(it);
      }
    }
    if (isTerminal(e.state)) {
      eventSeq_.erase(e.taskId);
      queuedAt_.erase(e.taskId);
    }
  }
  for (const auto& o : r.assignments) {
    auto a = toAssignment(o, nowNs);
    if (a) {
      out.assignments.push_back(std::move(*a));
      ++metrics_.assignments;
      continue;
    }
    // The order cannot be built: the task fails with the reason (and its robot is released)
    // rather than the robot being sent somewhere the task never meant.
    ++metrics_.badOrders;
    auto failed = dispatcher_->fail(o.task.id, a.error().message, nowNs);
    DispatchResult stop;
    if (failed) {
      stop = std::move(*failed);
    } else {
      stop.revoked.push_back(o.robotId);  // not stored as failed (storage): at least stop the robot
    }
    publish(std::move(stop), nowNs, out);
  }
  for (const auto& robot : r.revoked) {
    msg::TaskAssignment a;
    a.robot_id = robot;
    a.revision = nextRevision(robot, nowNs);
    a.stamp_ns = nowNs;
    a.paused = dispatcher_->robotHeld(robot);  // a held robot stands still without an order too
    a.epoch = epoch_;
    out.assignments.push_back(a);
  }
}

void FleetManagerNode::onRequests(const std::vector<msg::Task>& requests, std::int64_t nowNs, Outbox& out) {
  std::vector<Task> batch;
  std::vector<const msg::Task*> batchReq;
  auto flush = [&] {
    if (batch.empty()) {
      return;
    }
    DispatchResult r;
    std::vector<std::vector<FieldError>> fields;
    auto results = dispatcher_->submit(batch, nowNs, &r, &fields);
    for (std::size_t i = 0; i < results.size(); ++i) {
      const auto& req = *batchReq[i];
      if (!fields[i].empty()) {
        ++metrics_.rejected;
        out.acks.push_back(
            ack(req, msg::AckResult::Invalid, msg::TaskState::Rejected, fieldsJson(fields[i]), nowNs));
      } else if (results[i]) {
        const bool created = results[i]->created;
        ++(created ? metrics_.stored : metrics_.duplicates);
        out.acks.push_back(ack(req, created ? msg::AckResult::Stored : msg::AckResult::Duplicate,
                               results[i]->record.state, "", nowNs));
      } else {
        const auto& code = results[i].error().code;
        const auto result = code == errc::kConflict  ? msg::AckResult::Conflict
                            : code == errc::kStorage ? msg::AckResult::Unavailable
                                                     : msg::AckResult::Invalid;
        ++metrics_.rejected;
        out.acks.push_back(ack(req, result, msg::TaskState::Rejected, results[i].error().message, nowNs));
      }
    }
    publish(std::move(r), nowNs, out);
    batch.clear();
    batchReq.clear();
  };
  for (const auto& req : requests) {
    ++metrics_.requests;
    if (req.cancel || req.control != msg::TaskControl::None) {
      flush();  // a request on a task must see the tasks submitted before it
      control(req, nowNs, out);
      continue;
    }
    // The typed fields are the task; the dispatcher validates it, once, against the site.
    batch.push_back(fleet::fromWire(req, nowNs));
    batchReq.push_back(&req);
  }
  flush();
}

void FleetManagerNode::onStatus(const msg::TaskStatus& s, std::int64_t nowNs, Outbox& out) {
  if (s.task_id.empty()) {
    return;
  }
  const TaskState state = s.state;
  if (state == TaskState::Rejected || state == TaskState::Queued || state == TaskState::Assigned) {
    return;  // not a robot's report
  }
  const bool newStep = noteStep(s);
  auto r = dispatcher_->onTaskStatus(s.robot_id, s.task_id, state, s.error, nowNs);
  if (r) {
    const bool told = std::any_of(r->events.begin(), r->events.end(),
                                  [&](const TaskEvent& e) { return e.taskId == s.task_id; });
    publish(std::move(*r), nowNs, out);
    if (newStep && !told) {
      stepEvent(s.task_id, nowNs, out);
    }
    return;
  }
  // A robot working on a task it no longer holds (cancelled, or given to another robot while it
  // was thought lost) is told to drop it, unless it already has a newer task.
  const auto& code = r.error().code;
  const RobotInfo* robot = dispatcher_->robots().find(s.robot_id);
  if ((code == errc::kWrongRobot || code == errc::kNotFound) && (robot == nullptr || robot->taskId.empty())) {
    DispatchResult revoke;
    revoke.revoked.push_back(s.robot_id);
    publish(std::move(revoke), nowNs, out);
  }
}

void FleetManagerNode::onRobotState(const msg::RobotState& s, std::int64_t nowNs) {
  const auto update = dispatcher_->onRobotState(
      {s.robot_id, s.pose, static_cast<double>(s.battery), nowNs, s.mode == msg::RobotMode::Fault});
  if (update == RobotRegistry::Update::Stale) {
    return;
  }
  if (governed_) {
    activity_[s.robot_id] = msg::activityOf(s);
  }
  if (settings_.reconcileS <= 0) {
    return;
  }
  const RobotInfo* info = dispatcher_->robots().find(s.robot_id);
  reconciler_.observe(s.robot_id, s.task_id, info != nullptr ? info->taskId : std::string(), nowNs);
}

void FleetManagerNode::onRobotLost(const std::string& robotId, std::int64_t nowNs, Outbox& out) {
  reconciler_.forget(robotId);
  publish(dispatcher_->onRobotLost(robotId, nowNs), nowNs, out);
}

void FleetManagerNode::tick(std::int64_t nowNs, Outbox& out) {
  // First: a requeued task is assigned again in the same tick.
  reconcile(nowNs, out);
  govern(nowNs);
  publish(dispatcher_->tick(nowNs), nowNs, out);
}

void FleetManagerNode::govern(std::int64_t nowNs) {
  if (!governed_) {
    return;
  }
  if (governedAtNs_ >= 0 && nowNs > governedAtNs_) {
    // At most a second a tick: a clock that jumped (a stalled process, a paused run) must not let
    // one snapshot of the robots stand for a whole window.
    const double dt = std::min(1.0, static_cast<double>(nowNs - governedAtNs_) * 1e-9);
    for (const auto& [id, a] : activity_) {
      const RobotInfo* r = dispatcher_->robots().find(id);
      if (r != nullptr && !r->lost) {
        governor_.add(a, dt);
      }
    }
    if (governor_.tick(dt, dispatcher_->heldInLines() > 0)) {
      dispatcher_->setLineScale(governor_.scale());
    }
  }
  governedAtNs_ = nowNs;
}

std::vector<double> FleetManagerNode::assignLatencyBuckets() {
  return metrics::exponentialBuckets(0.01, 2.0, 16);
}

nlohmann::json FleetManagerNode::metricsJson() const {
  const auto& c = dispatcher_->counters();
  // Percentiles estimated from the histogram's buckets (error at most the bucket's width: the
  // bounds double, so within a factor of two of the true value, linear inside the bucket).
  const auto lat = assignLatency_->snapshot();
  auto pct = [&](double q) { return lat.quantile(q) * 1e3; };
  const nlohmann::json reconciled = {{"requeued", metrics_.reconciledRequeued},
                                     {"stale_report", metrics_.reconciledStale}};
  return {{"queued", dispatcher_->waitingCount()},
          {"active", dispatcher_->activeCount()},
          {"submitted", c.submitted},
          {"done", c.done},
          {"failed", c.failed},
          {"cancelled", c.cancelled},
          {"requeued", c.requeued},
          {"robots_lost", c.robotsLost},
          {"robots_online", dispatcher_->robots().onlineCount()},
          {"requests", metrics_.requests},
          {"duplicates", metrics_.duplicates},
          {"rejected", metrics_.rejected},
          {"assignments", metrics_.assignments},
          {"bad_orders", metrics_.badOrders},
          {"reconciled", reconciled},
          {"admission",
           {{"line_scale", governor_.scale()},
            {"waiting_on_robot_share", governor_.lastWaitingShare()},
            {"no_task_share", governor_.lastIdleShare()}}},
          {"assign_latency_ms", {{"p50", pct(0.5)}, {"p99", pct(0.99)}, {"samples", lat.count}}}};
}

}  // namespace fleet::manager
