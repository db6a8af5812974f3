// The dispatcher's side of the completion estimates (TaskEta): the estimate of each task event,
// and the waiting tasks ahead of a queued one.

#include "fleet/fleet/dispatcher.hpp"

#include <algorithm>
#include <cstdint>

namespace fleet {

void Dispatcher::countWaiting(const TaskRecord& r, int delta) {
  auto& n = waitingByPriority_[r.task.priority];
  n = delta > 0 ? n + 1 : (n > 0 ? n - 1 : 0);
  if (n == 0) {
    waitingByPriority_.erase(r.task.priority);
  }
}

std::int64_t Dispatcher::etaOf(const TaskRecord& r) {
  const double dwellS = static_cast<double>(taskDwellNs(r.task)) / 1e9;
  const std::int64_t now = r.updatedNs;
  switch (r.state) {
    case TaskState::Assigned: {
      const RobotInfo* robot = registry_.find(r.robotId);
      return eta_.assigned(r.task.id, now, robot != nullptr ? travel_(r.task)(*robot) + dwellS : kInfeasible);
    }
    case TaskState::EnRoute:
    case TaskState::Loading:
    case TaskState::Delivering:
    case TaskState::Unloading:
      return eta_.active(r.task.id, now);
    case TaskState::Done:
      eta_.ended(r.task.id, now, true);
      return now;
    case TaskState::Failed:
    case TaskState::Cancelled:
    case TaskState::Rejected:  // never a stored task's state
      eta_.ended(r.task.id, now, false);
      return 0;
    case TaskState::Queued:
    case TaskState::Requeued:
      eta_.ended(r.task.id, now, false);
      return waitingEta(r, now);
  }
  return 0;
}

std::int64_t Dispatcher::currentEta(const TaskRecord& r, std::int64_t nowNs) const {
  if (isActive(r.state)) {
    return eta_.active(r.task.id, nowNs);
  }
  return isWaiting(r.state) && !r.paused ? waitingEta(r, nowNs) : 0;
}

std::int64_t Dispatcher::waitingEta(const TaskRecord& r, std::int64_t nowNs) const {
  // Ahead of it: every waiting task of a higher or the same priority (it joins its own last).
  std::size_t ahead = 0;
  for (const auto& [priority, n] : waitingByPriority_) {
    if (priority < r.task.priority) {
      break;
    }
    ahead += n;
  }
  const double dwellS = static_cast<double>(taskDwellNs(r.task)) / 1e9;
  double predicted = eta_.typical();
  if (predicted <= 0.0) {
    // Before the first assignment: the nearest robot's way.
    predicted = kInfeasible;
    const auto travel = travel_(r.task);
    for (const auto& robot : registry_.all()) {
      if (!robot.lost) {
        predicted = std::min(predicted, travel(robot) + dwellS);
      }
    }
  }
  // The robots that may take it: online and not held by the operator (a held robot is given no
  // task). None: no estimate.
  std::size_t robots = registry_.onlineCount();
  for (const auto& id : held_) {
    const RobotInfo* robot = registry_.find(id);
    if (robot != nullptr && !robot->lost && robots > 0) {
      --robots;
    }
  }
  return eta_.waiting(nowNs, ahead, robots, predicted);
}

}  // namespace fleet
