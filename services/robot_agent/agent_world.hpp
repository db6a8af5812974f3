#pragma once

// What the agents of a process need of the world: the map, the landmarks and their robots with
// their starts. From a site and a list of robots (a deployment) or from a simulator scenario.

#include <cstdint>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "fleet/control/velocity_limits.hpp"
#include "fleet/core/pose2.hpp"
#include "fleet/planning/occupancy_grid.hpp"
#include "fleet/site/site.hpp"

namespace fleet::agent {

struct World {
  std::shared_ptr<const planning::OccupancyGrid> map;
  std::shared_ptr<const site::Site> site;  ///< its zones (null: a scenario with its map inline)
  std::vector<std::pair<std::int32_t, Vec2>> landmarks;
  struct Robot {
    std::string id;
    Pose2 start;
    double radius = 0.3;
    double wheelBase = 0.4;
    control::VelocityLimits limits;
  };
  std::vector<Robot> robots;
  double dt = 0.1;  // control period, s
  std::string name;
};

/// `--robot ID@PLACE`: PLACE is a station of the site or "x,y,theta" in the map frame. Every
/// problem is collected (ConfigError): a bad id, an unknown station, a start the robot does not
/// fit on, an id given twice.
World worldFromSite(const site::Site& st, const std::vector<std::string>& robotSpecs);

/// A simulator scenario file: its site (or inline map), its landmarks and robots.
World worldFromScenario(const std::string& scenarioPath);

}  // namespace fleet::agent
