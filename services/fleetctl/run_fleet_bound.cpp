#include "run_fleet_bound.hpp"

#include "round3.hpp"

#include <sqlite3.h>

#include <cmath>
#include <cstdio>
#include <optional>

#include "fleet/control/cruise.hpp"
#include "fleet/core/config.hpp"
#include "fleet/scenario/scenario.hpp"
#include "fleet/traffic/roadmap.hpp"

namespace fleet::ctl {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// A stored task's stops (ListTask), or none when it visits no station the bound counts (goto,
/// charge and park tasks: not the list's work). A multi-stop task is its steps, each with its
/// duration; a transport task its pickup and drop-off with their load and unload time.
std::optional<ListTask> stopsOf(const json& b) {
  const auto seconds = [](const json& o, const char* key) {
    const auto it = o.find(key);
    return it != o.end() && it->is_number() ? it->get<double>() * 1e-9 : 0.0;
  };
  if (const auto steps = b.find("steps"); steps != b.end() && steps->is_array() && !steps->empty()) {
    ListTask t;
    for (const auto& step : *steps) {
      if (!step.is_object()) {
        return std::nullopt;
      }
      const auto station = step.find("station");
      t.stops.push_back({station != step.end() && station->is_string() ? station->get<std::string>() : "",
                         seconds(step, "duration_ns")});
    }
    return t;
  }
  if (b.value("pickup", "").empty() || b.value("dropoff", "").empty()) {
    return std::nullopt;
  }
  return ListTask::transport(b.value("pickup", ""), b.value("dropoff", ""), seconds(b, "load_duration_ns"),
                             seconds(b, "unload_duration_ns"));
}

/// The tasks of the run in posting order (first transition), with their stops and dwell.
std::optional<std::string> readList(const fs::path& dbPath, std::vector<ListTask>& out, std::size_t& other) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(dbPath.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    std::string why = "cannot open " + dbPath.string() + ": " + (db ? sqlite3_errmsg(db) : "out of memory");
    sqlite3_close(db);
    return why;
  }
  sqlite3_stmt* s = nullptr;
  std::optional<std::string> error;
  const char* sql =
      "SELECT t.body FROM tasks t JOIN (SELECT task_id, MIN(seq) AS first FROM transitions GROUP BY task_id) "
      "f "
      "ON f.task_id = t.id ORDER BY f.first";
  if (sqlite3_prepare_v2(db, sql, -1, &s, nullptr) == SQLITE_OK) {
    while (sqlite3_step(s) == SQLITE_ROW) {
      const auto* p = sqlite3_column_text(s, 0);
      const json b = json::parse(p ? reinterpret_cast<const char*>(p) : "", nullptr, false);
      auto task = b.is_object() ? stopsOf(b) : std::nullopt;
      if (!task) {
        ++other;
        continue;
      }
      out.push_back(std::move(*task));
    }
  } else {
    error = std::string("task database: ") + sqlite3_errmsg(db);
  }
  sqlite3_finalize(s);
  sqlite3_close(db);
  return error;
}

}  // namespace

json fleetBoundJson(const FleetBound& b, double fleetRatePerH, double cruise, double radius) {
  json stations = json::array();
  for (const auto& s : b.stations) {
    stations.push_back({{"name", s.name},
                        {"visits", s.visits},
                        {"share", round3(s.share)},
                        {"move_s", round3(s.moveS)},
                        {"cycle_s", round3(s.cycleS)},
                        {"bound_per_h", round3(s.boundPerH)}});
  }
  const double bound = b.perH();
  return {{"definition",
           "min(robot bound, station bound): robots × a lone robot's rate on this task list (posted at once, "
           "done in posting order, each chained from the last stop of the one before, the disc's shortest "
           "way at cruise plus "
           "load and unload) and min over stations of 3600 / (c_s × f_s) (c_s its least dock cycle, f_s its "
           "visits per task); docs/algorithms.md, \"Fleet bound\""},
          {"robots", b.robots},
          {"tasks", b.tasks},
          {"cruise_m_s", cruise},
          {"radius_m", radius},
          {"lone_chain_m", round3(b.chainDriveM)},
          {"lone_chain_s", round3(b.chainS)},
          {"lone_rate_per_h", round3(b.lonePerH)},
          {"robot_bound_per_h", round3(b.robotPerH)},
          {"station_bound_per_h", round3(b.stationPerH)},
          {"binding_station", b.bindingStation},
          {"binds", b.robotsBind() ? "robots" : "stations"},
          {"bound_per_h", round3(bound)},
          {"fleet_rate_per_h", round3(fleetRatePerH)},
          {"fraction_of_bound", bound > 0.0 ? round3(fleetRatePerH / bound) : 0.0},
          {"stations", stations}};
}

json runFleetBound(const fs::path& runDir, double fleetRatePerH) {
  try {
    std::vector<ListTask> list;
    std::size_t other = 0;
    if (auto e = readList(runDir / "fleet.db", list, other)) {
      return {{"error", *e}};
    }
    const sim::Scenario scn = sim::loadScenario((runDir / "scenario.json").string());
    if (!scn.site) {
      return {{"error", "the scenario has no site"}};
    }
    if (scn.robots.empty()) {
      return {{"error", "the scenario has no robot"}};
    }
    FleetBoundInput in;
    // The stations as the traffic manager's roadmap lays them out (approach, queue and exit);
    // geometry only, so without flow guidance (its start-up is ~15 s on the site for 1,000 robots).
    traffic::RoadmapOptions geometry;
    geometry.guidance = 0.0;
    in.stations = boundStations(traffic::buildRoadmap(*scn.site, geometry));
    in.tasks = std::move(list);
    // The bound is the best robot's: the smallest disc at the fastest cruise.
    in.radius = scn.robots.front().radius;
    in.cruise = control::agentCruiseSpeed(scn.robots.front().limits);
    for (const auto& r : scn.robots) {
      in.starts.push_back(r.start.position());
      in.radius = std::min(in.radius, r.radius);
      in.cruise = std::max(in.cruise, control::agentCruiseSpeed(r.limits));
    }
    const auto b = fleetBound(scn.site->drivable(), in);
    if (!b) {
      return {{"error", b.error().code + ": " + b.error().message}};
    }
    json j = fleetBoundJson(*b, fleetRatePerH, in.cruise, in.radius);
    j["tasks_not_transport"] = other;
    return j;
  } catch (const ConfigError& e) {
    return {{"error", std::string("scenario: ") + e.what()}};
  } catch (const std::exception& e) {
    return {{"error", e.what()}};
  }
}

std::string fleetBoundLine(const json& b) {
  if (b.contains("error")) {
    return "fleet bound: not computed: " + b["error"].get<std::string>();
  }
  char buf[512];
  const bool robots = b.value("binds", "") == "robots";
  std::snprintf(
      buf, sizeof buf,
      "fleet: %.1f tasks/h = %.0f %% of the fleet bound %.1f tasks/h (%s) — robots %zu × a lone robot's "
      "%.1f/h on this list = %.1f/h; stations %.1f/h (busiest %s)",
      b.value("fleet_rate_per_h", 0.0), 100.0 * b.value("fraction_of_bound", 0.0),
      b.value("bound_per_h", 0.0), robots ? "robots" : "stations", b.value("robots", std::size_t{0}),
      b.value("lone_rate_per_h", 0.0), b.value("robot_bound_per_h", 0.0), b.value("station_bound_per_h", 0.0),
      b.value("binding_station", std::string("-")).c_str());
  return buf;
}

}  // namespace fleet::ctl
