#pragma once

// The site: everything about a warehouse that every service needs and that stays when the
// simulator is gone — the occupancy map, the stations with the way in and out of each, landmarks,
// zones, and the robots' description. Loaded by loadSite() (site_loader.hpp) from one site.json.

#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "fleet/control/velocity_limits.hpp"
#include "fleet/core/pose2.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::site {

enum class StationKind { Pickup, Dropoff, Charging, Parking };
const char* toString(StationKind k);
std::optional<StationKind> stationKindFromString(const std::string& s);

/// A place a robot docks at. `pose.theta` points out of the station, into the free space it is
/// reached from. `approach` is the pre-dock point (VDA 5050's approach pose): the straight last leg
/// runs from it to the station. When site.json gives none, it is the point
/// `kDefaultApproachDistance` along the heading if the robot's disc fits along that whole leg, and
/// there is none otherwise (a station in a narrow row is approached along the row). Where the disc
/// keeps less than `kApproachClearance` of free space at that point, the nearest point further in
/// (down to `kMinApproachDistance`) that keeps it is taken instead: a robot stops a few centimetres
/// off its approach point, and one stopped within reach of a shelf corner that its way on leads
/// past stood for good (100 robots on the generated warehouse).
struct Station {
  std::string name;
  StationKind kind = StationKind::Pickup;
  Pose2 pose;
  std::optional<Vec2> approach;
  bool approachGiven = false;  ///< false: derived by the loader
  std::vector<Vec2> queue;     ///< waiting points, nearest to the station first
  /// Where a robot leaves the dock to (a station as a server: it enters from its queue and leaves
  /// by a way of its own, so the leaving robot never meets the next in line). Given in site.json
  /// or placed by the roadmap (roadmap.hpp); none for parking places.
  std::optional<Vec2> exit;
  /// site.json's `"exit": "entry"`: a dead end left by its way in, said on purpose (the leaving
  /// robot meets the next in line there). Without it a pickup or drop-off the roadmap finds no
  /// way out for is refused.
  bool exitByEntry = false;
};

inline constexpr double kDefaultApproachDistance = 1.0;  // m
inline constexpr double kMinApproachDistance = 0.6;      // m
inline constexpr double kApproachClearance = 0.1;        // m beyond the disc (the roadmap's nodeClearance)

struct Landmark {
  std::int32_t id = 0;
  Vec2 position;
};

enum class ZoneKind { NoGo, SpeedLimit, OneWay };
const char* toString(ZoneKind k);

/// An area with a rule. Zones from site.json are polygons; zones from a Nav2 filter mask are cell
/// masks on the site map (`cells` lists the map cell indices, `polygon` is empty).
struct Zone {
  std::string name;
  ZoneKind kind = ZoneKind::NoGo;
  std::vector<Vec2> polygon;       ///< counter-clockwise or clockwise, not self-intersecting
  std::vector<std::size_t> cells;  ///< mask zones: OccupancyGrid::index of each covered cell
  double maxSpeed = 0.0;           ///< SpeedLimit: m/s
  double direction = 0.0;          ///< OneWay: allowed heading [rad]; within ±90° is allowed
};

struct SensorDescription {
  int rays = 72;
  double fov = 2.0 * 3.14159265358979323846;  ///< rad, centred on the heading
  double rangeMax = 8.0;                      ///< m
  double rateHz = 10.0;
  bool compass = true;
  bool landmarks = true;
  double landmarkRange = 15.0;  ///< m
  double detectionRange = 6.0;  ///< m: people and robots reported by the perception stack
};

/// What every service must know of a robot type.
struct RobotDescription {
  double radius = 0.3;     ///< m, the disc the footprint fits in
  double wheelBase = 0.4;  ///< m
  control::VelocityLimits limits{1.0, -0.3, 1.5, 1.0, 3.0};
  SensorDescription sensors;
};

/// Per-cell rules rasterised from the zones onto the site map (same size and frame).
struct ZoneLayers {
  std::vector<std::uint8_t> noGo;  ///< 1: a robot must not enter the cell
  std::vector<float> speedLimit;   ///< m/s; +inf: no limit
  std::vector<float> oneWay;       ///< allowed heading [rad]; NaN: any direction
};

struct Site {
  std::string name;
  std::string origin;  ///< the file it came from
  planning::OccupancyGrid map;
  std::vector<Station> stations;
  std::vector<Landmark> landmarks;
  std::vector<Zone> zones;
  RobotDescription robot;
  ZoneLayers layers;

  [[nodiscard]] const Station* station(const std::string& name) const;
  [[nodiscard]] std::vector<const Station*> ofKind(StationKind k) const;
  /// The map with no-go cells blocked: what a planner may use.
  [[nodiscard]] planning::OccupancyGrid drivable() const;
  [[nodiscard]] double speedLimitAt(Vec2 p) const;  ///< +inf outside every speed zone
};

}  // namespace fleet::site
