#include "agent_wire.hpp"

namespace fleet::agent {

SensorReading readingOf(const msg::SensorFrame& f) {
  SensorReading r;
  r.stampNs = f.stamp_ns;
  r.dsLeft = f.ds_left;
  r.dsRight = f.ds_right;
  r.wheelTotalsValid = f.wheel_totals_valid;
  r.wheelLeftTotal = f.wheel_left_total;
  r.wheelRightTotal = f.wheel_right_total;
  r.driverSession = f.driver_session;
  r.compassValid = f.compass_valid;
  r.compass = f.compass;
  r.bearings.reserve(f.landmarks.size());
  for (const auto& lb : f.landmarks) {
    r.bearings.emplace_back(lb.id, lb.bearing);
  }
  r.angleMin = f.angle_min;
  r.angleIncrement = f.angle_increment;
  r.rangeMax = f.range_max;
  r.ranges = f.ranges;
  r.sightings.reserve(f.detections.size());
  for (const auto& d : f.detections) {
    r.sightings.push_back(
        {d.kind == msg::SourceKind::Human ? SeenKind::kHuman : SeenKind::kRobot, d.x, d.y, d.r});
  }
  return r;
}

OtherRobot::Mode modeOf(msg::RobotMode m) {
  switch (m) {
    case msg::RobotMode::Idle:
      return OtherRobot::Mode::kIdle;
    case msg::RobotMode::Moving:
      return OtherRobot::Mode::kMoving;
    case msg::RobotMode::Waiting:
      return OtherRobot::Mode::kWaiting;
    case msg::RobotMode::Loading:
      return OtherRobot::Mode::kLoading;
    case msg::RobotMode::Charging:
      return OtherRobot::Mode::kCharging;
    case msg::RobotMode::Fault:
      return OtherRobot::Mode::kFault;
    case msg::RobotMode::Blocked:
      break;
  }
  return OtherRobot::Mode::kBlocked;  // (and a value off the enum: none of the modes the rules look at)
}

// The runner's actions are the wire's, in the same order.
static_assert(static_cast<int>(GoalAction::Park) == static_cast<int>(msg::GoalAction::Park) &&
              static_cast<int>(GoalAction::Charge) == static_cast<int>(msg::GoalAction::Charge) &&
              static_cast<int>(GoalAction::Unload) == static_cast<int>(msg::GoalAction::Unload) &&
              static_cast<int>(GoalAction::Load) == static_cast<int>(msg::GoalAction::Load));

TaskGoal goalOf(const msg::Goal& g) {
  return {g.pose, g.station, static_cast<GoalAction>(g.action), g.duration_s, g.load_id};
}

Order orderOf(const msg::TaskAssignment& a) {
  Order o{a.task_id, a.revision, {}, a.paused, a.stamp_ns, a.priority};
  o.goals.reserve(a.goals.size());
  for (const auto& g : a.goals) {
    o.goals.push_back(goalOf(g));
  }
  return o;
}

}  // namespace fleet::agent
