// vda5050_bridge: puts VDA 5050 vehicles under the fleet manager and the traffic manager. Reads
// TaskAssignment, TrafficRelease and Roadmap (DDS) and the vehicles' state, connection and factsheet (MQTT);
// writes orders and instant actions (MQTT) and RobotState, TrafficProgress, TaskStatus (DDS).
// See docs/operator-guide.md#vda-5050-vehicles for the configuration.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <deque>
#include <mutex>
#include <thread>

#include "bridge_node.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/core/config.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/mqtt/client.hpp"
#include "fleet/service/runtime.hpp"
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
  c.rejectUnknownKeys(
      {"broker", "interface", "map_id", "rate_hz", "allowed_deviation", "vehicles", "clock", "lockstep"});
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
  for (auto& v : c.array("vehicles", true)) {
    v.rejectUnknownKeys({"manufacturer", "serial", "robot"});
    s.bridge.vehicles.push_back(
        {v.requireString("manufacturer"), v.requireString("serial"), v.requireString("robot")});
  }
  return s;
}

int run(const Settings& settings) {
  WallClock wall;
  vdabridge::BridgeNode node(settings.bridge);
  std::mutex mutex;
  std::deque<std::pair<std::string, std::string>> inbox;
  auto client = mqtt::Client::start(settings.broker, [&](const std::string& t, const std::string& p) {
    std::lock_guard lock(mutex);
    if (inbox.size() < 100000) {  // a flood is dropped rather than eating the memory
      inbox.emplace_back(t, p);
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
  spdlog::info("vda5050 bridge: {} vehicle(s), broker {}:{}{}, map '{}'", settings.bridge.vehicles.size(),
               settings.broker.host, settings.broker.port,
               settings.broker.tls_ca_file.empty() ? "" : " (TLS)", settings.bridge.map_id);
  const auto period = std::chrono::duration_cast<std::chrono::nanoseconds>(
      std::chrono::duration<double>(1.0 / settings.rate_hz));
  auto next = std::chrono::steady_clock::now();
  auto lastStats = next;
  bool wasConnected = false;
  const auto cycle = [&](std::int64_t now) {
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
      if (!(*client)->publish(m.topic, m.payload, m.qos, m.retain)) {
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
    for (const auto& w : out.warnings) {
      log.warn(w.substr(0, w.find(':')), w);
    }
    if ((*client)->connected() != wasConnected) {
      wasConnected = !wasConnected;
      if (wasConnected) {
        spdlog::info("vda5050 bridge: connected to the broker");
      } else {
        spdlog::warn("vda5050 bridge: lost the broker; reconnecting");
      }
    }
    if (std::chrono::steady_clock::now() - lastStats > 10s) {
      const auto& c = node.counters();
      spdlog::info(
          "vda5050 bridge: {} orders, {} updates, {} cancels, {} refused messages, {} releases not stitched, "
          "{} orders rejected by vehicles, {} times a vehicle reported blocked after its retries",
          c.orders, c.updates, c.cancels, c.refused_messages, c.cannot_stitch, c.rejected, c.gave_up);
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
  spdlog::info("vda5050 bridge: stopped");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vda5050_bridge: VDA 5050 vehicles (MQTT) as robots of the fleet (DDS)"};
  std::string configPath;
  std::string level = "info";
  app.add_option("-c,--config", configPath, "JSON configuration file")->required();
  app.add_option("--log-level", level, "trace, debug, info, warn, error, critical, off");
  CLI11_PARSE(app, argc, argv);
  try {
    logging::setup("vda5050_bridge", level);
    Config cfg = Config::fromFile(configPath);
    const auto settings = readSettings(cfg);
    cfg.finish();
    service::installStopHandlers();
    return run(settings);
  } catch (const ConfigError& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("vda5050 bridge: {}", e.what());
    return 1;
  }
}
