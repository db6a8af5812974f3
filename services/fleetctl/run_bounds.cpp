#include "run_bounds.hpp"

#include "round3.hpp"

#include <sqlite3.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "fleet/control/cruise.hpp"
#include "fleet/core/config.hpp"
#include "fleet/scenario/scenario.hpp"
#include "gz_lines.hpp"
#include "kinematic_bound.hpp"

namespace fleet::ctl {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

/// A done task as the manager recorded it: its last assignment before its first "done".
struct DoneTask {
  std::string id;
  std::string robot;
  double assignedS = 0.0;
  double doneS = 0.0;
  std::string pickup;
  std::string dropoff;
  double dwellS = 0.0;
};

std::optional<std::string> readDoneTasks(const fs::path& dbPath, std::vector<DoneTask>& out) {
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(dbPath.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    std::string why = "cannot open " + dbPath.string() + ": " + (db ? sqlite3_errmsg(db) : "out of memory");
    sqlite3_close(db);
    return why;
  }
  auto text = [](sqlite3_stmt* s, int c) {
    const auto* p = sqlite3_column_text(s, c);
    return p ? std::string(reinterpret_cast<const char*>(p)) : std::string();
  };
  std::optional<std::string> error;
  std::map<std::string, std::pair<std::string, std::int64_t>> lastAssigned;
  std::set<std::string> done;
  sqlite3_stmt* s = nullptr;
  if (sqlite3_prepare_v2(db, "SELECT task_id, to_state, robot, stamp_ns FROM transitions ORDER BY seq", -1,
                         &s, nullptr) == SQLITE_OK) {
    while (sqlite3_step(s) == SQLITE_ROW) {
      const std::string task = text(s, 0);
      const std::string to = text(s, 1);
      if (to == "assigned") {
        lastAssigned[task] = {text(s, 2), sqlite3_column_int64(s, 3)};
      } else if (to == "done" && done.insert(task).second && lastAssigned.count(task)) {
        const auto& [robot, at] = lastAssigned[task];
        out.push_back({task,
                       robot,
                       static_cast<double>(at) * 1e-9,
                       static_cast<double>(sqlite3_column_int64(s, 3)) * 1e-9,
                       {},
                       {},
                       0.0});
      }
    }
  } else {
    error = std::string("task database: ") + sqlite3_errmsg(db);
  }
  sqlite3_finalize(s);
  std::map<std::string, json> bodies;
  if (!error && sqlite3_prepare_v2(db, "SELECT id, body FROM tasks", -1, &s, nullptr) == SQLITE_OK) {
    while (sqlite3_step(s) == SQLITE_ROW) {
      bodies[text(s, 0)] = json::parse(text(s, 1), nullptr, false);
    }
  } else if (!error) {
    error = std::string("task database: ") + sqlite3_errmsg(db);
  }
  sqlite3_finalize(s);
  sqlite3_close(db);
  for (auto& t : out) {
    const json& b = bodies[t.id];
    if (b.is_object()) {
      t.pickup = b.value("pickup", "");
      t.dropoff = b.value("dropoff", "");
      t.dwellS = static_cast<double>(b.value("load_duration_ns", std::int64_t{0}) +
                                     b.value("unload_duration_ns", std::int64_t{0})) *
                 1e-9;
    }
  }
  return error;
}

/// Each robot's position at each asked time: at the first replay step at or after it (the manager
/// stamps with the simulated clock of the step it last saw). `asks` is (time, robot index).
std::optional<std::string> positionsAt(const fs::path& replay,
                                       const std::vector<std::pair<double, std::size_t>>& asks,
                                       std::vector<std::string>& robotIds,
                                       std::map<std::pair<double, std::size_t>, Vec2>& out) {
  gzFile f = gzopen(replay.c_str(), "rb");
  if (f == nullptr) {
    return "cannot open " + replay.string();
  }
  std::string line;
  if (!readGzLine(f, line)) {
    gzclose(f);
    return replay.string() + " is empty";
  }
  const json header = json::parse(line, nullptr, false);
  if (!header.is_object() || header.value("type", "") != "header" || !header.contains("robots")) {
    gzclose(f);
    return replay.string() + ": no header line";
  }
  for (const auto& r : header["robots"]) {
    robotIds.push_back(r.value("id", ""));
  }
  std::vector<std::pair<double, std::size_t>> sorted = asks;
  std::sort(sorted.begin(), sorted.end());
  std::size_t next = 0;
  while (next < sorted.size() && readGzLine(f, line)) {
    // Keys are written sorted, so "t" is the line's last: read it without parsing the whole step.
    const auto k = line.rfind("\"t\":");
    const double t = k == std::string::npos ? -1.0 : std::strtod(line.c_str() + k + 4, nullptr);
    if (t + 1e-6 < sorted[next].first) {
      continue;
    }
    const json step = json::parse(line, nullptr, false);
    if (!step.is_object() || !step.contains("robots")) {
      continue;
    }
    const auto& robots = step["robots"];
    for (; next < sorted.size() && sorted[next].first <= t + 1e-6; ++next) {
      const std::size_t i = sorted[next].second;
      if (i < robots.size() && robots[i].is_array() && robots[i].size() >= 2) {
        out[sorted[next]] = {robots[i][0].get<double>(), robots[i][1].get<double>()};
      }
    }
  }
  gzclose(f);
  return std::nullopt;
}

}  // namespace

json runBounds(const fs::path& runDir) {
  try {
    std::vector<DoneTask> done;
    if (auto e = readDoneTasks(runDir / "fleet.db", done)) {
      return {{"error", *e}};
    }
    const sim::Scenario scn = sim::loadScenario((runDir / "scenario.json").string());
    if (!scn.site) {
      return {{"error", "the scenario has no site"}};
    }
    std::map<std::string, std::size_t> robotIndex;
    for (std::size_t i = 0; i < scn.robots.size(); ++i) {
      robotIndex[scn.robots[i].id] = i;
    }
    std::map<std::string, Vec2> stations;
    for (const auto& s : scn.stations) {
      stations[s.name] = s.pose.position();
    }
    std::vector<std::pair<double, std::size_t>> asks;
    for (const auto& t : done) {
      if (robotIndex.count(t.robot)) {
        asks.emplace_back(t.assignedS, robotIndex[t.robot]);
      }
    }
    std::vector<std::string> replayRobots;
    std::map<std::pair<double, std::size_t>, Vec2> where;
    if (auto e = positionsAt(runDir / "replay.jsonl.gz", asks, replayRobots, where)) {
      return {{"error", *e}};
    }
    std::vector<std::string> scenarioRobots;
    for (const auto& r : scn.robots) {
      scenarioRobots.push_back(r.id);
    }
    if (replayRobots != scenarioRobots) {
      return {{"error", "the replay's robots are not the scenario's"}};
    }
    // Every task that can be bounded goes to the computation; the others are listed with why.
    std::vector<BoundTask> inputs;
    std::vector<const DoneTask*> bounded;
    json unbounded = json::array();
    std::set<double> cruises, radii;
    for (const auto& t : done) {
      std::string why;
      const auto r = robotIndex.find(t.robot);
      if (r == robotIndex.end()) {
        why = "robot '" + t.robot + "' is not in the scenario";
      } else if (!stations.count(t.pickup) || !stations.count(t.dropoff)) {
        why = "station '" + (stations.count(t.pickup) ? t.dropoff : t.pickup) + "' is not in the scenario";
      } else if (!where.count({t.assignedS, r->second})) {
        why = "the replay has no step at " + std::to_string(t.assignedS) + " s";
      }
      if (!why.empty()) {
        unbounded.push_back({{"id", t.id}, {"reason", why}});
        continue;
      }
      const auto& spec = scn.robots[r->second];
      BoundTask b{where.at({t.assignedS, r->second}),
                  stations.at(t.pickup),
                  stations.at(t.dropoff),
                  spec.radius,
                  control::agentCruiseSpeed(spec.limits),
                  t.dwellS};
      cruises.insert(b.cruise);
      radii.insert(b.radius);
      inputs.push_back(b);
      bounded.push_back(&t);
    }
    const auto results = kinematicBounds(scn.site->drivable(), inputs);
    json perTask = json::array();
    std::vector<double> taskS, boundS;
    for (std::size_t i = 0; i < results.size(); ++i) {
      const DoneTask& t = *bounded[i];
      if (!results[i]) {
        unbounded.push_back({{"id", t.id}, {"reason", results[i].error().message}});
        continue;
      }
      const KinematicBound& b = *results[i];
      const double time = t.doneS - t.assignedS;
      taskS.push_back(time);
      boundS.push_back(b.seconds());
      perTask.push_back({{"id", t.id},
                         {"robot", t.robot},
                         {"from", {round3(inputs[i].start.x), round3(inputs[i].start.y)}},
                         {"pickup", t.pickup},
                         {"dropoff", t.dropoff},
                         {"to_pickup_m", round3(b.toPickupM)},
                         {"to_dropoff_m", round3(b.toDropoffM)},
                         {"dwell_s", round3(b.dwellS)},
                         {"bound_s", round3(b.seconds())},
                         {"task_time_s", round3(time)},
                         {"ratio", b.seconds() > 0.0 ? round3(time / b.seconds()) : 0.0}});
    }
    const BoundFigures f = boundFigures(taskS, boundS);
    return {
        {"method",
         "shortest way for the robot's disc on the free map (0.1 m cells, any-angle: Lazy Theta*) from where "
         "it was at its last assignment to the pickup and on to the drop-off, at the agent's cruise, plus "
         "load and unload"},
        {"cruise_m_s", json(std::vector<double>(cruises.begin(), cruises.end()))},
        {"radius_m", json(std::vector<double>(radii.begin(), radii.end()))},
        {"tasks_done", done.size()},
        {"tasks", f.tasks},
        {"mean_task_time_s", round3(f.meanTaskS)},
        {"mean_bound_s", round3(f.meanBoundS)},
        {"task_time_over_bound", round3(f.timeOverBound)},
        {"per_task", perTask},
        {"unbounded", unbounded}};
  } catch (const ConfigError& e) {
    return {{"error", std::string("scenario: ") + e.what()}};
  } catch (const std::exception& e) {
    return {{"error", e.what()}};
  }
}

std::string boundLine(const json& b) {
  if (b.contains("error")) {
    return "kinematic bound: not computed: " + b["error"].get<std::string>();
  }
  const auto n = b.value("tasks", std::size_t{0});
  if (n == 0) {
    return "kinematic bound: no task done" +
           std::string(b.value("tasks_done", 0) > 0 ? " with a bound (see loadtest.json)" : "");
  }
  char buf[512];
  std::snprintf(
      buf, sizeof buf,
      "kinematic bound: task time mean %.1f s = %.2fx the bound (mean %.1f s: the disc's shortest way at "
      "%g m/s plus dwell, from where the robot was at its assignment) over %zu of %zu done tasks",
      b.value("mean_task_time_s", 0.0), b.value("task_time_over_bound", 0.0), b.value("mean_bound_s", 0.0),
      b["cruise_m_s"].empty() ? 0.0 : b["cruise_m_s"].back().get<double>(), n,
      b.value("tasks_done", std::size_t{0}));
  return buf;
}

}  // namespace fleet::ctl
