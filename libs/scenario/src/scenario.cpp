#include "fleet/scenario/scenario.hpp"

#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "fleet/core/angles.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/planning/map_io.hpp"
#include "fleet/site/site_loader.hpp"

namespace fleet::sim {

namespace {

std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

using site::readPoint;

bool readArea(Config& c, const std::string& key, const nlohmann::json& j, Area& out) {
  bool ok = j.is_array() && j.size() == 4;
  if (ok) {
    for (const auto& e : j) {
      ok = ok && e.is_number();
    }
  }
  if (!ok || j[0].get<double>() >= j[2].get<double>() || j[1].get<double>() >= j[3].get<double>()) {
    c.problem(key, "expected [x0, y0, x1, y1] with x0 < x1 and y0 < y1, got " + j.dump());
    return false;
  }
  out = {{j[0].get<double>(), j[1].get<double>()}, {j[2].get<double>(), j[3].get<double>()}};
  return true;
}

void readSensors(Config c, SensorSpec& s) {
  c.rejectUnknownKeys({"rays", "fov", "range_max", "rate_hz", "range_sigma", "compass", "compass_sigma",
                       "landmarks", "landmark_range", "bearing_sigma", "detections", "detection_range"});
  s.rays = static_cast<int>(c.integer("rays", s.rays, {0, 1024}));
  s.fov = c.number("fov", s.fov, {0.0, 2.0 * kPi});
  s.rangeMax = c.number("range_max", s.rangeMax, {0.0, 1000.0, true});
  s.rateHz = c.number("rate_hz", s.rateHz, {0.0, 1000.0, true});
  s.rangeSigma = c.number("range_sigma", s.rangeSigma, {0.0, 10.0});
  s.compass = c.boolean("compass", s.compass);
  s.compassSigma = c.number("compass_sigma", s.compassSigma, {0.0, kPi});
  s.landmarks = c.boolean("landmarks", s.landmarks);
  s.landmarkRange = c.number("landmark_range", s.landmarkRange, {0.0, 1000.0});
  s.bearingSigma = c.number("bearing_sigma", s.bearingSigma, {0.0, kPi});
  s.detections = c.boolean("detections", s.detections);
  s.detectionRange = c.number("detection_range", s.detectionRange, {0.0, 1000.0});
}

// Robot parameters over `r` (defaults or an override); every key optional.
void readRobotParams(Config& c, RobotSpec& r) {
  r.radius = c.number("radius", r.radius, {0.0, 10.0, true});
  r.wheelBase = c.number("wheel_base", r.wheelBase, {0.0, 10.0, true});
  r.commandTimeout = c.number("command_timeout_s", r.commandTimeout, {0.0, 3600.0, true});
  if (c.has("limits")) {
    Config l = c.child("limits");
    site::readLimits(l, r.limits);
  }
  if (c.has("sensors")) {
    readSensors(c.child("sensors"), r.sensors);
  }
  if (c.has("noise")) {
    Config n = c.child("noise");
    n.rejectUnknownKeys({"slip_sigma", "odom_sigma"});
    r.noise.slipSigma = n.number("slip_sigma", r.noise.slipSigma, {0.0, 1.0});
    r.noise.odomSigma = n.number("odom_sigma", r.noise.odomSigma, {0.0, 1.0});
  }
  if (c.has("battery")) {
    Config b = c.child("battery");
    b.rejectUnknownKeys({"initial", "drain_idle_per_s", "drain_per_m", "charge_per_s"});
    r.battery.initial = b.number("initial", r.battery.initial, {0.0, 1.0});
    r.battery.drainIdlePerS = b.number("drain_idle_per_s", r.battery.drainIdlePerS, {0.0, 1.0});
    r.battery.drainPerM = b.number("drain_per_m", r.battery.drainPerM, {0.0, 1.0});
    r.battery.chargePerS = b.number("charge_per_s", r.battery.chargePerS, {0.0, 1.0});
  }
}

const std::vector<std::string> kRobotParamKeys = {
    "radius", "wheel_base", "command_timeout_s", "limits", "sensors", "noise", "battery"};

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// 4-connected free-cell components; label 0 = blocked.
std::vector<int> components(const GridMap& m) {
  std::vector<int> label(m.cells.size(), 0);
  int next = 0;
  std::deque<int> q;
  for (std::size_t i = 0; i < m.cells.size(); ++i) {
    if (m.cells[i] != 0 || label[i] != 0) {
      continue;
    }
    label[i] = ++next;
    q.push_back(static_cast<int>(i));
    while (!q.empty()) {
      const int c = q.front();
      q.pop_front();
      const int cx = c % m.width;
      const int cy = c / m.width;
      for (const auto& [dx, dy] : {std::pair{1, 0}, std::pair{-1, 0}, std::pair{0, 1}, std::pair{0, -1}}) {
        if (!m.blocked(cx + dx, cy + dy)) {
          const int n = (cy + dy) * m.width + cx + dx;
          if (label[static_cast<std::size_t>(n)] == 0) {
            label[static_cast<std::size_t>(n)] = next;
            q.push_back(n);
          }
        }
      }
    }
  }
  return label;
}

}  // namespace

Scenario parseScenario(const nlohmann::json& doc, const std::string& origin, const std::string& baseDir) {
  Config c = Config::fromJson(doc, origin);
  Scenario s;
  s.origin = origin;
  // "tasks" is `fleetctl loadtest`'s task list (checked there); the simulator ignores it.
  c.rejectUnknownKeys({"name", "seed", "duration_s", "dt", "clock", "near_miss_m", "site", "map", "stations",
                       "points_of_interest", "landmarks", "robot_defaults", "robots", "robot_fleet", "humans",
                       "social_force", "prediction", "tasks"});
  s.name = c.string("name", "scenario");
  s.seed = static_cast<std::uint64_t>(c.integer("seed", 1, {0.0, 9.0e15}));
  s.durationS = c.number("duration_s", s.durationS, {0.0, 1e7, true});
  s.dt = c.number("dt", s.dt, {0.0, 10.0, true});
  s.clock = c.string("clock", s.clock, {"wall", "lockstep"});
  s.nearMiss = c.number("near_miss_m", s.nearMiss, {0.0, 100.0});
  RobotSpec defaults;
  std::map<std::string, std::size_t> stationIndex;
  if (c.has("site")) {
    for (const char* k : {"map", "stations", "landmarks"}) {
      if (c.has(k)) {
        c.problem(k, "comes from the site file named by 'site'; remove it here");
      }
    }
    const std::filesystem::path sp(c.string("site", ""));
    const auto path = sp.is_relative() ? std::filesystem::path(baseDir) / sp : sp;
    try {
      auto st = std::make_shared<site::Site>(site::loadSite(path.string()));
      s.sitePath = std::filesystem::absolute(path).lexically_normal().string();
      s.map = fromOccupancyGrid(st->map);
      for (const auto& x : st->stations) {
        stationIndex[x.name] = s.stations.size();
        s.stations.push_back({x.name, x.kind, x.pose});
      }
      for (const auto& l : st->landmarks) {
        s.landmarks.push_back({l.id, l.position});
      }
      defaults.radius = st->robot.radius;
      defaults.wheelBase = st->robot.wheelBase;
      defaults.limits = st->robot.limits;
      const auto& d = st->robot.sensors;
      defaults.sensors.rays = d.rays;
      defaults.sensors.fov = d.fov;
      defaults.sensors.rangeMax = d.rangeMax;
      defaults.sensors.rateHz = d.rateHz;
      defaults.sensors.compass = d.compass;
      defaults.sensors.landmarks = d.landmarks;
      defaults.sensors.landmarkRange = d.landmarkRange;
      defaults.sensors.detectionRange = d.detectionRange;
      s.site = std::move(st);
    } catch (const ConfigError& e) {
      for (const auto& p : e.problems()) {
        c.problem("site", p);
      }
    }
  } else {
    s.map = fromOccupancyGrid(site::readMapSection(c.child("map", true), baseDir));
  }
  const bool haveMap = s.map.width > 0;

  for (auto& st : c.array("stations")) {
    st.rejectUnknownKeys({"name", "kind", "pose"});
    Station x;
    x.name = st.requireString("name");
    x.kind =
        site::stationKindFromString(st.requireString("kind", {"pickup", "dropoff", "charging", "parking"}))
            .value_or(StationKind::Pickup);
    Vec2 p;
    double th = 0;
    if (readPoint(st, "pose", p, true, &th)) {
      x.pose = {p.x, p.y, th};
      if (haveMap && s.map.blocked(s.map.cellX(p.x), s.map.cellY(p.y))) {
        st.problem("pose",
                   "station '" + x.name + "' at (" + fmt(p.x) + ", " + fmt(p.y) + ") is inside a wall/shelf");
      }
    }
    if (!x.name.empty() && stationIndex.count(x.name)) {
      st.problem("name", "duplicate station name '" + x.name + "'");
    }
    stationIndex[x.name] = s.stations.size();
    s.stations.push_back(x);
  }
  // A place given as [x, y] or a station name.
  auto readPlace = [&](Config& cc, const std::string& key, const nlohmann::json& j, Vec2& out) {
    if (j.is_string()) {
      auto it = stationIndex.find(j.get<std::string>());
      if (it == stationIndex.end()) {
        cc.problem(key, "unknown station '" + j.get<std::string>() + "'");
        return false;
      }
      out = s.stations[it->second].pose.position();
      return true;
    }
    if (j.is_array() && j.size() == 2 && j[0].is_number() && j[1].is_number()) {
      out = {j[0].get<double>(), j[1].get<double>()};
      return true;
    }
    cc.problem(key, "expected a station name or [x, y], got " + j.dump());
    return false;
  };

  if (const auto* pois = c.find("points_of_interest")) {
    if (!pois->is_array()) {
      c.problem("points_of_interest", "expected an array of [x, y] or station names");
    } else {
      for (std::size_t i = 0; i < pois->size(); ++i) {
        Vec2 p;
        if (readPlace(c, "points_of_interest[" + std::to_string(i) + "]", (*pois)[i], p)) {
          s.pointsOfInterest.push_back(p);
        }
      }
    }
  }
  for (auto& lm : c.array("landmarks")) {
    lm.rejectUnknownKeys({"id", "position"});
    Landmark l;
    l.id = static_cast<std::int32_t>(lm.requireInteger("id", {0, 2.0e9}));
    readPoint(lm, "position", l.position, true);
    s.landmarks.push_back(l);
  }

  if (c.has("robot_defaults")) {
    Config d = c.child("robot_defaults");
    d.rejectUnknownKeys(kRobotParamKeys);
    readRobotParams(d, defaults);
  }
  std::map<std::string, std::size_t> robotIndex;
  std::vector<std::string> robotKeys;  // config key of each robot, for messages
  for (auto& rc : c.array("robots")) {
    rc.rejectUnknownKeys(with(kRobotParamKeys, {"id", "start", "start_station"}));
    RobotSpec r = defaults;
    r.id = rc.requireString("id");
    if (!r.id.empty() && !isValidId(r.id)) {
      rc.problem("id", "'" + r.id + "' is not a valid id (letters, digits, '-', '_', '.')");
    }
    if (rc.has("start_station")) {
      const std::string st = rc.string("start_station", "");
      auto it = stationIndex.find(st);
      if (it == stationIndex.end()) {
        rc.problem("start_station", "unknown station '" + st + "'");
      } else {
        r.start = s.stations[it->second].pose;
      }
    } else {
      Vec2 p;
      double th = 0;
      if (readPoint(rc, "start", p, true, &th)) {
        r.start = {p.x, p.y, th};
      }
    }
    readRobotParams(rc, r);
    if (robotIndex.count(r.id)) {
      rc.problem("id", "duplicate robot id '" + r.id + "'");
    }
    robotIndex[r.id] = s.robots.size();
    robotKeys.push_back(rc.keyPath(""));
    s.robots.push_back(r);
  }
  if (c.has("robot_fleet")) {
    Config f = c.child("robot_fleet");
    f.rejectUnknownKeys({"count", "prefix", "area", "spacing", "heading"});
    const int count = static_cast<int>(f.requireInteger("count", {0, 100000}));
    const std::string prefix = f.string("prefix", "robot-");
    const double spacing = f.number("spacing", 2.5 * defaults.radius, {0.0, 100.0, true});
    const double heading = f.number("heading", 0.0);
    Area a{{0, 0}, {s.map.widthM(), s.map.heightM()}};
    if (const auto* aj = f.find("area")) {
      readArea(f, "area", *aj, a);
    }
    // Lattice of free spots in the area, row by row; spots whose disc touches a shelf are skipped.
    int placed = 0;
    if (haveMap) {
      for (double y = a.lo.y + spacing / 2; y <= a.hi.y - spacing / 2 + 1e-9 && placed < count;
           y += spacing) {
        for (double x = a.lo.x + spacing / 2; x <= a.hi.x - spacing / 2 + 1e-9 && placed < count;
             x += spacing) {
          if (discGridPenetration(s.map, {x, y}, defaults.radius + 0.05) > 0.0) {
            continue;
          }
          RobotSpec r = defaults;
          r.id = prefix + std::to_string(placed + 1);
          r.start = {x, y, wrapAngle(heading)};
          robotIndex[r.id] = s.robots.size();
          robotKeys.push_back(f.keyPath("") + "#" + std::to_string(placed + 1));
          s.robots.push_back(r);
          ++placed;
        }
      }
      if (placed < count) {
        f.problem("count", "only " + std::to_string(placed) + " of " + std::to_string(count) +
                               " robots fit in the free part of the area at spacing " + fmt(spacing) + " m");
      }
    }
  }

  if (c.has("humans")) {
    Config h = c.child("humans");
    h.rejectUnknownKeys({"count", "spawn_areas", "speed_mean", "speed_sd", "stop_probability", "stop_s",
                         "group_size", "radius", "list"});
    CrowdSpec& cr = s.crowd;
    cr.count = static_cast<int>(h.integer("count", 0, {0, 1000000}));
    cr.speedMean = h.number("speed_mean", cr.speedMean, {0.0, 5.0, true});
    cr.speedSd = h.number("speed_sd", cr.speedSd, {0.0, 5.0});
    cr.stopProbability = h.number("stop_probability", cr.stopProbability, {0.0, 1.0});
    cr.groupSize = static_cast<int>(h.integer("group_size", cr.groupSize, {1, 20}));
    cr.radius = h.number("radius", cr.radius, {0.0, 2.0, true});
    if (const auto* st = h.find("stop_s")) {
      if (!st->is_array() || st->size() != 2 || !(*st)[0].is_number() || !(*st)[1].is_number() ||
          (*st)[0].get<double>() < 0 || (*st)[0].get<double>() > (*st)[1].get<double>()) {
        h.problem("stop_s", "expected [min, max] seconds with 0 <= min <= max, got " + st->dump());
      } else {
        cr.stopMinS = (*st)[0].get<double>();
        cr.stopMaxS = (*st)[1].get<double>();
      }
    }
    if (const auto* areas = h.find("spawn_areas")) {
      if (!areas->is_array()) {
        h.problem("spawn_areas", "expected an array of [x0, y0, x1, y1]");
      } else {
        for (std::size_t i = 0; i < areas->size(); ++i) {
          Area a;
          if (readArea(h, "spawn_areas[" + std::to_string(i) + "]", (*areas)[i], a)) {
            cr.spawnAreas.push_back(a);
          }
        }
      }
    }
    for (auto& hc : h.array("list")) {
      hc.rejectUnknownKeys({"id", "start", "route", "speed"});
      HumanSpec hs;
      hs.id = hc.requireString("id");
      hs.speed = hc.number("speed", cr.speedMean, {0.0, 5.0, true});
      if (const auto* sj = hc.find("start")) {
        readPlace(hc, "start", *sj, hs.start);
      } else {
        hc.problem("start", "missing; expected a station name or [x, y]");
      }
      if (const auto* rj = hc.find("route")) {
        if (!rj->is_array()) {
          hc.problem("route", "expected an array of station names or [x, y]");
        } else {
          for (std::size_t i = 0; i < rj->size(); ++i) {
            Vec2 p;
            if (readPlace(hc, "route[" + std::to_string(i) + "]", (*rj)[i], p)) {
              hs.route.push_back(p);
            }
          }
        }
      }
      if (haveMap && s.map.blocked(s.map.cellX(hs.start.x), s.map.cellY(hs.start.y))) {
        hc.problem("start", "human '" + hs.id + "' starts inside a wall/shelf");
      }
      s.humans.push_back(hs);
    }
  }
  if (c.has("social_force")) {
    Config f = c.child("social_force");
    f.rejectUnknownKeys({"tau", "human_a", "human_b", "wall_a", "wall_b", "robot_a", "robot_b", "lambda",
                         "cutoff", "max_speed_factor", "robot_keep"});
    auto& p = s.social;
    p.tau = f.number("tau", p.tau, {0.0, 10.0, true});
    p.humanA = f.number("human_a", p.humanA, {0.0, 1000.0});
    p.humanB = f.number("human_b", p.humanB, {0.0, 10.0, true});
    p.wallA = f.number("wall_a", p.wallA, {0.0, 1000.0});
    p.wallB = f.number("wall_b", p.wallB, {0.0, 10.0, true});
    p.robotA = f.number("robot_a", p.robotA, {0.0, 1000.0});
    p.robotB = f.number("robot_b", p.robotB, {0.0, 10.0, true});
    p.lambda = f.number("lambda", p.lambda, {0.0, 1.0});
    p.cutoff = f.number("cutoff", p.cutoff, {0.0, 100.0, true});
    p.maxSpeedFactor = f.number("max_speed_factor", p.maxSpeedFactor, {1.0, 10.0});
    p.robotKeep = f.number("robot_keep", p.robotKeep, {-1.0, 1.0});
  }
  if (c.has("prediction")) {
    Config f = c.child("prediction");
    f.rejectUnknownKeys({"horizon_s", "dt", "sigma0", "sigma_rate"});
    s.predictionHorizonS = f.number("horizon_s", s.predictionHorizonS, {0.0, 60.0, true});
    s.predictionDt = f.number("dt", s.predictionDt, {0.0, 60.0, true});
    s.predictionSigma0 = f.number("sigma0", s.predictionSigma0, {0.0, 100.0});
    s.predictionSigmaRate = f.number("sigma_rate", s.predictionSigmaRate, {0.0, 100.0});
    if (s.predictionHorizonS / s.predictionDt > 63.0) {
      f.problem("horizon_s", "horizon_s / dt must give at most 64 discs");
    }
  }

  // Checks across entries: walls, overlaps, reachability.
  if (haveMap) {
    for (std::size_t i = 0; i < s.robots.size(); ++i) {
      const auto& r = s.robots[i];
      const double pen = discGridPenetration(s.map, r.start.position(), r.radius);
      if (pen > 1e-9) {
        c.problem("", robotKeys[i] + ": robot '" + r.id + "' at (" + fmt(r.start.x) + ", " + fmt(r.start.y) +
                          ") is inside a wall/shelf (overlap " + fmt(pen) + " m)");
      }
    }
    for (std::size_t i = 0; i < s.robots.size(); ++i) {
      for (std::size_t j = i + 1; j < s.robots.size(); ++j) {
        const double d = distance(s.robots[i].start, s.robots[j].start);
        if (d < s.robots[i].radius + s.robots[j].radius) {
          c.problem("", robotKeys[j] + ": robot '" + s.robots[j].id + "' overlaps robot '" + s.robots[i].id +
                            "' at its start (centres " + fmt(d) + " m apart, radii sum " +
                            fmt(s.robots[i].radius + s.robots[j].radius) + " m)");
        }
      }
    }
    if (!s.robots.empty()) {
      const auto label = components(s.map);
      auto labelAt = [&](Vec2 p) {
        const int cx = s.map.cellX(p.x);
        const int cy = s.map.cellY(p.y);
        return s.map.blocked(cx, cy)
                   ? 0
                   : label[static_cast<std::size_t>(cy) * static_cast<std::size_t>(s.map.width) +
                           static_cast<std::size_t>(cx)];
      };
      const int home = labelAt(s.robots[0].start.position());
      if (home != 0) {
        for (std::size_t i = 1; i < s.robots.size(); ++i) {
          const int l = labelAt(s.robots[i].start.position());
          if (l != 0 && l != home) {
            c.problem("", robotKeys[i] + ": robot '" + s.robots[i].id +
                              "' starts in an area unreachable from robot '" + s.robots[0].id + "'");
          }
        }
        for (const auto& st : s.stations) {
          const int l = labelAt(st.pose.position());
          if (l != 0 && l != home) {
            c.problem("stations",
                      "station '" + st.name + "' is unreachable from robot '" + s.robots[0].id + "'");
          }
        }
      }
    }
  }
  c.finish();
  if (!s.site) {
    auto st = std::make_shared<site::Site>();
    st->name = s.name;
    st->origin = origin;
    st->map = planning::OccupancyGrid(s.map.width, s.map.height, s.map.resolution, s.map.origin);
    for (std::size_t i = 0; i < s.map.cells.size(); ++i) {
      if (s.map.cells[i] != 0) {
        st->map.setBlocked(st->map.cellOf(i));
      }
    }
    for (const auto& x : s.stations) {
      st->stations.push_back({x.name, x.kind, x.pose, std::nullopt, false, {}, std::nullopt});
    }
    for (const auto& l : s.landmarks) {
      st->landmarks.push_back({l.id, l.position});
    }
    st->robot.radius = defaults.radius;
    st->robot.wheelBase = defaults.wheelBase;
    st->robot.limits = defaults.limits;
    site::completeSite(*st);
    s.site = std::move(st);
  }
  return s;
}

Scenario loadScenario(const std::string& path) {
  Config file = Config::fromFile(path);  // throws on unreadable / bad JSON
  const std::string base = std::filesystem::path(path).parent_path().string();
  return parseScenario(file.json(), path, base.empty() ? "." : base);
}

}  // namespace fleet::sim
