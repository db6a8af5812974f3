#include "fleet/core/robot_activity.hpp"

#include <cmath>

namespace fleet {

namespace {
constexpr std::array<const char*, kRobotActivities> kNames = {
    "unset",          "no_task",        "driving",  "turning_docking", "dwelling", "waiting_on_robot",
    "held_by_person", "held_by_safety", "charging", "faulted"};
}  // namespace

const char* toString(RobotActivity a) {
  const auto i = static_cast<std::size_t>(a);
  return i < kNames.size() ? kNames[i] : "unset";
}

bool parseRobotActivity(std::string_view name, RobotActivity& out) {
  for (std::size_t i = 0; i < kNames.size(); ++i) {
    if (name == kNames[i]) {
      out = static_cast<RobotActivity>(i);
      return true;
    }
  }
  return false;
}

RobotActivity activityFromMode(std::string_view mode, bool hasTask) {
  if (mode == "moving") {
    return RobotActivity::Driving;
  }
  if (mode == "loading") {
    return RobotActivity::Dwelling;
  }
  if (mode == "charging") {
    return RobotActivity::Charging;
  }
  if (mode == "fault") {
    return RobotActivity::Faulted;
  }
  if (mode == "waiting" || mode == "blocked") {
    return RobotActivity::WaitingOnRobot;
  }
  if (mode == "idle" && hasTask) {
    return RobotActivity::WaitingOnRobot;
  }
  return RobotActivity::NoTask;
}

void ActivityLedger::add(RobotActivity a, double seconds) {
  if (!std::isfinite(seconds) || seconds <= 0.0) {
    return;
  }
  if (a == RobotActivity::Unset || static_cast<std::size_t>(a) >= kRobotActivities) {
    a = RobotActivity::NoTask;
  }
  s_[static_cast<std::size_t>(a)] += seconds;
}

void ActivityLedger::add(const ActivityLedger& other) {
  for (std::size_t i = 0; i < kRobotActivities; ++i) {
    s_[i] += other.s_[i];
  }
}

double ActivityLedger::total() const {
  double t = 0.0;
  for (const double x : s_) {
    t += x;
  }
  return t;
}

double ActivityLedger::share(RobotActivity a) const {
  const double t = total();
  return t > 0.0 ? seconds(a) / t : 0.0;
}

}  // namespace fleet
