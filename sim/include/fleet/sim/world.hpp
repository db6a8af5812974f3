#pragma once

#include <cstdint>
#include <limits>
#include <memory>
#include <random>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "fleet/control/twist.hpp"
#include "fleet/scenario/scenario.hpp"
#include "fleet/sim/flow_field.hpp"
#include "fleet/sim/spatial_hash.hpp"

namespace fleet::sim {

struct RobotBody {
  Pose2 pose;
  control::Twist twist;                                           // executed in the last step
  control::Twist command;                                         // last accepted command
  double commandTime = -std::numeric_limits<double>::infinity();  // sim s
  double battery = 1.0;
  bool charging = false;
  /// Whether it charges when standing on a charger: always (our robots' chargers switch on by
  /// contact), or only once the vehicle has switched its charging on (a VDA 5050 vehicle's
  /// startCharging; setChargeSwitch()).
  bool switchedCharging = false;
  bool chargeSwitch = false;
  double odomLeft = 0.0;  // measured wheel distances since the last sensor frame, m
  double odomRight = 0.0;
  double odomLeftTotal = 0.0;  // measured wheel distances since the start, m (what wheel encoders count)
  double odomRightTotal = 0.0;
  double distance = 0.0;  // true path length, m
  double idleS = 0.0;     // time standing still, s
  std::uint32_t frameSeq = 0;
  int bumps = 0;     // steps a shelf stopped the robot
  std::string mode;  // label from outside (agent's RobotState), replay only
  std::string task;
  std::string activity;  // RobotState.activity's text name; empty when the agent does not say it
};

struct HumanBody {
  std::string id;
  Vec2 p;
  Vec2 v;
  double v0 = 1.3;  // desired speed
  double r = 0.25;
  int field = -1;          // flow field of the current goal
  std::vector<int> route;  // flow fields of an explicit route (looped); empty: random goals
  std::size_t routeIdx = 0;
  double stopUntil = 0.0;  // sim s
  int leader = -1;         // group leader's index (self when leading or alone)
  Vec2 progressRef;        // where the human was when it last made progress
  double progressAt = -1;  // sim s of that moment; -1 before the first step
  Vec2 aside;              // a point to step to out of a gap between robots ...
  double asideUntil = -1;  // ... until then (sim s); < 0: none
};

/// A contact between two bodies this step. Indices: robots 0..R-1, humans R..R+H-1, b = -1 is the map.
struct ContactInfo {
  int a = 0;
  int b = -1;
  double depth = 0.0;
};

struct Counters {
  std::uint64_t nanCommands = 0;      // NaN/inf commands ignored
  std::uint64_t clampedCommands = 0;  // commands beyond the robot's speed limits (clamped)
  std::uint64_t unknownRobot = 0;     // commands for robots not in the scenario (ignored)
  std::uint64_t foreignCommands = 0;  // commands from a writer outside the robot's partition (dropped)
  std::uint64_t timeouts = 0;         // robots stopped by the command timeout (rising edges)
  std::uint64_t stepTimeouts = 0;     // lockstep steps that advanced without every StepDone
  std::uint64_t wallOverruns = 0;     // wall-clock steps that took longer than dt (the run fell behind)
};

struct Metrics {
  std::uint64_t robotRobotContacts = 0;  // contact events (a pair that was not touching the step before)
  std::uint64_t robotHumanContacts = 0;
  std::uint64_t robotShelfContacts = 0;
  std::uint64_t contactSteps = 0;        // steps with at least one contact
  std::uint64_t nearMissRobotRobot = 0;  // pair came closer than nearMiss without touching (events)
  std::uint64_t nearMissRobotHuman = 0;
  // Smallest surface gap seen (m, < 0: overlap) among pairs closer than max(near_miss, 2 m) (shelves:
  // max(near_miss, 0.5 m)); inf if none.
  double minSepRobotRobot = std::numeric_limits<double>::infinity();
  double minSepRobotHuman = std::numeric_limits<double>::infinity();
  double minSepRobotShelf = std::numeric_limits<double>::infinity();
};

struct SensorReading {
  std::size_t robot = 0;
  std::uint32_t seq = 0;
  double dsLeft = 0.0;
  double dsRight = 0.0;
  double wheelLeftTotal = 0.0;
  double wheelRightTotal = 0.0;
  float angleMin = 0.0F;
  float angleIncrement = 0.0F;
  float rangeMax = 0.0F;
  std::vector<float> ranges;
  bool compassValid = false;
  double compass = 0.0;
  std::vector<std::pair<std::int32_t, float>> landmarks;  // id, bearing (robot frame)
  struct Seen {
    bool human = false;
    float x = 0.0F;  // robot frame
    float y = 0.0F;
    float r = 0.0F;
  };
  std::vector<Seen> detections;
  float battery = 1.0F;
  bool charging = false;
};

struct PredictedDisc {
  double x = 0;
  double y = 0;
  double r = 0;
  double sigma = 0;
};

/// A random stream with a cached second Box-Muller normal.
struct GaussianStream {
  std::mt19937_64 engine;
  bool hasSpare = false;
  double spare = 0.0;
};

enum class CommandOutcome { Accepted, Clamped, Ignored };

/// The simulated warehouse. Everything random comes from generators seeded by the scenario seed and
/// drawn in a fixed order, so the same seed and the same commands give the same states bit for bit.
class World {
 public:
  explicit World(Scenario scenario);

  [[nodiscard]] const Scenario& scenario() const { return sc_; }
  [[nodiscard]] std::int64_t step() const { return step_; }
  [[nodiscard]] double time() const { return static_cast<double>(step_) * sc_.dt; }
  [[nodiscard]] std::int64_t timeNs() const;
  [[nodiscard]] const std::vector<RobotBody>& robots() const { return robots_; }
  [[nodiscard]] const std::vector<HumanBody>& humans() const { return humans_; }
  [[nodiscard]] const std::vector<ContactInfo>& contacts() const { return contacts_; }
  [[nodiscard]] const Counters& counters() const { return counters_; }
  [[nodiscard]] Counters& counters() { return counters_; }
  [[nodiscard]] const Metrics& metrics() const { return metrics_; }
  /// Index of a robot id, -1 when unknown.
  [[nodiscard]] int robotIndex(const std::string& id) const;
  [[nodiscard]] std::string bodyId(int index) const;

  /// A velocity command for robot `id`, effective from the next step. NaN/inf: ignored and counted;
  /// outside the speed limits: clamped (by the kinematic limiter) and counted.
  CommandOutcome command(const std::string& id, double v, double w);
  CommandOutcome command(std::size_t robot, double v, double w);
  void setLabel(std::size_t robot, std::string mode, std::string task, std::string activity = {});
  /// From now on robot `robot` charges on a charger only while `on` (see RobotBody::chargeSwitch).
  void setChargeSwitch(std::size_t robot, bool on);
  /// Whether the robot stands within reach of a charging station's contacts.
  [[nodiscard]] bool atCharger(std::size_t robot) const;

  /// Advances by dt: robots (limits, slip, shelves), humans (social force), contacts, metrics, battery.
  void advance();

  /// Sensor frames due at the current step (every robot whose rate divides the step), in robot order.
  /// When `withScan` is false the range scan is skipped (cheap mode for huge runs).
  std::vector<SensorReading> sensorFrames(bool withScan = true);
  /// One robot's frame now (consumes the sensor noise stream).
  SensorReading sensorFrame(std::size_t robot, bool withScan = true);
  /// The scan alone, noise-free: ranges of `rays` rays from the robot's pose.
  std::vector<float> scan(std::size_t robot) const;

  /// Constant-velocity prediction of a human with growing σ (scenario.prediction*).
  [[nodiscard]] std::vector<PredictedDisc> predictHuman(std::size_t human) const;

 private:
  void spawnHumans();
  int fieldFor(Vec2 goal);
  void pickGoal(std::size_t h);
  /// Another goal for someone who could not get on: one whose way does not lead into a robot beside them.
  void pickGoalAwayFromRobots(std::size_t h);
  /// A free point a step away whose direction leads into none of `near`, as far from them as
  /// possible; false if there is none.
  bool stepAside(HumanBody& h, const std::vector<Vec2>& near);
  void stepRobots();
  void stepHumans();
  void updateContacts();
  void rebuildHash();
  void scanInto(std::size_t robot, std::vector<float>& out) const;

  Scenario sc_;
  std::vector<RobotBody> robots_;
  std::vector<HumanBody> humans_;
  std::unordered_map<std::string, int> robotIds_;
  std::vector<FlowField> fields_;
  std::vector<int> randomGoals_;  // fields humans pick from when they have no route
  GaussianStream motionRng_;
  GaussianStream humanRng_;
  GaussianStream sensorRng_;
  std::int64_t step_ = 0;
  std::vector<int> sensorEvery_;  // per robot, steps between frames
  std::vector<Vec2> positions_;   // robots then humans, for the hash
  std::vector<double> radii_;
  double maxRadius_ = 0.0;
  SpatialHash hash_;
  std::vector<ContactInfo> contacts_;
  std::vector<double> bumpDepth_;  // per robot, this step
  std::unordered_set<std::uint64_t> touching_;
  std::unordered_set<std::uint64_t> near_;
  std::vector<bool> timedOut_;
  Counters counters_;
  Metrics metrics_;
};

}  // namespace fleet::sim
