#pragma once

// The optional `tasks` list of a scenario file: transport tasks `fleetctl loadtest` posts through
// the WMS adapter's HTTP API, each when the simulated clock reaches its `at_s`.
//
//   "tasks": [{"at_s": 0, "pickup": "P-1", "dropoff": "D-2"},
//             {"at_s": 4.5, "pickup": "P-3", "dropoff": "D-1", "id": "order-17", "priority": 5},
//             {"at_s": 9, "steps": [{"action": "pick", "station": "P-2", "load_id": "L-1"},
//                                   {"action": "drop", "station": "D-3", "load_id": "L-1"},
//                                   {"action": "wait", "duration_ns": 3000000000}]}]
//
// An entry has a pickup and a drop-off (a transport task, 2 s load and unload) or `steps` (a
// multi-stop task, the steps exactly as the HTTP API takes them, checked by the same rules).

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace fleet::ctl {

struct ScenarioTask {
  std::string id;       // as given, else generated ("task-001" after its place in the list)
  double atS = 0;       // simulated seconds after the start at which it is posted
  std::string pickup;   // a station of kind pickup (empty for a multi-stop task)
  std::string dropoff;  // a station of kind dropoff (empty for a multi-stop task)
  nlohmann::json steps = nlohmann::json::array();  // a multi-stop task's steps as the API takes them
  std::optional<std::int64_t> priority;
};

/// Priorities the HTTP API accepts (docs/openapi.yaml, libs/fleet Task).
inline constexpr std::int64_t kMinTaskPriority = -1000;
inline constexpr std::int64_t kMaxTaskPriority = 1000;

/// The scenario with its site inlined for fleetctl's own reading: a relative "site" path made
/// absolute against `origin`'s folder (the run's copy of the scenario lives elsewhere), and the
/// site's stations copied under "site_stations". A scenario without "site" is returned as it is.
/// Throws ConfigError when the site file cannot be read.
nlohmann::json resolveScenarioSite(nlohmann::json scenario, const std::string& origin);

/// A scenario template for generateScenario(): "site" dropped, the site's robot description
/// (radius, wheel base, limits, sensors) merged under "robot_defaults" where the template does
/// not set it. Throws ConfigError when the site file cannot be read.
nlohmann::json inlineSiteRobot(nlohmann::json scenario, const std::string& origin);

/// A scenario that carries its map, stations and landmarks inline split into a site.json document
/// (with the robot description from "robot_defaults") and the rest of the scenario.
std::pair<nlohmann::json, nlohmann::json> splitSite(nlohmann::json scenario);

/// The scenario's stations: the site's (after resolveScenarioSite) or its inline "stations".
const nlohmann::json& scenarioStations(const nlohmann::json& scenario);

/// Reads and checks the scenario document's `tasks` list against its stations (scenarioStations). No `tasks`
/// key: std::nullopt. Throws ConfigError listing every problem, each with `origin` and the key path
/// (`small_warehouse.json: tasks[3].pickup: unknown station 'P-9'`). The result is in list order.
std::optional<std::vector<ScenarioTask>> parseScenarioTasks(const nlohmann::json& scenario,
                                                            const std::string& origin);

/// The task as the HTTP API takes it (transport, 2 s load and unload, as generated tasks; or
/// multi-stop with its steps).
nlohmann::json toTaskRequest(const ScenarioTask& t);

}  // namespace fleet::ctl
