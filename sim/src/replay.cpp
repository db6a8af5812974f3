#include "fleet/sim/replay.hpp"

#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <set>

namespace fleet::sim {

namespace {
double mm(double x) {
  const double r = std::round(x * 1000.0) / 1000.0;
  return r == 0.0 ? 0.0 : r;  // no "-0.0"
}
}  // namespace

nlohmann::json replayHeader(const World& w) {
  const Scenario& s = w.scenario();
  nlohmann::json h;
  h["type"] = "header";
  h["scenario"] = s.name;
  h["seed"] = s.seed;
  h["dt"] = s.dt;
  h["near_miss_m"] = s.nearMiss;
  nlohmann::json map;
  map["width"] = s.map.width;
  map["height"] = s.map.height;
  map["resolution"] = s.map.resolution;
  map["origin"] = {s.map.origin.x, s.map.origin.y};
  nlohmann::json rows = nlohmann::json::array();
  for (int cy = s.map.height - 1; cy >= 0; --cy) {
    std::string row(static_cast<std::size_t>(s.map.width), '.');
    for (int cx = 0; cx < s.map.width; ++cx) {
      if (s.map.blocked(cx, cy)) {
        row[static_cast<std::size_t>(cx)] = '@';
      }
    }
    rows.push_back(row);
  }
  map["rows"] = rows;
  h["map"] = map;
  nlohmann::json st = nlohmann::json::array();
  for (const auto& x : s.stations) {
    st.push_back(
        {{"name", x.name}, {"kind", toString(x.kind)}, {"pose", {x.pose.x, x.pose.y, x.pose.theta}}});
  }
  h["stations"] = st;
  nlohmann::json robots = nlohmann::json::array();
  for (const auto& r : s.robots) {
    robots.push_back({{"id", r.id}, {"radius", r.radius}});
  }
  h["robots"] = robots;
  nlohmann::json humans = nlohmann::json::array();
  for (const auto& x : w.humans()) {
    humans.push_back({{"id", x.id}, {"radius", x.r}});
  }
  h["humans"] = humans;
  return h;
}

nlohmann::json replayStep(const World& w) {
  nlohmann::json j;
  j["step"] = w.step();
  j["t"] = mm(w.time());
  nlohmann::json robots = nlohmann::json::array();
  for (const auto& r : w.robots()) {
    robots.push_back({mm(r.pose.x), mm(r.pose.y), mm(r.pose.theta), mm(r.twist.v), mm(r.battery),
                      r.charging ? 1 : 0, r.mode, r.task});
    if (!r.activity.empty()) {
      robots.back().push_back(r.activity);  // the agent's RobotState.activity, when it says one
    }
  }
  j["robots"] = robots;
  nlohmann::json humans = nlohmann::json::array();
  for (const auto& h : w.humans()) {
    humans.push_back({mm(h.p.x), mm(h.p.y), mm(h.v.x), mm(h.v.y)});
  }
  j["humans"] = humans;
  nlohmann::json contacts = nlohmann::json::array();
  for (const auto& c : w.contacts()) {
    contacts.push_back({w.bodyId(c.a), w.bodyId(c.b), mm(c.depth)});
  }
  j["contacts"] = contacts;
  return j;
}

nlohmann::json replayRoadmap(const msg::Roadmap& m) {
  nlohmann::json nodes = nlohmann::json::array();
  nlohmann::json closed = nlohmann::json::array();
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    nodes.push_back(std::round(m.nodes[i].x * 100.0) / 100.0);
    nodes.push_back(std::round(m.nodes[i].y * 100.0) / 100.0);
    if (i < m.open.size() && !m.open[i]) {
      closed.push_back(i);
    }
  }
  nlohmann::json lanes = nlohmann::json::array();
  nlohmann::json closedEdges = nlohmann::json::array();
  std::set<std::pair<std::int32_t, std::int32_t>> drawn;
  for (const auto& e : m.edges) {
    if (!e.open) {
      closedEdges.push_back(e.from);
      closedEdges.push_back(e.to);
    } else if (drawn.insert({std::min(e.from, e.to), std::max(e.from, e.to)}).second) {
      lanes.push_back(e.from);
      lanes.push_back(e.to);
    }
  }
  return {{"epoch", m.epoch},           {"revision", m.revision}, {"nodes", nodes},
          {"kinds", m.kinds},           {"closed", closed},       {"lanes", lanes},
          {"closed_edges", closedEdges}};
}

nlohmann::json replayRelease(const msg::TrafficRelease& r) {
  nlohmann::json base = nlohmann::json::array();
  nlohmann::json horizon = nlohmann::json::array();
  for (const auto& n : r.base) {
    base.push_back(n.node);
  }
  for (const auto& n : r.horizon) {
    horizon.push_back(n.node);
  }
  return {{"b", base}, {"h", horizon}, {"g", r.ends_at_goal}};
}

nlohmann::json summary(const World& w) {
  const auto& m = w.metrics();
  const auto& c = w.counters();
  auto fin = [](double x) { return std::isfinite(x) ? nlohmann::json(mm(x)) : nlohmann::json(nullptr); };
  nlohmann::json j;
  j["scenario"] = w.scenario().name;
  j["seed"] = w.scenario().seed;
  j["steps"] = w.step();
  j["sim_time_s"] = w.time();
  j["robots"] = w.robots().size();
  j["humans"] = w.humans().size();
  j["contacts"] = {{"robot_robot", m.robotRobotContacts},
                   {"robot_human", m.robotHumanContacts},
                   {"robot_shelf", m.robotShelfContacts},
                   {"steps_with_contact", m.contactSteps}};
  j["near_misses"] = {{"robot_robot", m.nearMissRobotRobot}, {"robot_human", m.nearMissRobotHuman}};
  j["min_separation_m"] = {{"robot_robot", fin(m.minSepRobotRobot)},
                           {"robot_human", fin(m.minSepRobotHuman)},
                           {"robot_shelf", fin(m.minSepRobotShelf)}};
  j["commands"] = {{"nan_ignored", c.nanCommands},
                   {"clamped", c.clampedCommands},
                   {"unknown_robot", c.unknownRobot},
                   {"foreign_robot", c.foreignCommands},
                   {"timeouts", c.timeouts}};
  j["lockstep_step_timeouts"] = c.stepTimeouts;
  j["wall_overruns"] = c.wallOverruns;
  nlohmann::json per = nlohmann::json::object();
  for (std::size_t i = 0; i < w.robots().size(); ++i) {
    const auto& r = w.robots()[i];
    per[w.scenario().robots[i].id] = {{"distance_m", mm(r.distance)},
                                      {"idle_s", mm(r.idleS)},
                                      {"bumps", r.bumps},
                                      {"battery", mm(r.battery)}};
  }
  j["per_robot"] = per;
  return j;
}

Expected<ReplayWriter> ReplayWriter::open(const std::string& path) {
  gzFile f = gzopen(path.c_str(), "wb6");
  if (f == nullptr) {
    return unexpected("replay_io", "cannot open replay file '" + path + "' for writing");
  }
  return ReplayWriter(f);
}

ReplayWriter::ReplayWriter(ReplayWriter&& o) noexcept : f_(o.f_) {
  o.f_ = nullptr;
}

ReplayWriter::~ReplayWriter() {
  (void)close();
}

Expected<void> ReplayWriter::write(const nlohmann::json& line) {
  const std::string s = line.dump() + "\n";
  if (f_ == nullptr || gzwrite(static_cast<gzFile>(f_), s.data(), static_cast<unsigned>(s.size())) !=
                           static_cast<int>(s.size())) {
    return unexpected("replay_io", "write to replay failed");
  }
  return {};
}

Expected<void> ReplayWriter::close() {
  if (f_ == nullptr) {
    return {};
  }
  const int rc = gzclose(static_cast<gzFile>(f_));
  f_ = nullptr;
  if (rc != Z_OK) {
    return unexpected("replay_io", "closing the replay failed (zlib " + std::to_string(rc) + ")");
  }
  return {};
}

Expected<std::vector<std::string>> readReplayLines(const std::string& path) {
  gzFile f = gzopen(path.c_str(), "rb");  // reads plain text transparently too
  if (f == nullptr) {
    return unexpected("replay_io", "cannot open replay '" + path + "'");
  }
  std::vector<std::string> lines;
  std::string cur;
  char buf[1 << 16];
  int n = 0;
  while ((n = gzread(f, buf, sizeof buf)) > 0) {
    for (int i = 0; i < n; ++i) {
      if (buf[i] == '\n') {
        lines.push_back(std::move(cur));
        cur.clear();
      } else {
        cur.push_back(buf[i]);
      }
    }
  }
  gzclose(f);
  if (n < 0) {
    return unexpected("replay_io", "replay '" + path + "' is corrupt");
  }
  if (!cur.empty()) {
    lines.push_back(cur);
  }
  return lines;
}

}  // namespace fleet::sim
