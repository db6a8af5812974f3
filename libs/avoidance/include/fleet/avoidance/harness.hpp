#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "fleet/avoidance/local_planner.hpp"
#include "fleet/avoidance/safety_layer.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::avoidance {

struct ScenarioRobot {
  Pose2 start;
  Vec2 goal;
  double radius = 0.4;
};

/// A human (or any non-cooperating mover): back and forth between a and b, or a seeded random
/// walk inside the box [a, b].
struct ScenarioHuman {
  Vec2 a;
  Vec2 b;
  double speed = 1.0;
  double radius = 0.3;
  bool randomWalk = false;
};

struct Scenario {
  std::string name;
  planning::OccupancyGrid grid;  ///< static obstacles; occupied cells bordering free space become scan points
  std::vector<ScenarioRobot> robots;
  std::vector<ScenarioHuman> humans;
  control::VelocityLimits limits;
  double dt = 0.1;
  int maxSteps = 3000;
  double sensingRange = 4.0;  ///< scan points and discs farther than this are not in the view
  double goalTolerance = 0.15;
  std::uint32_t seed = 1;
  /// Give each robot an A* path on the grid inflated by its radius + pathMargin (as the robot
  /// agent does) instead of only its goal. Planners that navigate by the goal alone (Bug) ignore it.
  bool globalPath = false;
  double pathMargin = 0.2;
};

struct ScenarioResult {
  std::string planner;
  std::string scenario;
  int robots = 0;
  int reached = 0;
  int collisions = 0;            ///< overlap events (a pair or robot/obstacle entering contact), all kinds
  int robotCollisions = 0;       ///< robot–robot
  int staticCollisions = 0;      ///< robot–shelf/wall
  int humanCollisions = 0;       ///< robot–human (humans do not avoid: a stopped robot can be walked into)
  int humanHitsWhileMoving = 0;  ///< robot–human contacts that began while the robot was moving
  int humanHitsByRobot = 0;      ///< ... while the robot drove towards the person at > 0.05 m/s (its fault)
  double minSeparation = 0.0;    ///< smallest surface gap robot–anything over the run [m]
  double meanTimeToGoal = 0.0;   ///< over the robots that arrived [s]
  double makespan = 0.0;         ///< time the last robot arrived (or the run ended) [s]
  double meanPathLength = 0.0;   ///< over the robots that arrived [m]
  double meanRemaining = 0.0;    ///< mean distance to goal at the end over all robots [m]
  double meanTravelled = 0.0;    ///< mean path length over all robots [m]
  std::int64_t agentSteps = 0;   ///< planner calls
  double computeMeanUs = 0.0;    ///< per planner call (safety layer included)
  double computeP99Us = 0.0;
  int overruled = 0;  ///< safety-layer interventions

  [[nodiscard]] bool success() const { return reached == robots && collisions == 0; }
};

/// Run every robot with its own instance of the named planner, wrapped by the safety layer when
/// `withSafety`. Robots that arrive stop and stay as obstacles. Library-level (no DDS).
Expected<ScenarioResult> runScenario(const Scenario& scenario, std::string_view planner,
                                     bool withSafety = true, SafetyParams safety = {});

/// N robots evenly on a circle of radius R, each going to its antipode.
Scenario circleSwap(int n, double circle_radius, double robot_radius = 0.4);

/// A 20 m warehouse aisle between two shelf rows with a cross aisle in the middle; robots drive
/// along the aisle both ways while humans cross it (straight, back and forth) and one walks at random.
Scenario aisleCrossing(int robots_each_way = 2, int crossing_humans = 2, std::uint32_t seed = 1);

/// One robot, 16 m to go past three boxes (the first square across the straight line, the other
/// two offset to alternating sides) inside a walled hall: the static case every local planner is
/// built for, with no moving discs.
Scenario obstacleCourse();

/// One robot driving the length of aisleCrossing's aisle while people cross it and one walks at
/// random: the moving-obstacle case for a single robot (the multi-robot cases are comparisons).
Scenario aisleCrossingAlone(int crossing_humans = 2, std::uint32_t seed = 1);

}  // namespace fleet::avoidance
