#pragma once

// The agent's side of the wire: the DDS messages it takes in, as its parts' own types, and the task
// stages it reports, as the wire's.

#include "fleet/messages/messages.hpp"
#include "localizer.hpp"
#include "other_robot.hpp"
#include "task_runner.hpp"

namespace fleet::agent {

/// A sensor frame as the localizer reads it.
SensorReading readingOf(const msg::SensorFrame& f);
/// Another robot's reported mode.
OtherRobot::Mode modeOf(msg::RobotMode m);
TaskGoal goalOf(const msg::Goal& g);
/// An assignment as the task runner takes it.
Order orderOf(const msg::TaskAssignment& a);

}  // namespace fleet::agent
