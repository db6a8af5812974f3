#pragma once

// Scenarios of any fleet size for load tests: the small warehouse template (robot model, sensors,
// crowd and prediction settings) with a procedural warehouse scaled to the fleet. About 30 m² of
// floor per robot (the small warehouse's ratio), parking rows in the bottom margin (one spot per
// robot, rows 1.6 m apart so a robot leaving an inner row has a 1 m lane), pickups along the top
// margin, drop-offs along the right margin, chargers along the left margin.

#include <nlohmann/json.hpp>

#include "fleet/core/expected.hpp"

namespace fleet::ctl {

struct ScenarioSize {
  int robots = 20;
  int humans = 8;
  double durationS = 180;
  std::uint64_t seed = 7;
  // Size the warehouse, its parking and stations for this many robots (0: for `robots`) and place
  // `robots` of them: a sweep over fleet sizes on one site.
  int siteRobots = 0;
};

/// Builds the scenario document from a template document (keys other than map, stations, robots,
/// landmarks and humans.count/spawn_areas are kept). Errors: robots outside [1, 2000], humans
/// outside [0, 5000], siteRobots outside [robots, 2000] (when not 0).
Expected<nlohmann::json> generateScenario(const nlohmann::json& templ, const ScenarioSize& size);

/// Extent of a scenario's map in metres (generated warehouse maps only; else 0 x 0).
std::pair<double, double> mapExtent(const nlohmann::json& scenario);

}  // namespace fleet::ctl
