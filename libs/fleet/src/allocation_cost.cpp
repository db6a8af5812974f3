#include <algorithm>
#include <cmath>

#include "fleet/core/clock.hpp"
#include "fleet/fleet/allocator.hpp"

namespace fleet {

bool eligible(const RobotInfo& r, const Task& t, const AllocationPolicy& p) {
  if (r.lost || !r.taskId.empty()) {
    return false;
  }
  if (!t.robot.empty() && t.robot != r.id) {
    return false;
  }
  if (r.battery < p.batteryThreshold && t.kind != TaskKind::Charge) {
    return false;
  }
  return true;
}

double pairCost(const Task& t, double travelS, const AllocationPolicy& p, std::int64_t nowNs) {
  if (t.deadlineNs <= 0) {
    return travelS;
  }
  const double finish = nsToSec(nowNs) + travelS + nsToSec(taskDwellNs(t));
  return travelS + p.latenessWeight * std::max(0.0, finish - nsToSec(t.deadlineNs));
}

TravelModel perPair(TravelCost f) {
  return [f = std::move(f)](const Task& t) -> RobotTravel {
    return [&f, &t](const RobotInfo& r) { return f(r, t); };
  };
}

CostMatrix effectiveCosts(std::span<const Task> tasks, std::span<const RobotInfo> robots,
                          const TravelModel& travel, const AllocationPolicy& p, std::int64_t nowNs,
                          CostMatrix* travelOut) {
  CostMatrix c(tasks.size(), robots.size(), kInfeasible);
  if (travelOut != nullptr) {
    *travelOut = CostMatrix(tasks.size(), robots.size(), kInfeasible);
  }
  const double now = nsToSec(nowNs);
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    const Task& t = tasks[i];
    const double handling = nsToSec(taskDwellNs(t));
    const double deadline = t.deadlineNs > 0 ? nsToSec(t.deadlineNs) : kInfeasible;
    double minTravel = kInfeasible;
    const RobotTravel fromRobot = travel(t);
    for (std::size_t j = 0; j < robots.size(); ++j) {
      if (!eligible(robots[j], t, p)) {
        continue;
      }
      const double d = fromRobot(robots[j]);
      if (!std::isfinite(d)) {
        continue;
      }
      c.at(i, j) = pairCost(t, d, p, nowNs);
      if (travelOut != nullptr) {
        travelOut->at(i, j) = d;
      }
      minTravel = std::min(minTravel, d);
    }
    if (!std::isfinite(minTravel)) {
      continue;  // no robot can take it: the whole row stays +inf
    }
    const double deferredLate = std::max(0.0, now + p.deferHorizonS + minTravel + handling - deadline);
    const double age = t.createdNs > 0 ? std::max(0.0, now - nsToSec(t.createdNs)) : 0.0;
    const double skip = p.priorityWeightS * static_cast<double>(t.priority) +
                        p.latenessWeight * deferredLate + p.ageWeight * age;
    for (std::size_t j = 0; j < robots.size(); ++j) {
      c.at(i, j) -= skip;  // +inf stays +inf
    }
  }
  return c;
}

}  // namespace fleet
