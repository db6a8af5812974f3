// The JSON views of a robot, the robot time, the proximity figures, the risk map and the site
// picture that the dashboard and the API send.

#include "dashboard.hpp"

#include <cmath>
#include <fstream>
#include <string>

#include "fleet/fleet/site_stations.hpp"
#include "robot_time.hpp"

namespace fleet::wms {
namespace {

using nlohmann::json;

json kindsOf(const Station& s) {
  json k = json::array();
  for (auto kind : {StationKind::Pickup, StationKind::Dropoff, StationKind::Charging, StationKind::Parking}) {
    if (s.has(kind)) {
      k.push_back(std::string(toString(kind)));
    }
  }
  return k;
}
}  // namespace

json robotJson(const msg::RobotState& r, const msg::PeopleSeen* people) {
  // One number for how well the pose is known: the position's standard deviation (largest axis
  // bound by the trace). A huge one means the robot does not know where it is.
  const double var = r.covariance[0] + r.covariance[4];
  json seen = json::array();
  if (people != nullptr) {
    // To the centimetre: the page draws them, nobody steers by them.
    auto cm = [](float v) { return std::round(static_cast<double>(v) * 100.0) / 100.0; };
    for (const auto& p : people->people) {
      seen.push_back({{"x", cm(p.x)},
                      {"y", cm(p.y)},
                      {"vx", cm(p.vx)},
                      {"vy", cm(p.vy)},
                      {"radius", cm(p.r)},
                      {"velocity_known", p.velocity_known}});
    }
  }
  return {{"id", r.robot_id},
          {"pose", {{"x", r.pose.x}, {"y", r.pose.y}, {"theta", r.pose.theta}}},
          {"heading_deg", r.pose.theta * 180.0 / M_PI},
          {"v", r.v},
          {"w", r.w},
          {"mode", msg::toString(r.mode)},
          {"activity", toString(msg::activityOf(r))},
          {"fault", r.mode == msg::RobotMode::Fault},
          {"paused", r.paused},
          {"battery", r.battery},
          {"task", r.task_id},
          {"radius", r.radius},
          {"position_sigma", std::isfinite(var) && var >= 0 ? std::sqrt(var) : -1.0},
          {"stamp_ns", r.stamp_ns},
          {"people_seen", seen},
          {"people_seen_stamp_ns", people != nullptr ? json(people->stamp_ns) : json()}};
}

json robotTimeJson(const RobotTimeLedger& ledger) {
  auto shares = [](const ActivityLedger& l) {
    json seconds = json::object();
    json share = json::object();
    for (const auto a : kLedgerActivities) {
      seconds[toString(a)] = l.seconds(a);
      share[toString(a)] = l.share(a);
    }
    return json{{"seconds", l.total()}, {"by_activity_s", seconds}, {"shares", share}};
  };
  json robots = json::array();
  for (const auto& [id, l] : ledger.robots()) {
    json r = shares(l);
    r["id"] = id;
    robots.push_back(std::move(r));
  }
  return {{"fleet", shares(ledger.fleet())}, {"robots", robots}};
}

json proximityJson(const FleetView::Proximity& p) {
  auto counts = [](const ProximityCounts& c) {
    return json{{"contacts", c.contacts},
                {"near_misses", c.nearMisses},
                {"in_contact_now", c.inContact},
                {"close_now", c.close},
                {"min_clearance_m", std::isfinite(c.minClearance) ? json(c.minClearance) : json()}};
  };
  return {{"robot_robot", counts(p.robotRobot)},
          {"robot_person", counts(p.robotPerson)},
          {"near_miss_margin_m", p.params.nearMissMargin},
          {"hysteresis_m", p.params.hysteresis}};
}

json riskJson(const msg::RiskMap& m) {
  if (m.runs.size() > 500'000) {
    return nullptr;
  }
  std::vector<std::uint32_t> runs;
  runs.reserve(2 * m.runs.size());
  for (const auto& r : m.runs) {
    runs.push_back(r.level);
    runs.push_back(r.count);
  }
  return {{"stamp_ns", m.stamp_ns},
          {"origin", {m.origin_x, m.origin_y}},
          {"resolution", m.resolution},
          {"width", m.width},
          {"height", m.height},
          {"levels", m.levels},
          {"runs", runs}};
}

json sitePictureOf(const std::string& path) {
  auto loaded = fleet::loadSiteStations(path);
  if (!loaded) {
    return {{"error", loaded.error().message}};
  }
  json out = {{"name", loaded->site ? loaded->site->name : path}};
  json stations = json::array();
  for (const Station* s : loaded->stations.all()) {
    stations.push_back({{"name", s->name},
                        {"x", s->pose.x},
                        {"y", s->pose.y},
                        {"theta", s->pose.theta},
                        {"kinds", kindsOf(*s)}});
  }
  out["stations"] = stations;
  if (loaded->site) {
    const auto& g = loaded->site->map;
    json rows = json::array();
    for (int y = g.height() - 1; y >= 0; --y) {
      std::string row(static_cast<std::size_t>(g.width()), '.');
      for (int x = 0; x < g.width(); ++x) {
        if (g.blocked({x, y})) {
          row[static_cast<std::size_t>(x)] = '#';
        }
      }
      rows.push_back(std::move(row));
    }
    out["map"] = {{"width", g.width()},
                  {"height", g.height()},
                  {"resolution", g.resolution()},
                  {"origin", {g.origin().x, g.origin().y}},
                  {"rows", rows}};
  }
  // A scenario names each robot's parking place: where "send home" sends it.
  std::ifstream in(path);
  const json doc = json::parse(in, nullptr, false);
  json homes = json::object();
  if (doc.is_object() && doc.contains("robots") && doc["robots"].is_array()) {
    for (const auto& r : doc["robots"]) {
      if (r.is_object() && r.value("id", json()).is_string() &&
          r.value("start_station", json()).is_string()) {
        homes[r["id"].get<std::string>()] = r["start_station"];
      }
    }
  }
  out["homes"] = homes;
  return out;
}

}  // namespace fleet::wms
