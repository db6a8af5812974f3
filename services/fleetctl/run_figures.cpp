#include "run_figures.hpp"

#include <sqlite3.h>
#include <zlib.h>

#include <algorithm>
#include <map>

#include "fleet/control/cruise.hpp"
#include "fleet/core/config.hpp"
#include "fleet/scenario/scenario.hpp"
#include "fleet/traffic/roadmap.hpp"
#include "gz_lines.hpp"
#include "run_fleet_bound.hpp"
#include "run_ledger.hpp"

namespace fleet::ctl {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::map<std::string, LedgerTask> taskStations(const fs::path& dbPath) {
  std::map<std::string, LedgerTask> out;
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(dbPath.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) == SQLITE_OK) {
    sqlite3_stmt* s = nullptr;
    if (sqlite3_prepare_v2(db, "SELECT id, body FROM tasks", -1, &s, nullptr) == SQLITE_OK) {
      while (sqlite3_step(s) == SQLITE_ROW) {
        const auto* id = sqlite3_column_text(s, 0);
        const auto* body = sqlite3_column_text(s, 1);
        const json b = json::parse(body ? reinterpret_cast<const char*>(body) : "", nullptr, false);
        if (id != nullptr && b.is_object()) {
          out[reinterpret_cast<const char*>(id)] = {b.value("pickup", ""), b.value("dropoff", "")};
        }
      }
    }
    sqlite3_finalize(s);
  }
  sqlite3_close(db);
  return out;
}

/// m beyond the farthest place of a station's line at which a robot still counts as in it (it
/// follows its line within a few tenths of a metre).
constexpr double kLineTolerance = 0.5;
/// m within which a robot is at a dock or at a station's entry (RunLedger's dockTolerance).
constexpr double kDockTolerance = 0.25;

/// Both ledgers over the replay: {"robot_time": ..., "stations": ...} or {"error": ...}.
json ledgers(const fs::path& runDir) {
  const sim::Scenario scn = sim::loadScenario((runDir / "scenario.json").string());
  // Each station's line (queue places and approach) as the traffic manager's roadmap lays it out:
  // a dock cycle counts when the next robot stood within it.
  std::map<std::string, double> lineReach;
  std::map<std::string, std::pair<Vec2, double>> entries;  // the last leg's start and its time
  const double cruise = scn.robots.empty() ? 0.0 : control::agentCruiseSpeed(scn.robots.front().limits);
  if (scn.site) {
    // Geometry only: no flow guidance (its start-up is ~15 s on the site for 1,000 robots).
    traffic::RoadmapOptions geometry;
    geometry.guidance = 0.0;
    const traffic::Roadmap roadmap = traffic::buildRoadmap(*scn.site, geometry);
    for (const auto& st : roadmap.stations) {
      if (st.dock == traffic::kNoNode) {
        continue;
      }
      std::vector<traffic::NodeId> line = st.queue;
      line.push_back(st.approach);
      double reach = 0.0;
      for (const traffic::NodeId v : line) {
        if (v != traffic::kNoNode) {
          reach = std::max(reach, (roadmap.graph.position(v) - roadmap.graph.position(st.dock)).norm());
        }
      }
      lineReach[st.name] = reach + kLineTolerance;
      // The last leg: from the approach, or from the queue's head for a station entered along a row.
      const traffic::NodeId entry = st.approach != traffic::kNoNode ? st.approach
                                    : st.queue.empty()              ? traffic::kNoNode
                                                                    : st.queue.front();
      // The ledger times the leg from the last step within its tolerance of the entry (a turn on
      // the spot there included in neither) to the first within it of the dock: that span at cruise.
      if (entry != traffic::kNoNode && roadmap.graph.edge(entry, st.dock) != nullptr && cruise > 0.0) {
        const double length = (roadmap.graph.position(st.dock) - roadmap.graph.position(entry)).norm();
        entries[st.name] = {roadmap.graph.position(entry),
                            std::max(0.0, length - 2.0 * kDockTolerance) / cruise};
      }
    }
  }
  std::vector<LedgerStation> stations;
  for (const auto& s : scn.stations) {
    if (s.kind == site::StationKind::Pickup || s.kind == site::StationKind::Dropoff) {
      const auto it = lineReach.find(s.name);
      LedgerStation ls{s.name, s.pose.position(), it == lineReach.end() ? 0.0 : it->second};
      if (const auto e = entries.find(s.name); e != entries.end()) {
        ls.hasEntry = true;
        ls.entry = e->second.first;
        ls.dockModelS = e->second.second;
      }
      stations.push_back(ls);
    }
  }
  std::vector<std::string> robots;
  for (const auto& r : scn.robots) {
    robots.push_back(r.id);
  }
  RunLedger ledger(robots, stations, taskStations(runDir / "fleet.db"), kDockTolerance);
  const fs::path replay = runDir / "replay.jsonl.gz";
  gzFile f = gzopen(replay.c_str(), "rb");
  if (f == nullptr) {
    return {{"error", "cannot open " + replay.string()}};
  }
  std::string line;
  std::vector<RobotSample> samples(robots.size());
  while (readGzLine(f, line)) {
    const json step = json::parse(line, nullptr, false);
    if (!step.is_object() || !step.contains("robots") || !step.contains("t")) {
      continue;  // the header, or a line cut short
    }
    const auto& rs = step["robots"];
    if (!rs.is_array() || rs.size() != robots.size()) {
      continue;
    }
    for (std::size_t i = 0; i < rs.size(); ++i) {
      const auto& r = rs[i];
      RobotSample& x = samples[i];
      // [x, y, theta, v, battery, charging, mode, task(, activity)] (sim/src/replay.cpp)
      if (!r.is_array() || r.size() < 8) {
        x = {};
        continue;
      }
      x.position = {r[0].get<double>(), r[1].get<double>()};
      x.charging = r[5].is_number() && r[5].get<double>() != 0.0;
      x.mode = r[6].is_string() ? r[6].get<std::string>() : "";
      x.task = r[7].is_string() ? r[7].get<std::string>() : "";
      x.activity = r.size() > 8 && r[8].is_string() ? r[8].get<std::string>() : "";
    }
    ledger.step(step["t"].get<double>(), samples);
  }
  gzclose(f);
  return {{"robot_time", ledger.robotTimeJson()}, {"stations", ledger.stationsJson()}};
}

}  // namespace

void addRunFigures(json& report, const fs::path& runDir, bool wallClock) {
  const double rate = report["throughput"].value("done_per_sim_hour", 0.0);
  report["fleet_bound"] = runFleetBound(runDir, rate);
  if (wallClock && !report["fleet_bound"].contains("error")) {
    report["fleet_bound"]["note"] = "wall-clock run: the rate is per simulated hour of a 1x simulator";
  }
  try {
    json l = ledgers(runDir);
    if (l.contains("error")) {
      report["robot_time"] = l;
      report["stations"] = json::array();
    } else {
      report["robot_time"] = std::move(l["robot_time"]);
      report["stations"] = std::move(l["stations"]);
    }
  } catch (const std::exception& e) {
    report["robot_time"] = {{"error", e.what()}};
    report["stations"] = json::array();
  }
}

std::vector<std::string> runFigureLines(const json& report) {
  std::vector<std::string> out;
  if (report.contains("fleet_bound")) {
    out.push_back(fleetBoundLine(report["fleet_bound"]));
  }
  const json& rt = report.contains("robot_time") ? report["robot_time"] : json();
  if (rt.is_object() && rt.contains("error")) {
    out.push_back("robot time: not computed: " + rt["error"].get<std::string>());
  }
  for (auto& l : ledgerLines(rt, report.contains("stations") ? report["stations"] : json::array())) {
    out.push_back(std::move(l));
  }
  return out;
}

}  // namespace fleet::ctl
