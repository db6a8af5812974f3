#include "agent_world.hpp"

#include <cmath>
#include <cstdio>

#include "fleet/core/angles.hpp"
#include "fleet/core/config.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/scenario/grid_map.hpp"
#include "fleet/scenario/scenario.hpp"
#include "fleet/site/reachability.hpp"

namespace fleet::agent {

World worldFromScenario(const std::string& scenarioPath) {
  const sim::Scenario scn = sim::loadScenario(scenarioPath);
  World w;
  w.map = std::make_shared<const planning::OccupancyGrid>(sim::toOccupancyGrid(scn.map));
  if (scn.site && scn.site->map.width() == w.map->width() && scn.site->map.height() == w.map->height()) {
    w.site = scn.site;
  }
  for (const auto& l : scn.landmarks) {
    w.landmarks.emplace_back(l.id, l.position);
  }
  for (const auto& r : scn.robots) {
    w.robots.push_back({r.id, r.start, r.radius, r.wheelBase, r.limits});
  }
  w.dt = scn.dt;
  w.name = scn.name;
  return w;
}

World worldFromSite(const site::Site& st, const std::vector<std::string>& robotSpecs) {
  World w;
  w.map = std::make_shared<const planning::OccupancyGrid>(st.map);
  w.site = std::make_shared<const site::Site>(st);
  for (const auto& l : st.landmarks) {
    w.landmarks.emplace_back(l.id, l.position);
  }
  w.name = st.name;
  std::vector<std::string> problems;
  for (const auto& spec : robotSpecs) {
    const auto at = spec.find('@');
    const std::string robot = spec.substr(0, at);
    const std::string place = at == std::string::npos ? "" : spec.substr(at + 1);
    const std::string where = "--robot " + spec + ": ";
    if (!isValidId(robot) || place.empty()) {
      problems.push_back(where +
                         "expected ID@STATION or ID@x,y,theta with an id of 1 to 63 of A-Z a-z 0-9 _ . : -");
      continue;
    }
    World::Robot r{robot, {}, st.robot.radius, st.robot.wheelBase, st.robot.limits};
    if (const auto* station = st.station(place)) {
      r.start = station->pose;
    } else {
      double x = 0, y = 0, th = 0;
      char tail = 0;
      if (std::sscanf(place.c_str(), "%lf,%lf,%lf%c", &x, &y, &th, &tail) != 3 || !std::isfinite(x) ||
          !std::isfinite(y) || !std::isfinite(th)) {
        problems.push_back(where + "'" + place + "' is neither a station of site '" + st.name +
                           "' nor x,y,theta");
        continue;
      }
      r.start = {x, y, wrapAngle(th)};
    }
    if (!site::discFits(st.map, r.start.position(), r.radius)) {
      problems.push_back(where + "a robot of radius " + std::to_string(r.radius) +
                         " m does not fit at its start");
    }
    for (const auto& o : w.robots) {
      if (o.id == robot) {
        problems.push_back(where + "robot '" + robot + "' is given twice");
      }
    }
    w.robots.push_back(r);
  }
  if (robotSpecs.empty()) {
    problems.push_back("--site needs at least one --robot ID@STATION");
  }
  if (!problems.empty()) {
    throw ConfigError(problems);
  }
  return w;
}

}  // namespace fleet::agent
