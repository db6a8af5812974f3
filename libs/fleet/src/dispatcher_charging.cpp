// Charge tasks: a low idle robot is sent to charge, and a charge task ends when the robot is full.

#include "fleet/fleet/dispatcher.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "dispatcher_detail.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/fleet/errors.hpp"

namespace fleet {

using dispatcher_detail::happyPath;

namespace {

// RobotState carries the battery as a float: 0.9f reads 0.8999999762 as a double.
constexpr double kBatteryEps = 1e-6;

std::string chargeTaskId(const std::string& robot, std::int64_t nowNs) {
  std::string id = "charge.";
  id += std::to_string(nowNs);
  id += '.';
  if (id.size() + robot.size() <= kMaxIdLength) {
    id += robot;
  } else {
    id += std::to_string(std::hash<std::string>{}(robot));
  }
  return id;
}

}  // namespace
void Dispatcher::completeCharged(std::int64_t nowNs, DispatchResult& out) {
  std::vector<TransitionRequest> steps;
  std::map<std::string, std::string, std::less<>> robotOf;  // task id -> robot
  for (const auto& [id, r] : open_) {
    if (r.task.kind != TaskKind::Charge || !isActive(r.state) || r.paused) {
      continue;
    }
    const RobotInfo* info = registry_.find(r.robotId);
    const Station* st = stations_.find(r.task.station);
    if (info == nullptr || info->lost || info->taskId != id || st == nullptr ||
        info->battery + kBatteryEps < cfg_.chargeUntil ||
        distance(info->pose.position(), st->pose.position()) > cfg_.chargeReach) {
      continue;
    }
    // Steps the robot did not report (a lost status sample) are filled in, as in onTaskStatus.
    const auto path = happyPath(r.task.kind);
    for (auto s = std::find(path.begin(), path.end(), r.state) + 1; s < path.end(); ++s) {
      char why[64];
      std::snprintf(why, sizeof why, "charged to %.2f", info->battery);
      steps.push_back(
          {id, *s, r.robotId, *s == TaskState::Done ? std::string(why) : "implied by the charge", nowNs, {}});
    }
    robotOf.emplace(id, r.robotId);
  }
  if (steps.empty()) {
    return;
  }
  auto results = store_.transitionBatch(steps);
  for (auto& res : results) {
    if (!res) {
      out.errors.push_back(res.error());
      continue;
    }
    if (res->state == TaskState::Done) {
      const std::string& robot = robotOf.at(res->task.id);
      ++counters_.charged;
      registry_.clearTask(robot);
      out.revoked.push_back(robot);  // stop dwelling at the charger
    }
    applied(*res, out);
  }
}

void Dispatcher::chargeLowRobots(std::int64_t nowNs, DispatchResult& out) {
  const auto chargers = stations_.ofKind(StationKind::Charging);
  for (const auto& r : registry_.idleRobots()) {
    if (r.battery >= cfg_.policy.batteryThreshold || robotHeld(r.id)) {
      continue;
    }
    const bool pending = std::any_of(open_.begin(), open_.end(), [&](const auto& kv) {
      return kv.second.task.robot == r.id && kv.second.task.kind == TaskKind::Charge &&
             isWaiting(kv.second.state);
    });
    if (pending) {
      continue;
    }
    Task t;
    t.id = chargeTaskId(r.id, nowNs);
    t.kind = TaskKind::Charge;
    t.robot = r.id;
    // No station: the charger is chosen when the task is assigned (in this tick, the task being
    // the robot's own): the nearest free one, so that low robots do not queue at one charger while
    // another stands free, and none is sent to a charger another robot is already on its way to.
    const bool reachable = std::any_of(chargers.begin(), chargers.end(), [&](const Station* s) {
      Task cand = t;
      cand.station = s->name;
      return std::isfinite(travel_(cand)(r));
    });
    if (!reachable) {
      out.errors.push_back(
          Error{errc::kNotFound, "robot " + r.id + " is low but no charging station is reachable"});
      continue;
    }
    auto res = store_.submit(t, nowNs);
    if (!res) {
      out.errors.push_back(res.error());
      continue;
    }
    ++counters_.submitted;
    applied(res->record, out);
  }
}

}  // namespace fleet
