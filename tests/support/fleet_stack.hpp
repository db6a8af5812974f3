// The lockstep fleet of the scenario tests: the fleet manager's config, the traffic manager the
// agents follow (reserved traffic: an agent with no traffic manager stands still) and a task
// submitted over DDS as the WMS adapter does it. Header-only; the tests that include it link
// fleet::transport.
#pragma once

#include <chrono>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "fleet/transport/dds.hpp"
#include "test_process.hpp"

namespace fleet::test {

/// A fresh DDS domain (set for this process as well, so the test's own participants join it) and an
/// empty temporary folder named after it.
struct ScenarioRun {
  std::string domain;
  std::filesystem::path dir;
};
inline ScenarioRun freshRun(const std::string& prefix) {
  ScenarioRun r{std::to_string(uniqueDomain()), {}};
  setenv("FLEET_DDS_DOMAIN", r.domain.c_str(), 1);
  r.dir = std::filesystem::temp_directory_path() / (prefix + r.domain);
  std::filesystem::remove_all(r.dir);
  std::filesystem::create_directories(r.dir);
  return r;
}

/// dir/manager.json: the database in `dir`, the stations of `scenario`, the simulated clock, a 3 s
/// lease, plus `extra` keys (e.g. battery settings). Returns its path.
inline std::filesystem::path writeManagerConfig(const std::filesystem::path& dir, const std::string& scenario,
                                                const nlohmann::json& extra = nlohmann::json::object()) {
  nlohmann::json cfg{{"db", (dir / "fleet.db").string()},
                     {"stations", scenario},
                     {"clock", "sim"},
                     {"lease_s", 3.0},
                     {"sync", "normal"}};
  cfg.update(extra);
  std::ofstream(dir / "manager.json") << cfg.dump();
  return dir / "manager.json";
}

/// The site file of `scenario` (its "site", relative to the scenario's folder).
inline std::string siteOf(const std::string& scenario) {
  const auto s = nlohmann::json::parse(std::ifstream(scenario));
  const std::filesystem::path site = s.at("site").get<std::string>();
  return site.is_absolute()
             ? site.string()
             : (std::filesystem::path(scenario).parent_path() / site).lexically_normal().string();
}

/// dir/traffic_manager.json: the site of `scenario`, the simulator's clock (the Clock topic, also on
/// the wall clock) and, with `lockstep`, a lockstep participant (fleet-sim's --participants counts
/// it), plus `extra` keys. Returns the traffic_manager arguments that use it, with `id` as its
/// lockstep id.
inline std::vector<std::string> trafficManagerArgs(const std::filesystem::path& dir,
                                                   const std::string& scenario, bool lockstep,
                                                   const nlohmann::json& extra = nlohmann::json::object(),
                                                   const std::string& id = "traffic_manager") {
  nlohmann::json cfg{{"site", siteOf(scenario)}, {"clock", "sim"}, {"lockstep", lockstep}};
  cfg.update(extra);
  const auto path = dir / (id + ".json");
  std::ofstream(path) << cfg.dump();
  return {"--config", path.string(), "--id", id, "--log-level", "warn"};
}

inline constexpr const char* kTrafficManagerBinary =
    FLEET_BINARY_DIR "/services/traffic_manager/traffic_manager";

/// fleet_manager (config from writeManagerConfig with `managerExtra`), traffic_manager (on the
/// scenario's site; a lockstep participant when the agent is, `agentArgs` having "--clock
/// lockstep") and robot_agent (`agentArgs` after --scenario) as processes on `domain`; all die with
/// the test. `env` is for the simulator, whose --participants is kLockstepParticipants.
struct ManagerAndAgent {
  /// The agent process and the traffic manager.
  static constexpr const char* kLockstepParticipants = "2";

  ManagerAndAgent(const std::filesystem::path& dir, const std::string& scenario, const std::string& domain,
                  std::vector<std::string> agentArgs,
                  const nlohmann::json& managerExtra = nlohmann::json::object())
      : env{{"FLEET_DDS_DOMAIN", domain}},
        manager(FLEET_BINARY_DIR "/services/fleet_manager/fleet_manager",
                {"--config", writeManagerConfig(dir, scenario, managerExtra).string(), "--log-level", "warn"},
                env),
        traffic(kTrafficManagerBinary, trafficManagerArgs(dir, scenario, inLockstep(agentArgs)), env),
        agent(FLEET_BINARY_DIR "/services/robot_agent/robot_agent",
              withScenario(scenario, std::move(agentArgs)), env) {}

  std::vector<std::pair<std::string, std::string>> env;
  ChildProcess manager;
  ChildProcess traffic;
  ChildProcess agent;

 private:
  static bool inLockstep(const std::vector<std::string>& args) {
    for (std::size_t i = 0; i + 1 < args.size(); ++i) {
      if (args[i] == "--clock" && args[i + 1] == "lockstep")
        return true;
    }
    return false;
  }
  static std::vector<std::string> withScenario(const std::string& scenario, std::vector<std::string> args) {
    args.insert(args.begin(), {"--scenario", scenario, "--log-level", "warn"});
    return args;
  }
};

/// The transport task `id` (request "req-" + id), 2 s to load and 2 s to unload.
inline msg::Task transportTask(const std::string& id, const std::string& pickup, const std::string& dropoff) {
  msg::Task t;
  t.task_id = id;
  t.request_id = "req-" + id;
  t.kind = msg::TaskKind::Transport;
  t.pickup = pickup;
  t.dropoff = dropoff;
  t.load_ns = 2'000'000'000;
  t.unload_ns = 2'000'000'000;
  return t;
}

/// Submits `task` and waits for the manager's durable acknowledgement until `deadline`. Task is
/// volatile: a request written before the manager's reader has matched this writer is lost, so it is
/// repeated every 2 s (the same request: answered `duplicate` if the first one was stored after all).
inline std::optional<msg::TaskAck> submitUntilAcknowledged(transport::Writer<msg::Task>& tasks,
                                                           transport::Reader<msg::TaskAck>& acks,
                                                           const msg::Task& task,
                                                           std::chrono::steady_clock::time_point deadline) {
  using namespace std::chrono_literals;
  while (tasks.matchedReaders() == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(20ms);
  }
  for (int i = 0; std::chrono::steady_clock::now() < deadline; ++i) {
    if (i % 20 == 0) {
      tasks.write(task);
    }
    acks.waitForData(100ms);
    for (const auto& a : acks.take()) {
      if (a.request_id == task.request_id) {
        return a;
      }
    }
  }
  return std::nullopt;
}

/// The WMS adapter's side of the Task topic, on the test's participant (further readers of the test
/// go on `participant`).
struct TaskClient {
  transport::Participant participant;
  transport::Writer<msg::Task> tasks{participant};
  transport::Reader<msg::TaskAck> acks{participant};

  /// submitUntilAcknowledged with a deadline `wait` from now.
  std::optional<msg::TaskAck> submit(const msg::Task& task, std::chrono::seconds wait) {
    return submitUntilAcknowledged(tasks, acks, task, std::chrono::steady_clock::now() + wait);
  }
};

}  // namespace fleet::test
