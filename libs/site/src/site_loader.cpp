#include "fleet/site/site_loader.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <sstream>

#include "fleet/core/angles.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/geometry/polygon.hpp"
#include "fleet/planning/map_io.hpp"
#include "fleet/planning/map_limits.hpp"
#include "fleet/site/reachability.hpp"
#include "fleet/site/ros_map.hpp"

namespace fleet::site {

namespace {

std::string fmt(double v) {
  std::ostringstream os;
  os << v;
  return os.str();
}

std::string at(Vec2 p) {
  return "(" + fmt(p.x) + ", " + fmt(p.y) + ")";
}

std::string resolve(const std::string& baseDir, const std::string& f) {
  const std::filesystem::path p(f);
  return (p.is_relative() ? std::filesystem::path(baseDir) / p : p).string();
}

bool insideMap(const planning::OccupancyGrid& g, Vec2 p) {
  const Vec2 lo = g.origin();
  const Vec2 hi = lo + Vec2{g.width() * g.resolution(), g.height() * g.resolution()};
  return p.x >= lo.x && p.y >= lo.y && p.x <= hi.x && p.y <= hi.y;
}

std::string mapExtent(const planning::OccupancyGrid& g) {
  const Vec2 lo = g.origin();
  const Vec2 hi = lo + Vec2{g.width() * g.resolution(), g.height() * g.resolution()};
  return "x " + fmt(lo.x) + ".." + fmt(hi.x) + ", y " + fmt(lo.y) + ".." + fmt(hi.y) + " m";
}

double signedArea(const std::vector<Vec2>& poly) {
  double a = 0.0;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    a += poly[j].cross(poly[i]);
  }
  return 0.5 * a;
}

std::vector<std::size_t> polygonCells(const planning::OccupancyGrid& g, const std::vector<Vec2>& poly) {
  std::vector<std::size_t> out;
  if (poly.size() < 3) {
    return out;
  }
  for (int y = 0; y < g.height(); ++y) {
    for (int x = 0; x < g.width(); ++x) {
      if (geometry::insidePolygon(g.cellCenter({x, y}), poly)) {
        out.push_back(g.index({x, y}));
      }
    }
  }
  return out;
}

void readStations(Config& c, Site& s) {
  std::map<std::string, int> seen;
  for (auto& st : c.array("stations")) {
    st.rejectUnknownKeys({"name", "kind", "pose", "approach", "queue", "exit"});
    Station x;
    x.name = st.requireString("name");
    if (!x.name.empty() && !isValidId(x.name)) {
      st.problem("name", "'" + x.name + "' is not a valid station name (1 to 63 of A-Z a-z 0-9 _ . : -)");
    }
    x.kind = stationKindFromString(st.requireString("kind", {"pickup", "dropoff", "charging", "parking"}))
                 .value_or(StationKind::Pickup);
    Vec2 p;
    double th = 0.0;
    if (readPoint(st, "pose", p, true, &th)) {
      x.pose = {p.x, p.y, th};
    }
    Vec2 a;
    if (readPoint(st, "approach", a, false)) {
      x.approach = a;
      x.approachGiven = true;
    }
    Vec2 out;
    if (const auto* e = st.find("exit"); e != nullptr && e->is_string()) {
      if (e->get<std::string>() == "entry") {
        x.exitByEntry = true;
      } else {
        st.problem("exit", "expected [x, y] in m or \"entry\" (left by its way in), got " + e->dump());
      }
    } else if (readPoint(st, "exit", out, false)) {
      x.exit = out;
    }
    if (const auto* q = st.find("queue")) {
      if (!q->is_array()) {
        st.problem("queue", "expected an array of [x, y], nearest to the station first");
      } else {
        for (std::size_t i = 0; i < q->size(); ++i) {
          // readPoint addresses keys of an object; the queue is an array, so check in place.
          const auto& e = (*q)[i];
          if (e.is_array() && e.size() == 2 && e[0].is_number() && e[1].is_number() &&
              std::isfinite(e[0].get<double>()) && std::isfinite(e[1].get<double>())) {
            x.queue.push_back({e[0].get<double>(), e[1].get<double>()});
          } else {
            st.problem("queue[" + std::to_string(i) + "]", "expected [x, y] in m, got " + e.dump());
          }
        }
      }
    }
    if (!x.name.empty() && seen.count(x.name) != 0) {
      st.problem("name", "duplicate station name '" + x.name + "' (first at stations[" +
                             std::to_string(seen[x.name]) + "])");
    }
    seen.emplace(x.name, static_cast<int>(s.stations.size()));
    s.stations.push_back(std::move(x));
  }
}

void readZones(Config& c, Site& s) {
  for (auto& zc : c.array("zones")) {
    zc.rejectUnknownKeys({"name", "kind", "polygon", "max_speed", "direction"});
    Zone z;
    z.name = zc.requireString("name");
    const std::string kind = zc.requireString("kind", {"no_go", "speed_limit", "one_way"});
    z.kind = kind == "speed_limit" ? ZoneKind::SpeedLimit
             : kind == "one_way"   ? ZoneKind::OneWay
                                   : ZoneKind::NoGo;
    if (z.kind == ZoneKind::SpeedLimit) {
      z.maxSpeed = zc.requireNumber("max_speed", {0.0, 20.0, true});
    } else if (zc.has("max_speed")) {
      zc.problem("max_speed", "only a speed_limit zone has a max_speed");
    }
    if (z.kind == ZoneKind::OneWay) {
      z.direction = wrapAngle(zc.requireNumber("direction", {-2.0 * kPi, 2.0 * kPi}));
    } else if (zc.has("direction")) {
      zc.problem("direction", "only a one_way zone has a direction");
    }
    const auto* pj = zc.find("polygon");
    if (pj == nullptr || !pj->is_array() || pj->size() < 3) {
      zc.problem("polygon", "expected an array of at least 3 points [x, y]");
    } else {
      for (std::size_t i = 0; i < pj->size(); ++i) {
        const auto& e = (*pj)[i];
        const std::string key = "polygon[" + std::to_string(i) + "]";
        if (!(e.is_array() && e.size() == 2 && e[0].is_number() && e[1].is_number() &&
              std::isfinite(e[0].get<double>()) && std::isfinite(e[1].get<double>()))) {
          zc.problem(key, "expected [x, y] in m, got " + e.dump());
          continue;
        }
        const Vec2 v{e[0].get<double>(), e[1].get<double>()};
        if (s.map.size() > 0 && !insideMap(s.map, v)) {
          zc.problem(key, "corner " + at(v) + " lies outside the map (" + mapExtent(s.map) + ")");
        }
        z.polygon.push_back(v);
      }
      if (z.polygon.size() == pj->size() && std::abs(signedArea(z.polygon)) < 1e-9) {
        zc.problem("polygon", "has no area");
      }
    }
    s.zones.push_back(std::move(z));
  }
}

void readMasks(Config& c, const std::string& baseDir, Site& s) {
  for (auto& mc : c.array("masks")) {
    mc.rejectUnknownKeys({"name", "kind", "map", "type", "base", "multiplier"});
    Zone z;
    z.name = mc.requireString("name");
    const std::string kind = mc.requireString("kind", {"keepout", "speed"});
    const std::string file = mc.requireString("map");
    const std::string type = mc.string("type", "percent", {"percent", "absolute"});
    const double base = mc.number("base", 0.0, {-1000.0, 1000.0});
    const double mult = mc.number("multiplier", 1.0, {-1000.0, 1000.0});
    if (kind == "keepout") {
      for (const char* k : {"type", "base", "multiplier"}) {
        if (mc.has(k)) {
          mc.problem(k, "only a speed mask has a " + std::string(k));
        }
      }
    }
    if (file.empty() || s.map.size() == 0) {
      continue;
    }
    const auto mask = loadRosMap(resolve(baseDir, file));
    if (!mask) {
      mc.problem("map", mask.error().message);
      continue;
    }
    if (kind == "keepout") {
      z.kind = ZoneKind::NoGo;
      z.cells = keepoutCells(*mask, s.map);
      s.zones.push_back(std::move(z));
      continue;
    }
    // A speed mask has many levels; each becomes its own zone so a zone keeps one max_speed.
    std::map<double, Zone> byLimit;
    for (const auto& sc :
         speedCells(*mask, s.map, type == "absolute" ? SpeedMaskType::Absolute : SpeedMaskType::Percent, base,
                    mult, s.robot.limits.vMax)) {
      auto& lz = byLimit[sc.limit];
      lz.cells.push_back(sc.cell);
    }
    for (auto& [limit, lz] : byLimit) {
      lz.name = z.name + "@" + fmt(limit);
      lz.kind = ZoneKind::SpeedLimit;
      lz.maxSpeed = limit;
      s.zones.push_back(std::move(lz));
    }
  }
}

}  // namespace

bool readPoint(Config& c, const std::string& key, Vec2& out, bool required, double* theta) {
  const nlohmann::json* j = c.find(key);
  if (j == nullptr) {
    if (required) {
      c.problem(key, theta ? "missing; expected [x, y, theta]" : "missing; expected [x, y]");
    }
    return false;
  }
  const std::size_t want = theta ? 3 : 2;
  const bool shapeOk = j->is_array() && (j->size() == want || (theta && j->size() == 2));
  bool numbers = shapeOk;
  if (shapeOk) {
    for (const auto& e : *j) {
      numbers = numbers && e.is_number() && std::isfinite(e.get<double>());
    }
  }
  if (!numbers) {
    c.problem(key, std::string(theta ? "expected [x, y] or [x, y, theta] in m/rad" : "expected [x, y] in m") +
                       ", got " + j->dump());
    return false;
  }
  out = {(*j)[0].get<double>(), (*j)[1].get<double>()};
  if (theta) {
    *theta = j->size() == 3 ? wrapAngle((*j)[2].get<double>()) : 0.0;
  }
  return true;
}

void readLimits(Config& l, control::VelocityLimits& v) {
  l.rejectUnknownKeys({"v_max", "v_min", "w_max", "accel_max", "alpha_max"});
  v.vMax = l.number("v_max", v.vMax, {0.0, 20.0});
  v.vMin = l.number("v_min", v.vMin, {-20.0, 0.0});
  v.omegaMax = l.number("w_max", v.omegaMax, {0.0, 20.0});
  v.accelMax = l.number("accel_max", v.accelMax, {0.0, 100.0, true});
  v.alphaMax = l.number("alpha_max", v.alphaMax, {0.0, 100.0, true});
}

void readRobotDescription(Config& c, RobotDescription& r) {
  r.radius = c.number("radius", r.radius, {0.0, 10.0, true});
  r.wheelBase = c.number("wheel_base", r.wheelBase, {0.0, 10.0, true});
  if (c.has("limits")) {
    Config l = c.child("limits");
    readLimits(l, r.limits);
  }
  if (c.has("sensors")) {
    Config s = c.child("sensors");
    s.rejectUnknownKeys(
        {"rays", "fov", "range_max", "rate_hz", "compass", "landmarks", "landmark_range", "detection_range"});
    auto& d = r.sensors;
    d.rays = static_cast<int>(s.integer("rays", d.rays, {0, 1024}));
    d.fov = s.number("fov", d.fov, {0.0, 2.0 * kPi});
    d.rangeMax = s.number("range_max", d.rangeMax, {0.0, 1000.0, true});
    d.rateHz = s.number("rate_hz", d.rateHz, {0.0, 1000.0, true});
    d.compass = s.boolean("compass", d.compass);
    d.landmarks = s.boolean("landmarks", d.landmarks);
    d.landmarkRange = s.number("landmark_range", d.landmarkRange, {0.0, 1000.0});
    d.detectionRange = s.number("detection_range", d.detectionRange, {0.0, 1000.0});
  }
}

planning::OccupancyGrid readMapSection(Config c, const std::string& baseDir) {
  c.rejectUnknownKeys(
      {"file", "ros", "image", "warehouse", "rows", "resolution", "origin", "width", "height"});
  const double res = c.number("resolution", 0.5, {0.0, 100.0, true});
  Vec2 origin;
  readPoint(c, "origin", origin, false);
  const char* kinds[] = {"file", "ros", "image", "warehouse", "rows"};
  const auto sources =
      std::count_if(std::begin(kinds), std::end(kinds), [&](const char* k) { return c.has(k); });
  if (sources != 1) {
    c.problem("",
              "expected exactly one of 'file' (MovingAI .map), 'ros' (ROS map YAML + PGM/PNG image), 'image' "
              "(JSON side file of a PGM map), 'warehouse' (generated) or 'rows'");
    return {};
  }
  const bool frameFromFile = c.has("ros") || c.has("image");
  if (frameFromFile) {
    for (const char* k : {"resolution", "origin"}) {
      if (c.has(k)) {
        c.problem(k, "comes from the map's side file; remove it here");
      }
    }
  }
  Expected<planning::OccupancyGrid> grid = planning::OccupancyGrid{};
  std::string key;
  if (c.has("file")) {
    key = "file";
    grid = planning::loadMovingAiMap(resolve(baseDir, c.string("file", "")), res, origin);
  } else if (c.has("ros")) {
    key = "ros";
    const auto m = loadRosMap(resolve(baseDir, c.string("ros", "")));
    if (m) {
      grid = toOccupancyGrid(*m);
    } else {
      grid = unexpected(m.error());
    }
  } else if (c.has("image")) {
    key = "image";
    grid = planning::loadImageMap(resolve(baseDir, c.string("image", "")));
  } else if (c.has("warehouse")) {
    key = "warehouse";
    Config w = c.child("warehouse");
    w.rejectUnknownKeys({"width", "height", "margin", "shelf_width", "shelf_height", "aisle_x", "aisle_y"});
    planning::WarehouseParams l;
    l.resolution = res;
    l.origin = origin;
    l.width = static_cast<int>(w.integer("width", 60, {3, 10000}));
    l.height = static_cast<int>(w.integer("height", 40, {3, 10000}));
    l.margin = static_cast<int>(w.integer("margin", 4, {1, 10000}));
    l.shelfWidth = static_cast<int>(w.integer("shelf_width", 8, {1, 10000}));
    l.shelfHeight = static_cast<int>(w.integer("shelf_height", 2, {1, 10000}));
    l.aisleX = static_cast<int>(w.integer("aisle_x", 3, {1, 10000}));
    l.aisleY = static_cast<int>(w.integer("aisle_y", 3, {1, 10000}));
    if (auto ok = planning::checkMapSize(l.width, l.height, res, origin, "", "width x height"); !ok) {
      grid = unexpected(ok.error());
    } else {
      grid = planning::makeWarehouseGrid(l);
    }
  } else {
    key = "rows";
    const nlohmann::json* rows = c.find("rows");
    bool ok = rows->is_array() && !rows->empty();
    std::size_t w = 0;
    if (ok) {
      w = (*rows)[0].is_string() ? (*rows)[0].get<std::string>().size() : 0;
      for (const auto& r : *rows) {
        ok = ok && r.is_string() && r.get<std::string>().size() == w;
      }
    }
    if (!ok || w == 0) {
      c.problem("rows",
                "expected a non-empty array of equally long strings ('.' free, '@' blocked; first = top)");
      return {};
    }
    std::string text =
        "type octile\nheight " + std::to_string(rows->size()) + "\nwidth " + std::to_string(w) + "\nmap\n";
    for (const auto& r : *rows) {
      text += r.get<std::string>() + "\n";
    }
    grid = planning::parseMovingAiMap(text, c.keyPath("rows"), res, origin);
  }
  if (!grid) {
    c.problem(key, grid.error().message);
    return {};
  }
  const auto w = c.integer("width", grid->width(), {1, 1e6});
  const auto h = c.integer("height", grid->height(), {1, 1e6});
  if (w != grid->width() || h != grid->height()) {
    c.problem(key, "the map is " + std::to_string(grid->width()) + " x " + std::to_string(grid->height()) +
                       " cells, the site declares " + std::to_string(w) + " x " + std::to_string(h));
  }
  return std::move(grid).value();
}

void completeSite(Site& s) {
  const std::size_t n = s.map.size();
  s.layers.noGo.assign(n, 0);
  s.layers.speedLimit.assign(n, std::numeric_limits<float>::infinity());
  s.layers.oneWay.assign(n, std::numeric_limits<float>::quiet_NaN());
  for (const auto& z : s.zones) {
    const auto cells = z.polygon.empty() ? z.cells : polygonCells(s.map, z.polygon);
    for (const auto i : cells) {
      if (i >= n) {
        continue;
      }
      switch (z.kind) {
        case ZoneKind::NoGo:
          s.layers.noGo[i] = 1;
          break;
        case ZoneKind::SpeedLimit:
          s.layers.speedLimit[i] = std::min(s.layers.speedLimit[i], static_cast<float>(z.maxSpeed));
          break;
        case ZoneKind::OneWay:
          s.layers.oneWay[i] = static_cast<float>(z.direction);
          break;
      }
    }
  }
  const auto drivable = s.drivable();
  for (auto& st : s.stations) {
    if (st.approachGiven) {
      continue;
    }
    const Vec2 a = st.pose.position() + st.pose.heading() * kDefaultApproachDistance;
    st.approach = n > 0 && segmentFits(drivable, st.pose.position(), a, s.robot.radius) ? std::optional(a)
                                                                                        : std::nullopt;
    if (st.approach && !discFits(drivable, a, s.robot.radius + kApproachClearance)) {
      for (double d = kDefaultApproachDistance - 0.05; d >= kMinApproachDistance - 1e-9; d -= 0.05) {
        const Vec2 nearer = st.pose.position() + st.pose.heading() * d;
        if (discFits(drivable, nearer, s.robot.radius + kApproachClearance)) {
          st.approach = nearer;
          break;
        }
      }
    }
  }
}

std::vector<SiteProblem> checkSite(const Site& s) {
  std::vector<SiteProblem> out;
  if (s.map.size() == 0) {
    return out;
  }
  const auto g = s.drivable();
  const double r = s.robot.radius;
  const auto regions = discRegions(g, r);
  std::vector<std::int32_t> regionOfStation(s.stations.size(), 0);
  std::vector<bool> placed(s.stations.size(), false);  // passed the checks above: in, free, fits
  for (std::size_t i = 0; i < s.stations.size(); ++i) {
    const auto& st = s.stations[i];
    const std::string key = "stations[" + std::to_string(i) + "]";
    const Vec2 p = st.pose.position();
    const auto c = s.map.cellAt(p);
    if (!c) {
      out.push_back({key + ".pose", "station '" + st.name + "' at " + at(p) + " lies outside the map (" +
                                        mapExtent(s.map) + ")"});
      continue;
    }
    if (s.map.blocked(*c)) {
      out.push_back({key + ".pose", "station '" + st.name + "' at " + at(p) + " is inside an obstacle"});
      continue;
    }
    if (s.layers.noGo[s.map.index(*c)]) {
      out.push_back({key + ".pose", "station '" + st.name + "' at " + at(p) + " is inside a no-go zone"});
      continue;
    }
    if (!discFits(g, p, r)) {
      out.push_back({key + ".pose", "station '" + st.name + "' at " + at(p) + ": a robot of radius " +
                                        fmt(r) + " m does not fit there"});
      continue;
    }
    regionOfStation[i] = regionOf(g, regions, p, r);
    placed[i] = true;
    if (st.approachGiven && st.approach &&
        !(discFits(g, *st.approach, r) && segmentFits(g, *st.approach, p, r))) {
      out.push_back({key + ".approach", "station '" + st.name + "': a robot of radius " + fmt(r) +
                                            " m cannot drive straight from the approach " + at(*st.approach) +
                                            " to the station"});
    }
    if (st.exit && !(discFits(g, *st.exit, r) && segmentFits(g, p, *st.exit, r))) {
      out.push_back({key + ".exit", "station '" + st.name + "': a robot of radius " + fmt(r) +
                                        " m cannot drive straight from the station to its exit " +
                                        at(*st.exit)});
    }
    for (std::size_t q = 0; q < st.queue.size(); ++q) {
      if (st.exit && distance(st.queue[q], *st.exit) < 2.0 * r + 0.1) {
        out.push_back({key + ".exit", "station '" + st.name + "': its exit " + at(*st.exit) +
                                          " leads into its queue (queue point " + std::to_string(q) + " " +
                                          at(st.queue[q]) + " is within a robot's diameter)"});
      }
      if (!discFits(g, st.queue[q], r)) {
        out.push_back({key + ".queue[" + std::to_string(q) + "]",
                       "station '" + st.name + "': a robot of radius " + fmt(r) + " m does not fit at " +
                           at(st.queue[q])});
      }
    }
  }
  const std::int32_t main = floorRegion(regions, regionOfStation);
  const auto most =
      static_cast<std::size_t>(std::count(regionOfStation.begin(), regionOfStation.end(), main));
  for (std::size_t i = 0; i < s.stations.size(); ++i) {
    const auto& st = s.stations[i];
    if (!placed[i] || regionOfStation[i] == main) {
      continue;  // fine, or already reported
    }
    out.push_back({"stations[" + std::to_string(i) + "].pose",
                   "station '" + st.name + "' is unreachable for a robot of radius " + fmt(r) +
                       " m: no way for its disc to the region holding " + std::to_string(most) + " of " +
                       std::to_string(s.stations.size()) + " stations"});
  }
  return out;
}

Site parseSite(const nlohmann::json& doc, const std::string& origin, const std::string& baseDir,
               bool checkGeometry) {
  Config c = Config::fromJson(doc, origin);
  c.rejectUnknownKeys({"format", "name", "map", "robot", "stations", "landmarks", "zones", "masks"});
  Site s;
  s.origin = origin;
  c.requireString("format", {kSiteFormat});
  s.name = c.requireString("name");
  s.map = readMapSection(c.child("map", true), baseDir);
  if (c.has("robot")) {
    Config r = c.child("robot");
    r.rejectUnknownKeys({"radius", "wheel_base", "limits", "sensors"});
    readRobotDescription(r, s.robot);
  }
  readStations(c, s);
  std::map<std::int32_t, int> ids;
  for (auto& lm : c.array("landmarks")) {
    lm.rejectUnknownKeys({"id", "position"});
    Landmark l;
    l.id = static_cast<std::int32_t>(lm.requireInteger("id", {0, 2.0e9}));
    if (readPoint(lm, "position", l.position, true) && s.map.size() > 0 && !insideMap(s.map, l.position)) {
      lm.problem("position", "landmark " + std::to_string(l.id) + " at " + at(l.position) +
                                 " lies outside the map (" + mapExtent(s.map) + ")");
    }
    if (ids.count(l.id) != 0) {
      lm.problem("id", "duplicate landmark id " + std::to_string(l.id));
    }
    ids.emplace(l.id, 0);
    s.landmarks.push_back(l);
  }
  readZones(c, s);
  readMasks(c, baseDir, s);
  if (c.ok()) {
    // Geometry is checked only on a site that parsed: a typo should not hide behind "unreachable".
    completeSite(s);
    for (const auto& p : checkGeometry ? checkSite(s) : std::vector<SiteProblem>{}) {
      c.problem(p.key, p.what);
    }
  }
  c.finish();
  return s;
}

Site loadSite(const std::string& path, bool checkGeometry) {
  Config file = Config::fromFile(path);
  const std::string base = std::filesystem::path(path).parent_path().string();
  return parseSite(file.json(), path, base.empty() ? "." : base, checkGeometry);
}

Site loadSiteOrMap(const std::string& path, double mapResolution, bool checkGeometry) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext != ".map" && ext != ".yaml" && ext != ".yml") {
    return loadSite(path, checkGeometry);
  }
  Site s;
  s.origin = path;
  s.name = std::filesystem::path(path).stem().string();
  if (ext == ".map") {
    auto g = planning::loadMovingAiMap(path, mapResolution);
    if (!g) {
      throw ConfigError({g.error().message});
    }
    s.map = std::move(g).value();
  } else {
    const auto m = loadRosMap(path);
    if (!m) {
      throw ConfigError({m.error().message});
    }
    s.map = toOccupancyGrid(*m);
  }
  completeSite(s);
  return s;
}

}  // namespace fleet::site
