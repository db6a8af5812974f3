#pragma once

// Loading a site: one documented file (site.json, schema in docs/site.schema.json), or a bare map
// (MovingAI .map, ROS map YAML) as a site without stations. Every problem is collected and
// reported at once, each naming the file and the key path (fleet::ConfigError).

#include <nlohmann/json.hpp>
#include <string>

#include "fleet/core/config.hpp"
#include "fleet/site/site.hpp"

namespace fleet::site {

/// Current format tag of site.json ("format" key).
inline constexpr const char* kSiteFormat = "fleet-site/1";

/// Loads and validates a site.json; throws ConfigError listing every problem: unknown keys, wrong
/// types, a map image that does not match its side file or the declared size, stations inside
/// obstacles or no-go zones or unreachable for the robot's disc, zones that cross the map's edge.
/// `checkGeometry` false leaves out checkSite() (what `fleetctl site check` reports itself).
Site loadSite(const std::string& path, bool checkGeometry = true);
/// Same from a parsed document; `baseDir` resolves the map and mask files.
Site parseSite(const nlohmann::json& doc, const std::string& origin, const std::string& baseDir,
               bool checkGeometry = true);
/// site.json, a MovingAI .map or a ROS .yaml, by extension (a bare map: no stations, the default
/// robot description, resolution 1 m for a .map unless given).
Site loadSiteOrMap(const std::string& path, double mapResolution = 1.0, bool checkGeometry = true);

/// The map section shared with simulator scenarios that still carry their map inline: exactly one
/// of "file" (MovingAI), "ros" (ROS map YAML), "image" (JSON side file of a PGM, older format),
/// "warehouse" (generated) or "rows"; "resolution" and "origin" for the first, fourth and fifth;
/// optional "width"/"height" in cells that the loaded map must match.
planning::OccupancyGrid readMapSection(Config c, const std::string& baseDir);

/// [x, y] or, with `theta`, [x, y] / [x, y, theta]: records a problem and returns false otherwise.
bool readPoint(Config& c, const std::string& key, Vec2& out, bool required, double* theta = nullptr);

/// A "limits" object (vMax, vMin, w_max, accelMax, alphaMax) over `v`.
void readLimits(Config& l, control::VelocityLimits& v);

/// The "robot" section's keys (radius, wheelBase, limits, sensors) over `r`.
void readRobotDescription(Config& c, RobotDescription& r);

/// Derives what site.json leaves out (approach points) and rasterises the zones into `layers`.
/// parseSite calls it; services that build a Site in code call it too.
void completeSite(Site& s);

/// One problem of a complete site: the key path in site.json ("stations[3].pose") and what is wrong.
struct SiteProblem {
  std::string key;
  std::string what;
};
/// The problems with a complete site (empty: fine): stations in obstacles or no-go cells,
/// stations the robot's disc cannot reach from the others, approach legs and queue points where
/// the disc does not fit.
std::vector<SiteProblem> checkSite(const Site& s);

}  // namespace fleet::site
