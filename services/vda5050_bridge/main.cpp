// vda5050_bridge: puts VDA 5050 vehicles under the fleet manager and the traffic manager. Reads
// TaskAssignment, TrafficRelease and Roadmap (DDS) and the vehicles' state, connection and factsheet (MQTT);
// writes orders and instant actions (MQTT) and RobotState, TrafficProgress, TaskStatus (DDS).
// See docs/operator-guide.md#vda-5050-vehicles for the configuration.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <deque>
#include <map>
#include <mutex>
#include <set>
#include <thread>

#include "bridge_node.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/core/config.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/mqtt/client.hpp"
#include "fleet/service/command_line.hpp"
#include "fleet/service/common_options.hpp"
#include "fleet/service/dds_security_check.hpp"
#include "fleet/service/runtime.hpp"
#include "fleet/service/service_ops.hpp"
#include "fleet/transport/dds.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

struct Settings {
  mqtt::ClientOptions broker;
  vdabridge::BridgeSettings bridge;
  double rate_hz = 10.0;
  bool sim_clock = false;  // stamps and timing from the simulator's Clock (load tests)
  bool lockstep = false;   // ... and a lockstep participant (implies sim_clock)
};

constexpr const char* kParticipant = "vda5050_bridge";

Settings readSettings(Config& c) {
  Settings s;
  c.rejectUnknownKeys({"broker", "interface", "map_id", "rate_hz", "allowed_deviation", "order_retries",
                       "retry_backoff_s", "order_ack_timeout_s", "field_cancel_s", "vehicles", "clock",
                       "lockstep", "max_message_bytes", "site_margin"});
  s.sim_clock = c.string("clock", "wall", {"wall", "sim"}) == "sim";
  s.lockstep = c.boolean("lockstep", false);
  if (s.lockstep && !s.sim_clock) {
    c.problem("lockstep", "needs \"clock\": \"sim\"");
  }
  auto b = c.child("broker", true);
  b.rejectUnknownKeys({"host", "port", "username", "password", "ca_file", "client_id"});
  s.broker.host = b.string("host", "127.0.0.1");
  s.broker.port = static_cast<int>(b.requireInteger("port", {1, 65535}));
  s.broker.username = b.requireString("username");
  s.broker.password = b.requireString("password");
  s.broker.tls_ca_file = b.string("ca_file", "");
  s.broker.client_id = b.string("client_id", "vda5050_bridge");
  s.bridge.interface_name = c.string("interface", "uagv");
  s.bridge.map_id = c.requireString("map_id");
  s.rate_hz = c.number("rate_hz", 10.0, {1.0, 100.0});
  s.bridge.allowed_deviation = c.number("allowed_deviation", 0.2, {0.01, 5.0});
  s.bridge.order_retries = static_cast<int>(c.integer("order_retries", s.bridge.order_retries, {0, 100}));
  s.bridge.retry_backoff_s = c.number("retry_backoff_s", s.bridge.retry_backoff_s, {0.0, 60.0});
  s.bridge.order_ack_timeout_s = c.number("order_ack_timeout_s", s.bridge.order_ack_timeout_s, {0.1, 600.0});
  s.bridge.field_cancel_s = c.number("field_cancel_s", s.bridge.field_cancel_s, {0.0, 600.0});
  for (auto& v : c.array("vehicles", true)) {
    v.rejectUnknownKeys({"manufacturer", "serial", "robot"});
    s.bridge.vehicles.push_back(
        {v.requireString("manufacturer"), v.requireString("serial"), v.requireString("robot")});
  }
  for (const auto& problem : vda5050::vehicleEntryProblems(s.bridge.vehicles)) {
    c.problem(problem.substr(0, problem.find(':')), problem.substr(problem.find(':') + 2));
  }
  s.bridge.max_message_bytes = static_cast<std::size_t>(c.integer(
      "max_message_bytes", static_cast<std::int64_t>(s.bridge.max_message_bytes), {1024, 64 << 20}));
  s.bridge.site_margin = c.number("site_margin", s.bridge.site_margin, {0.0, 10000.0});
  return s;
}

int run(const Settings& settings, const service::OpsSettings& opsSettings) {
  service::ServiceOps ops("vda5050_bridge");
  if (!ops.start(opsSettings)) {
    return service::kExitUsage;
  }
  auto& cycleSeconds = ops.registry().histogram(
      "vda5050_bridge_cycle_seconds", "Wall time of one cycle (messages read, orders and reports written)",
      metrics::exponentialBuckets(1e-5, 2.0, 20));
  // Counted on the MQTT client's thread: a counter is an atomic add, constant cost per message.
  auto& mqttReceived = ops.registry().counter("vda5050_bridge_mqtt_messages_received_total",
                                              "MQTT messages from the vehicles");
  auto& mqttDropped = ops.registry().counter("vda5050_bridge_mqtt_messages_dropped_total",
                                             "MQTT messages dropped because 100,000 were already waiting");
  auto& mqttSent = ops.registry().counter("vda5050_bridge_mqtt_messages_sent_total",
                                          "Orders and instant actions published to the vehicles");
  auto& mqttUnsent = ops.registry().counter("vda5050_bridge_mqtt_messages_unsent_total",
                                            "Orders and instant actions not published (broker unreachable)");
  std::map<std::string, metrics::Gauge*> byHealth;
  for (auto h :
       {vda5050::VehicleHealth::kUnknown, vda5050::VehicleHealth::kOnline, vda5050::VehicleHealth::kManual,
        vda5050::VehicleHealth::kFault, vda5050::VehicleHealth::kOffline}) {
    byHealth[vda5050::toString(h)] = &ops.registry().gauge("vda5050_bridge_vehicles", "Vehicles by health",
                                                           {{"health", vda5050::toString(h)}});
  }
  std::set<std::string> refusalKinds;  // watched by ops already
  WallClock wall;
  vdabridge::BridgeNode node(settings.bridge);
  std::mutex mutex;
  std::deque<std::pair<std::string, std::string>> inbox;
  auto client = mqtt::Client::start(settings.broker, [&](const std::string& t, const std::string& p) {
    mqttReceived.inc();
    std::lock_guard lock(mutex);
    if (inbox.size() < 100000) {  // a flood is dropped rather than eating the memory
      inbox.emplace_back(t, p);
    } else {
      mqttDropped.inc();
    }
  });
  if (!client) {
    spdlog::critical("{}", client.error().message);
    return 2;
  }
  const auto& in = settings.bridge.interface_name;
  (*client)->subscribe(in + "/v2/+/+/state", 0);
  (*client)->subscribe(in + "/v2/+/+/connection", 1);
  (*client)->subscribe(in + "/v2/+/+/factsheet", 0);

  transport::Participant p;
  transport::Reader<msg::TaskAssignment> assignments(p);
  transport::Reader<msg::TrafficRelease> releases(p);
  transport::Reader<msg::Roadmap> roadmaps(p);
  transport::Writer<msg::RobotState> states(p);
  transport::Writer<msg::TaskStatus> statuses(p);
  transport::Writer<msg::TrafficProgress> progress(p);
  transport::Reader<msg::Clock> clockIn(p);
  transport::Writer<msg::StepDone> stepDone(p);
  // One writer per vehicle's robot, each in its robot's partition, made now so that the fleet
  // manager has matched them before the first report (and so that DDS Security refuses, at start,
  // a vehicle this bridge's permissions do not name).
  std::vector<std::string> robots;
  for (const auto& v : settings.bridge.vehicles) {
    robots.push_back(v.robot_id);
  }
  states.forRobots(robots);
  statuses.forRobots(robots);
  progress.forRobots(robots);
  std::int64_t simNow = -1;
  service::RateLimitedLog log;
  const auto& b = settings.bridge;
  spdlog::info(
      "vda5050 bridge: {} vehicle(s), broker {}:{}{}, map '{}'; a rejected order re-sent {} times (first "
      "after "
      "{} s), unanswered after {} s; a vehicle held by its field cancelled after {} s",
      b.vehicles.size(), settings.broker.host, settings.broker.port,
      settings.broker.tls_ca_file.empty() ? "" : " (TLS)", b.map_id, b.order_retries, b.retry_backoff_s,
      b.order_ack_timeout_s, b.field_cancel_s);
  const auto period = std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::duration<double>(1.0 / settings.rate_hz));
  auto next = std::chrono::steady_clock::now();
  auto lastStats = next;
  bool wasConnected = false;
  const auto total = [&](const char* what, const char* help,
                         std::uint64_t vdabridge::BridgeCounters::*field) {
    ops.watchTotal(ops.registry().counter(std::string("vda5050_bridge_") + what + "_total", help),
                   [&node, field] { return node.counters().*field; });
  };
  total("orders", "New orders sent", &vdabridge::BridgeCounters::orders);
  total("order_updates", "Order updates sent (more of the route released)",
        &vdabridge::BridgeCounters::updates);
  total("stale_epoch_assignments", "TaskAssignments dropped: sent by a fleet manager of an older lease epoch",
        &vdabridge::BridgeCounters::stale_epoch);
  total("cancels", "Orders cancelled", &vdabridge::BridgeCounters::cancels);
  total("releases_not_stitched", "Releases that did not extend the vehicle's base",
        &vdabridge::BridgeCounters::cannot_stitch);
  total("orders_rejected", "Orders and updates the vehicle rejected or did not take",
        &vdabridge::BridgeCounters::rejected);
  total("vehicles_given_up", "Times a vehicle was reported blocked after its retries",
        &vdabridge::BridgeCounters::gave_up);
  total("field_cancels", "Orders cancelled because the vehicle's protective field held it",
        &vdabridge::BridgeCounters::field_cancels);
  total("refused_vehicles",
        "Times a vehicle was refused (no factsheet yet, or a footprint the roadmap does not fit)",
        &vdabridge::BridgeCounters::refused_vehicles);
  total("late_updates", "Stops of a vehicle at its base end while its release went further (update latency)",
        &vdabridge::BridgeCounters::late_updates);
  total("charges_started", "startCharging sent at a charge goal", &vdabridge::BridgeCounters::charges);
  total("charge_failures", "startCharging the vehicle answered FAILED (the task failed)",
        &vdabridge::BridgeCounters::charge_failures);
  total("charge_stops", "stopCharging sent", &vdabridge::BridgeCounters::charge_stops);
  ops.watchMatchedReaders("RobotState", [&] { return states.matchedReaders(); });
  ops.watchMatchedWriters("TaskAssignment", [&] { return assignments.matchedWriters(); });
  ops.watchMatchedWriters("TrafficRelease", [&] { return releases.matchedWriters(); });
  // Ready: it hears the broker (the vehicles' side); the DDS side shows in the matched gauges.
  ops.health().setReady("broker", false);
  const auto logStats = [&] {
    const auto& c = node.counters();
    spdlog::info(
        "vda5050 bridge: {} orders, {} updates, {} cancels, {} refused messages, {} releases not stitched, "
        "{} orders rejected by vehicles, {} times a vehicle reported blocked after its retries, {} orders "
        "cancelled for a vehicle its field held, {} charges started ({} failed), {} stopped, {} stops at a "
        "base end "
        "an update had not reached",
        c.orders, c.updates, c.cancels, c.refused_messages, c.cannot_stitch, c.rejected, c.gave_up,
        c.field_cancels, c.charges, c.charge_failures, c.charge_stops, c.late_updates);
  };
  const auto refreshMetrics = [&] {
    if (!ops.refresh()) {
      return;
    }
    ops.health().setReady("broker", (*client)->connected());
    // By kind, as the registry meets them (a kind is listed from its first refusal on).
    for (const auto& entry : node.registry().refusals()) {
      if (const std::string& kind = entry.first; refusalKinds.insert(kind).second) {
        ops.watchTotal(ops.rejected(kind), [&node, kind] { return node.registry().refusals().at(kind); });
      }
    }
    std::map<std::string, double> health;
    for (const auto& [id, v] : node.registry().vehicles()) {
      health[vda5050::toString(v.health)] += 1.0;
    }
    for (auto& [h, g] : byHealth) {
      g->set(health[h]);
    }
  };
  const auto cycle = [&](std::int64_t now) {
    const auto t0 = std::chrono::steady_clock::now();
    vdabridge::BridgeOutbox out;
    std::deque<std::pair<std::string, std::string>> batch;
    {
      std::lock_guard lock(mutex);
      batch.swap(inbox);
    }
    for (const auto& [t, payload] : batch) {
      node.onMqtt(t, payload, out);
    }
    for (const auto& a : assignments.take()) {
      node.onAssignment(a, now, out);
    }
    for (const auto& m : roadmaps.take()) {
      node.onRoadmap(m);
    }
    for (const auto& r : releases.take()) {
      node.onRelease(r);
    }
    node.tick(now, out);
    for (const auto& m : out.mqtt) {
      if ((*client)->publish(m.topic, m.payload, m.qos, m.retain)) {
        mqttSent.inc();
      } else {
        mqttUnsent.inc();
        log.warn("mqtt:" + m.topic, "not sent (broker unreachable): " + m.topic);
      }
    }
    for (const auto& s : out.states) {
      states.write(s);
    }
    for (const auto& s : out.statuses) {
      statuses.write(s);
    }
    for (const auto& s : out.progress) {
      progress.write(s);
    }
    for (const auto& n : out.notices) {
      spdlog::warn("{}", n);
    }
    for (const auto& w : out.warnings) {
      // Rate-limited per vehicle and kind ("r3: refused", "r3: online"): one kind does not hide
      // another (a vehicle's refusal came right after its "online" and was swallowed).
      const auto colon = w.find(':');
      const auto word = colon == std::string::npos ? colon : w.find_first_of(" (:", colon + 2);
      log.warn(w.substr(0, word), w);
    }
    if ((*client)->connected() != wasConnected) {
      wasConnected = !wasConnected;
      if (wasConnected) {
        spdlog::info("vda5050 bridge: connected to the broker");
      } else {
        spdlog::warn("vda5050 bridge: lost the broker; reconnecting");
      }
    }
    cycleSeconds.observe(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    refreshMetrics();
    if (std::chrono::steady_clock::now() - lastStats > 10s) {
      logStats();
      lastStats = std::chrono::steady_clock::now();
    }
  };

  if (settings.lockstep) {
    // A lockstep participant: one cycle per simulated step, acknowledged, so that the bridge keeps
    // pace with the vehicles however fast or loaded the machine.
    bool registered = false;
    auto lastRegister = std::chrono::steady_clock::now() - 10s;
    while (!service::stopRequested()) {
      if (!registered && std::chrono::steady_clock::now() - lastRegister > 1s) {
        stepDone.write({kParticipant, msg::StepDone::kRegister});
        lastRegister = std::chrono::steady_clock::now();
      }
      clockIn.waitForData(100ms);
      refreshMetrics();  // the liveness beats while no simulated time comes
      for (const auto& c : clockIn.take()) {
        registered = true;
        cycle(c.sim_time_ns);
        if (c.lockstep) {
          stepDone.write({kParticipant, c.step});
        }
      }
    }
    stepDone.write({kParticipant, msg::StepDone::kLeave});
  }
  while (!settings.lockstep && !service::stopRequested()) {
    std::this_thread::sleep_until(next);
    next += period;
    for (const auto& c : clockIn.take()) {
      simNow = std::max(simNow, c.sim_time_ns);
    }
    if (settings.sim_clock && simNow < 0) {
      continue;  // no simulated time yet
    }
    cycle(settings.sim_clock ? simNow : wall.nowNs());
  }
  logStats();  // the final counts
  spdlog::info("vda5050 bridge: stopped");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vda5050_bridge: VDA 5050 vehicles (MQTT) as robots of the fleet (DDS)"};
  std::string configPath;
  service::CommonOptions common;
  app.add_option("-c,--config", configPath, "JSON configuration file")->required();
  service::addCommonOptions(app, common);
  if (auto code = service::parse(app, argc, argv)) {
    return *code;
  }
  try {
    service::setupLogging("vda5050_bridge", common);
    service::checkDdsSecurity();  // exit 2 naming a missing certificate, key or document
    Config cfg = Config::fromFile(configPath);
    const auto settings = readSettings(cfg);
    cfg.finish();
    service::installStopHandlers();
    return run(settings, common.ops);
  } catch (const ConfigError& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("vda5050 bridge: {}", e.what());
    return 1;
  }
}
