#include "fleet/site/site_report.hpp"

#include <algorithm>
#include <sstream>

#include "fleet/site/reachability.hpp"

namespace fleet::site {

SiteReport analyseSite(const Site& site, double radius) {
  SiteReport r;
  Site s = site;
  if (radius > 0.0) {
    s.robot.radius = radius;
  }
  r.name = s.name;
  r.width = s.map.width();
  r.height = s.map.height();
  r.resolution = s.map.resolution();
  r.origin = s.map.origin();
  r.freeCells = s.map.freeCount();
  r.radius = s.robot.radius;
  r.landmarks = s.landmarks.size();
  r.zones = s.zones.size();
  for (std::size_t i = 0; i < s.map.size(); ++i) {
    r.noGoCells += i < s.layers.noGo.size() && s.layers.noGo[i] ? 1 : 0;
    r.speedLimitedCells += i < s.layers.speedLimit.size() && std::isfinite(s.layers.speedLimit[i]) ? 1 : 0;
    r.oneWayCells += i < s.layers.oneWay.size() && std::isfinite(s.layers.oneWay[i]) ? 1 : 0;
  }
  r.cellComponents = cellRegions(s.map).count();
  const auto g = s.drivable();
  const auto regions = discRegions(g, r.radius);
  r.robotRegions = regions.count();
  for (std::int32_t l = 1; l <= static_cast<std::int32_t>(regions.count()); ++l) {
    r.floorArea = std::max(r.floorArea, regions.area(l));
  }
  std::vector<std::int32_t> reg;
  for (const auto& st : s.stations) {
    reg.push_back(regionOf(g, regions, st.pose.position(), r.radius));
  }
  const std::int32_t floor = floorRegion(regions, reg);
  for (std::size_t i = 0; i < s.stations.size(); ++i) {
    const auto& st = s.stations[i];
    StationReach sr;
    sr.name = st.name;
    sr.kind = st.kind;
    sr.pose = st.pose;
    sr.fits = discFits(g, st.pose.position(), r.radius);
    sr.reachable = sr.fits && reg[i] != 0 && reg[i] == floor;
    sr.hasApproach = st.approach.has_value();
    r.stations.push_back(sr);
  }
  r.problems = checkSite(s);
  return r;
}

std::string formatReport(const SiteReport& r) {
  std::ostringstream os;
  os << "site " << r.name << "\n";
  os << "  map: " << r.width << " x " << r.height << " cells of " << r.resolution << " m ("
     << r.width * r.resolution << " x " << r.height * r.resolution << " m, origin " << r.origin.x << ", "
     << r.origin.y << ")\n";
  os << "  free cells: " << r.freeCells << " in " << r.cellComponents << " connected component"
     << (r.cellComponents == 1 ? "" : "s") << "\n";
  os << "  robot of radius " << r.radius << " m: " << r.robotRegions << " region"
     << (r.robotRegions == 1 ? "" : "s") << " it can drive in, the largest " << r.floorArea << " m²\n";
  os << "  zones: " << r.zones << " (no-go cells " << r.noGoCells << ", speed-limited " << r.speedLimitedCells
     << ", one-way " << r.oneWayCells << "), landmarks: " << r.landmarks << "\n";
  std::size_t reachable = 0;
  for (const auto& s : r.stations) {
    reachable += s.reachable ? 1 : 0;
  }
  os << "  stations: " << r.stations.size() << ", reachable " << reachable << "\n";
  for (const auto& s : r.stations) {
    os << "    " << s.name << " (" << toString(s.kind) << ") at " << s.pose.x << ", " << s.pose.y << ": "
       << (s.reachable ? "reachable"
           : s.fits    ? "UNREACHABLE"
                       : "robot does not fit")
       << (s.hasApproach ? "" : ", no straight approach") << "\n";
  }
  for (const auto& p : r.problems) {
    os << "  problem: " << p.key << ": " << p.what << "\n";
  }
  return os.str();
}

nlohmann::json reportJson(const SiteReport& r) {
  nlohmann::json st = nlohmann::json::array();
  for (const auto& s : r.stations) {
    st.push_back({{"name", s.name},
                  {"kind", toString(s.kind)},
                  {"pose", {s.pose.x, s.pose.y, s.pose.theta}},
                  {"fits", s.fits},
                  {"reachable", s.reachable},
                  {"approach", s.hasApproach}});
  }
  nlohmann::json problems = nlohmann::json::array();
  for (const auto& p : r.problems) {
    problems.push_back({{"key", p.key}, {"what", p.what}});
  }
  return {{"name", r.name},
          {"width", r.width},
          {"height", r.height},
          {"resolution", r.resolution},
          {"origin", {r.origin.x, r.origin.y}},
          {"free_cells", r.freeCells},
          {"cell_components", r.cellComponents},
          {"robot_radius", r.radius},
          {"robot_regions", r.robotRegions},
          {"floor_area_m2", r.floorArea},
          {"no_go_cells", r.noGoCells},
          {"speed_limited_cells", r.speedLimitedCells},
          {"one_way_cells", r.oneWayCells},
          {"landmarks", r.landmarks},
          {"zones", r.zones},
          {"stations", st},
          {"problems", problems}};
}

}  // namespace fleet::site
