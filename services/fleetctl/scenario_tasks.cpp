#include "scenario_tasks.hpp"

#include <cstdio>
#include <filesystem>
#include <limits>
#include <map>
#include <set>

#include "fleet/core/bounded_file.hpp"
#include "fleet/core/config.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/fleet/station_map.hpp"
#include "fleet/fleet/task.hpp"

namespace fleet::ctl {
namespace {

std::optional<StationKind> stationKindOf(std::string_view kind) {
  for (const auto k :
       {StationKind::Pickup, StationKind::Dropoff, StationKind::Charging, StationKind::Parking}) {
    if (toString(k) == kind) {
      return k;
    }
  }
  return std::nullopt;
}

/// "P-1, P-2, P-3" (at most 8 names).
std::string nameList(const std::vector<std::string>& names) {
  std::string out;
  for (std::size_t i = 0; i < names.size() && i < 8; ++i) {
    out += (i == 0 ? "" : ", ") + names[i];
  }
  if (names.size() > 8) {
    out += ", ... (" + std::to_string(names.size()) + " in all)";
  }
  return out.empty() ? "none" : out;
}

}  // namespace

nlohmann::json resolveScenarioSite(nlohmann::json scenario, const std::string& origin) {
  if (!scenario.is_object() || !scenario.contains("site") || !scenario["site"].is_string()) {
    return scenario;
  }
  std::filesystem::path p(scenario["site"].get<std::string>());
  if (p.is_relative()) {
    p = std::filesystem::absolute(std::filesystem::path(origin).parent_path() / p).lexically_normal();
  }
  scenario["site"] = p.string();
  const auto text = readBoundedFile(p.string(), kConfigFileLimit, "invalid");
  if (!text) {
    throw ConfigError({origin + ": site: cannot read the site file: " + text.error().message});
  }
  auto site = nlohmann::json::parse(*text, nullptr, false);
  if (site.is_discarded() || !site.is_object()) {
    throw ConfigError({origin + ": site: cannot read the site file " + p.string() + " (not a JSON object)"});
  }
  scenario["site_stations"] = site.value("stations", nlohmann::json::array());
  return scenario;
}

nlohmann::json inlineSiteRobot(nlohmann::json scenario, const std::string& origin) {
  scenario = resolveScenarioSite(std::move(scenario), origin);
  if (!scenario.contains("site")) {
    return scenario;
  }
  // resolveScenarioSite read it already, so it is a bounded regular file holding a JSON object.
  const auto text = readBoundedFile(scenario["site"].get<std::string>(), kConfigFileLimit, "invalid");
  const auto site = text ? nlohmann::json::parse(*text, nullptr, false) : nlohmann::json::object();
  auto& defaults = scenario["robot_defaults"];
  if (!defaults.is_object()) {
    defaults = nlohmann::json::object();
  }
  const auto robot = site.value("robot", nlohmann::json::object());
  for (const auto& [k, v] : robot.items()) {
    if (!defaults.contains(k)) {
      defaults[k] = v;
    } else if (v.is_object() && defaults[k].is_object()) {
      for (const auto& [kk, vv] : v.items()) {
        if (!defaults[k].contains(kk)) {
          defaults[k][kk] = vv;
        }
      }
    }
  }
  scenario.erase("site");
  scenario.erase("site_stations");
  return scenario;
}

std::pair<nlohmann::json, nlohmann::json> splitSite(nlohmann::json scenario) {
  nlohmann::json site = {{"format", "fleet-site/1"}, {"name", scenario.value("name", "generated")}};
  for (const char* k : {"map", "stations", "landmarks"}) {
    if (scenario.contains(k)) {
      site[k] = scenario[k];
      scenario.erase(k);
    }
  }
  if (scenario.contains("robot_defaults") && scenario["robot_defaults"].is_object()) {
    auto& d = scenario["robot_defaults"];
    for (const char* k : {"radius", "wheel_base", "limits"}) {
      if (d.contains(k)) {
        site["robot"][k] = d[k];
        d.erase(k);
      }
    }
  }
  return {site, scenario};
}

const nlohmann::json& scenarioStations(const nlohmann::json& scenario) {
  static const nlohmann::json none = nlohmann::json::array();
  for (const char* k : {"site_stations", "stations"}) {
    if (scenario.is_object() && scenario.contains(k) && scenario[k].is_array()) {
      return scenario[k];
    }
  }
  return none;
}

std::optional<std::vector<ScenarioTask>> parseScenarioTasks(const nlohmann::json& scenario,
                                                            const std::string& origin) {
  if (!scenario.is_object() || !scenario.contains("tasks")) {
    return std::nullopt;
  }
  // Station names and kinds; the stations themselves are the simulator's to check.
  std::map<std::string, std::string> kindOf;
  std::map<std::string, std::vector<std::string>> byKind;
  StationMap stations;
  {
    const auto withSite = scenario.contains("site") && !scenario.contains("site_stations")
                              ? resolveScenarioSite(scenario, origin)
                              : scenario;
    for (const auto& s : scenarioStations(withSite)) {
      if (s.is_object() && s.contains("name") && s["name"].is_string() && s.contains("kind") &&
          s["kind"].is_string()) {
        const std::string name = s["name"];
        if (kindOf.emplace(name, s["kind"].get<std::string>()).second) {
          byKind[s["kind"].get<std::string>()].push_back(name);
          // For the steps' checks: the name and its kind (a pose is not needed to check a task).
          if (auto kind = stationKindOf(s["kind"].get<std::string>())) {
            (void)stations.add({name, {}, static_cast<std::uint8_t>(*kind)});
          }
        }
      }
    }
  }

  Config c = Config::fromJson(scenario, origin);
  std::vector<ScenarioTask> tasks;
  std::vector<bool> hasId;
  std::map<std::string, std::string> idAt;  // explicit id -> its key path
  for (auto& e : c.array("tasks")) {
    if (!e.json().is_object()) {
      tasks.emplace_back();
      hasId.push_back(false);
      continue;  // already a problem
    }
    e.rejectUnknownKeys({"at_s", "pickup", "dropoff", "steps", "id", "priority"});
    ScenarioTask t;
    t.atS = e.requireNumber("at_s", {0.0, std::numeric_limits<double>::infinity()});
    if (const nlohmann::json* steps = e.find("steps"); steps != nullptr) {
      if (e.find("pickup") != nullptr || e.find("dropoff") != nullptr) {
        e.problem("steps", "a task has steps or a pickup and a drop-off, not both");
      }
      // The fleet manager's own rules (libs/fleet parseTask): what it would refuse is named here.
      const auto task =
          parseTask({{"id", "scenario-task"}, {"kind", "multistop"}, {"steps", *steps}}, &stations);
      if (!task) {
        for (const auto& f : task.error().fields) {
          e.problem(f.path, f.reason);
        }
      }
      t.steps = *steps;
    } else {
      for (const auto& [key, wanted] : {std::pair<std::string, std::string>{"pickup", "pickup"},
                                        std::pair<std::string, std::string>{"dropoff", "dropoff"}}) {
        const nlohmann::json* j = e.find(key);
        std::string name = e.requireString(key);
        if (j == nullptr || !j->is_string()) {
          continue;
        }
        auto it = kindOf.find(name);
        if (it == kindOf.end()) {
          e.problem(key, "unknown station '" + name + "' (" + wanted +
                             " stations: " + nameList(byKind[wanted]) + ")");
        } else if (it->second != wanted) {
          e.problem(key, "station '" + name + "' is a " + it->second + " station; expected a " + wanted +
                             " station (" + nameList(byKind[wanted]) + ")");
        }
        (key == "pickup" ? t.pickup : t.dropoff) = name;
      }
    }
    if (const nlohmann::json* j = e.find("id"); j != nullptr) {
      const std::string id = e.requireString("id");
      if (j->is_string()) {
        if (!isValidId(id)) {
          e.problem("id", "expected 1 to 63 characters of A-Z a-z 0-9 _ . : - (as the HTTP API), got \"" +
                              id + "\"");
        } else if (auto [it, fresh] = idAt.emplace(id, e.keyPath("")); !fresh) {
          e.problem("id", "duplicate id '" + id + "' (also " + it->second + ")");
        }
        t.id = id;
      }
    }
    hasId.push_back(e.find("id") != nullptr);
    if (e.find("priority") != nullptr) {
      const nlohmann::json* j = e.find("priority");
      const std::int64_t p = e.integer(
          "priority", 0, {static_cast<double>(kMinTaskPriority), static_cast<double>(kMaxTaskPriority)});
      if ((j->is_number_integer() || j->is_number_unsigned()) && p >= kMinTaskPriority &&
          p <= kMaxTaskPriority) {
        t.priority = p;
      }
    }
    tasks.push_back(t);
  }
  c.finish();  // throws ConfigError listing every problem

  // Ids for entries without one: task-NNN after the entry's place in the list, never an id given.
  std::set<std::string> used;
  for (const auto& [id, at] : idAt) {
    used.insert(id);
  }
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    if (hasId[i]) {
      continue;
    }
    char buf[32];
    std::snprintf(buf, sizeof buf, "task-%03zu", i + 1);
    std::string id = buf;
    for (int k = 2; used.count(id); ++k) {
      id = std::string(buf) + "-" + std::to_string(k);
    }
    used.insert(id);
    tasks[i].id = id;
  }
  return tasks;
}

nlohmann::json toTaskRequest(const ScenarioTask& t) {
  if (!t.steps.empty()) {
    nlohmann::json j = {{"id", t.id}, {"kind", "multistop"}, {"steps", t.steps}};
    if (t.priority) {
      j["priority"] = *t.priority;
    }
    return j;
  }
  nlohmann::json j = {{"id", t.id},
                      {"kind", "transport"},
                      {"pickup", t.pickup},
                      {"dropoff", t.dropoff},
                      {"load_duration_ns", 2000000000LL},
                      {"unload_duration_ns", 2000000000LL}};
  if (t.priority) {
    j["priority"] = *t.priority;
  }
  return j;
}

}  // namespace fleet::ctl
