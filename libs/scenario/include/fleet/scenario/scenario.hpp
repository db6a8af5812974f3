#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "fleet/control/velocity_limits.hpp"
#include "fleet/core/config.hpp"
#include "fleet/core/pose2.hpp"
#include "fleet/scenario/grid_map.hpp"
#include "fleet/site/site.hpp"

namespace fleet::sim {

using site::StationKind;  // one set of station kinds; site::toString names them

struct Station {
  std::string name;
  StationKind kind = StationKind::Pickup;
  Pose2 pose;
};

struct Landmark {
  std::int32_t id = 0;
  Vec2 position;
};

struct SensorSpec {
  int rays = 72;
  double fov = 2.0 * 3.14159265358979323846;  // rad, centred on the heading
  double rangeMax = 8.0;                      // m
  double rateHz = 10.0;                       // frames per second (rounded to whole steps)
  double rangeSigma = 0.01;                   // m
  bool compass = true;
  double compassSigma = 0.02;  // rad
  bool landmarks = true;
  double landmarkRange = 15.0;  // m
  double bearingSigma = 0.01;   // rad
  bool detections = true;
  double detectionRange = 6.0;  // m
};

struct NoiseSpec {
  double slipSigma = 0.01;  // relative error of the executed wheel speeds (wheel slip)
  double odomSigma = 0.01;  // relative error of each reported wheel distance
};

struct BatterySpec {
  double initial = 1.0;         // state of charge 0..1
  double drainIdlePerS = 1e-5;  // SoC per second at rest
  double drainPerM = 2e-4;      // SoC per metre driven
  double chargePerS = 2e-3;     // SoC per second on a charging station
};

struct RobotSpec {
  std::string id;
  Pose2 start;
  double radius = 0.3;
  double wheelBase = 0.4;
  control::VelocityLimits limits{1.0, -0.3, 1.5, 1.0, 3.0};
  double commandTimeout = 0.5;  // s without a command -> stop
  SensorSpec sensors;
  NoiseSpec noise;
  BatterySpec battery;
};

struct Area {
  Vec2 lo;
  Vec2 hi;
};

/// A human with an explicit route (looped) or random goals when the route is empty.
struct HumanSpec {
  std::string id;
  Vec2 start;
  std::vector<Vec2> route;
  double speed = 1.3;
};

struct CrowdSpec {
  int count = 0;
  std::vector<Area> spawnAreas;  // empty: anywhere free
  double speedMean = 1.3;        // m/s
  double speedSd = 0.2;
  double stopProbability = 0.2;  // chance to pause at a reached goal
  double stopMinS = 1.0;
  double stopMaxS = 5.0;
  int groupSize = 1;  // members of a group share goals and spawn together
  double radius = 0.25;
};

struct SocialForceParams {
  double tau = 0.5;      // s, relaxation time
  double humanA = 2.1;   // m/s², strength of human-human repulsion
  double humanB = 0.3;   // m, its range
  double wallA = 5.0;    // m/s²
  double wallB = 0.2;    // m
  double robotA = 4.0;   // m/s²: people keep more room from machines
  double robotB = 0.4;   // m
  double lambda = 0.35;  // anisotropy: weight of what is behind
  double cutoff = 3.0;   // m, interactions further than this are ignored
  double maxSpeedFactor = 1.3;
  /// m: a person's step never ends closer than this to a robot's body (cut like a step into a
  /// wall: slide or stand). Negative: off (people may walk into robots, pure social force).
  double robotKeep = 0.05;
};

struct Scenario {
  std::string name;
  std::string origin;  // file it came from
  /// The site the scenario runs on: the file named by "site", or one made from the scenario's own
  /// map, stations and landmarks (older scenarios carry them inline). `map`, `stations` and
  /// `landmarks` below are the simulator's copies of it.
  std::shared_ptr<const site::Site> site;
  std::string sitePath;  // absolute path of the site file; empty for an inline site
  GridMap map;
  std::vector<Station> stations;
  std::vector<Vec2> pointsOfInterest;  // human goals besides the stations
  std::vector<Landmark> landmarks;
  std::vector<RobotSpec> robots;
  std::vector<HumanSpec> humans;
  CrowdSpec crowd;
  SocialForceParams social;
  double durationS = 60.0;
  double dt = 0.1;
  std::uint64_t seed = 1;
  double nearMiss = 0.3;            // m of clearance under which a pass counts as a near miss
  double predictionHorizonS = 3.0;  // human PredictedDiscs horizon
  double predictionDt = 0.5;
  double predictionSigma0 = 0.05;    // m
  double predictionSigmaRate = 0.3;  // m/s: σ(t) = σ0 + rate * t
  std::string clock = "wall";        // default clock mode: wall | lockstep
};

/// Loads and validates a scenario; throws ConfigError listing every problem (file, key, expectation):
/// unknown keys, wrong types, negative speeds, robots in walls or overlapping, unknown stations,
/// stations or robots unreachable from the first robot's free region.
Scenario loadScenario(const std::string& path);
/// Same from an already parsed document; `baseDir` resolves a relative map file.
Scenario parseScenario(const nlohmann::json& doc, const std::string& origin, const std::string& baseDir);

}  // namespace fleet::sim
