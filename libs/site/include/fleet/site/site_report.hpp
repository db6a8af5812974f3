#pragma once

// What `fleetctl site check` prints: what a site or map holds and where a robot of a given
// radius can go on it.

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fleet/site/site.hpp"
#include "fleet/site/site_loader.hpp"

namespace fleet::site {

struct StationReach {
  std::string name;
  StationKind kind = StationKind::Pickup;
  Pose2 pose;
  bool fits = false;       ///< the robot's disc fits at the station
  bool reachable = false;  ///< ... and it lies in the floor region (the one holding most stations)
  bool hasApproach = false;
};

struct SiteReport {
  std::string name;
  int width = 0;
  int height = 0;
  double resolution = 0.0;
  Vec2 origin;
  std::size_t freeCells = 0;
  std::size_t noGoCells = 0;
  std::size_t speedLimitedCells = 0;
  std::size_t oneWayCells = 0;
  std::size_t cellComponents = 0;  ///< 4-connected components of free cells
  double radius = 0.0;             ///< the disc the robot regions are for
  std::size_t robotRegions = 0;    ///< regions where that disc can drive
  double floorArea = 0.0;          ///< m² of lattice points of the largest such region
  std::size_t landmarks = 0;
  std::size_t zones = 0;
  std::vector<StationReach> stations;
  std::vector<SiteProblem> problems;  ///< checkSite() for `radius`
};

/// Analyses `site` for a robot of `radius` (the site's robot radius when <= 0).
SiteReport analyseSite(const Site& site, double radius = 0.0);
std::string formatReport(const SiteReport& r);
nlohmann::json reportJson(const SiteReport& r);

}  // namespace fleet::site
