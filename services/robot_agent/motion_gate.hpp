#pragma once

// The last word on a twist before it drives the robot: the stop rule (keep a gap, growing with
// speed, to whatever the sensors see in the corridor the robot sweeps), the same behind it when
// reversing, and the cross-traffic check (the safety layer against the robots and people around,
// extrapolated at their velocities, then against the scan and the map's obstacle faces). It says
// whether the robot is held up and by what, so the standoff rules know whom to yield to.

#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fleet/avoidance/safety_layer.hpp"
#include "fleet/control/twist.hpp"
#include "fleet/control/velocity_limits.hpp"
#include "fleet/planning/occupancy_grid.hpp"
#include "localizer.hpp"
#include "other_robot.hpp"

namespace fleet::agent {

struct GateParams {
  double radius = 0.3;
  double stopGap = 0.35;  ///< m of free space kept ahead at standstill
  double headway = 1.0;   ///< s: the stop distance grows with speed
  /// The same gap to another robot (detected, or the range readings on its disc); < 0: stopGap.
  /// Reserved traffic keeps it smaller than the gap to people: the traffic layer plans robots
  /// one behind another at the roadmap's following distance (libs/traffic RoadmapOptions::stopGap
  /// is this plus 0.05 m), and a wider gap here turned every planned follow into a halt.
  double robotStopGap = -1.0;
  control::VelocityLimits limits;
  /// The site's speed limit at a map point [m/s] (+inf: none); empty: no zones.
  std::function<double(Vec2)> speedLimit;
  /// The cross-traffic check's slow-down zone counts walls and shelves too (see
  /// avoidance::SafetyParams::slowForStatic; false in reserved traffic).
  bool slowForStatic = true;
  /// A person beside the corridor ahead, at most this far from its edge [m], may step into it
  /// faster than the cross-traffic check (which extrapolates at the person's velocity) foresees:
  /// the robot keeps a speed it can stop from before the person's place along its way (the stop
  /// rule's law on the gap along), and at most nearPersonSpeed while the person is level with it.
  /// (A person overtaking a robot 0.33 m to its side turned onto its way 0.45 m ahead; from
  /// 0.8 m/s the robot needed 0.40 m to stop and touched them, docs/algorithms.md.)
  double personSideGap = 0.35;
  double nearPersonSpeed = 0.3;  ///< m/s
};

/// What the gate looks at in one cycle (non-owning: the caller keeps it alive for the call).
struct GateView {
  const Perception& seen;                 ///< pose, scan, detections and people
  const std::vector<OtherRobot>& others;  ///< as they report themselves
  const planning::OccupancyGrid& map;     ///< the raw map (its obstacle faces near the robot)
  control::Twist current;                 ///< the command of the previous cycle
  bool docking = false;                   ///< on the final approach to a goal: static points may come closer
  /// The route the robot follows from where it is (map frame; null: none). With one, the stop
  /// rule keeps its gap to static points on the route, not in the straight corridor ahead: a
  /// roadmap route passes a shelf corner 0.1 m clear of the disc while the corner is still in the
  /// straight corridor (the robot heading past it), which held a robot for good at its first
  /// release. What really sweeps past the corner is left to the cross-traffic check.
  const std::vector<Vec2>* route = nullptr;
};

/// What holds the robot up: a robot (its id, or "robot" when it cannot be named), "human", or
/// nothing named (empty: a static obstacle).
struct Blocker {
  bool robot = false;
  std::string id;
};

class MotionGate {
 public:
  explicit MotionGate(GateParams params) : p_(std::move(params)), safety_(safetyOf(p_)) {}

  struct Clearance {
    double speed = 0.0;              ///< largest forward speed that keeps the stop gap
    std::optional<Vec2> blockPoint;  ///< where the nearest thing that limits it is (map frame)
  };
  /// The stop rule for a forward speed `v`. Names what blocks in `blocker` when a detection stops
  /// the robot (left as it is otherwise).
  [[nodiscard]] Clearance clearSpeed(const GateView& view, double v, Blocker& blocker) const;
  /// Nothing within a short distance behind (backing off must not hit what it cannot see coming).
  [[nodiscard]] bool rearClear(const GateView& view) const;
  /// (v, w) through the safety layer against the robots and people ahead or beside, extrapolated
  /// at their velocities (crossings at intersections, which the stop rule's straight-ahead corridor
  /// sees too late), then against the scan and the map's faces. False when it had to stop the
  /// robot; `blocker` then names the robot or person in the way (empty: a static obstacle).
  bool crossTrafficSafe(const GateView& view, double& v, double& w, std::string& blocker) const;

  struct Hold {
    bool held = false;
    std::optional<Vec2> blockPoint;  ///< as clearSpeed found it
  };
  /// The site's speed limit for the robot now: the lowest at its position and at the point it
  /// would reach within its headway (so it slows before a slow zone, not inside it); +inf: none.
  [[nodiscard]] double zoneSpeed(const GateView& view, double v) const;
  /// The speed for the people beside the corridor ahead (see GateParams::personSideGap); +inf:
  /// none there.
  [[nodiscard]] double besidePeopleSpeed(const GateView& view) const;
  /// Speed zones, people beside the way, stop rule and cross-traffic check on (v, w), which come
  /// out limited (a speed zone or a person beside keeps the curvature and does not count as being
  /// held); held: the robot is held.
  Hold heldUp(const GateView& view, double& v, double& w, Blocker& blocker) const;

 private:
  static avoidance::SafetyParams safetyOf(const GateParams& p) {
    avoidance::SafetyParams s;
    s.slowForStatic = p.slowForStatic;
    return s;
  }
  GateParams p_;
  /// The library's default zones, not AgentParams::safety (those are the local planner's).
  avoidance::SafetyLayer safety_;
};

}  // namespace fleet::agent
