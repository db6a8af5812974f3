#include "fleet/core/admission_governor.hpp"

#include <algorithm>
#include <cmath>

namespace fleet {

bool AdmissionGovernor::tick(double elapsedS, bool tasksHeld) {
  held_ = held_ || tasksHeld;
  if (std::isfinite(elapsedS) && elapsedS > 0.0) {
    sinceStepS_ += elapsedS;
  }
  if (sinceStepS_ < c_.windowS) {
    return false;
  }
  if (window_.total() <= 0.0) {  // nobody reported: nothing to decide on, start a new window
    sinceStepS_ = 0.0;
    held_ = false;
    return false;
  }
  lastWaiting_ = window_.share(RobotActivity::WaitingOnRobot);
  lastIdle_ = window_.share(RobotActivity::NoTask);
  const double before = k_;
  if (lastWaiting_ > c_.waitHigh) {
    k_ = std::max(1.0, k_ - c_.step);
  } else if (lastWaiting_ < c_.waitLow && lastIdle_ > c_.idleLeast && held_) {
    k_ = std::min(c_.maxScale, k_ + c_.step);
  }
  window_ = {};
  sinceStepS_ = 0.0;
  held_ = false;
  return k_ != before;
}

std::size_t AdmissionGovernor::slots(std::size_t places) const {
  return static_cast<std::size_t>(std::floor(k_ * static_cast<double>(places) + 1e-9));
}

}  // namespace fleet
