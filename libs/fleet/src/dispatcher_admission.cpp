// Station admission: waiting tasks held back while a station they need has as many active tasks
// as its capacity allows, each saying which line holds it (and when it is past its deadline).

#include "fleet/fleet/dispatcher.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>
#include <vector>

#include "dispatcher_detail.hpp"

namespace fleet {

using dispatcher_detail::stationsOf;

namespace {
// The stations an active task loads now when load is counted by phase: where its robot is going.
std::vector<const std::string*> phaseStationsOf(const Task& t, TaskState state) {
  // Its pickup until it has loaded there, its drop-off for the whole task: a loaded robot must not
  // find its drop-off's line full (docs/algorithms.md, "Traffic: stations as servers").
  // A multi-stop task reports no loading phase: all of its stops count until it ends.
  const bool delivering = state == TaskState::Delivering || state == TaskState::Unloading;
  auto s = taskStops(t);
  std::erase_if(s, [&](const std::string* n) { return delivering && n == &t.pickup; });
  return s;
}
}  // namespace

std::vector<Dispatcher::HeldAtStation> Dispatcher::admitByStationCapacity(std::vector<Task>& waiting) const {
  const bool byPhase = cfg_.stationLoad != StationLoad::Task;
  std::unordered_map<std::string, std::size_t> load;
  for (const auto& [id, r] : open_) {
    if (isActive(r.state)) {
      for (const std::string* s : byPhase ? phaseStationsOf(r.task, r.state) : stationsOf(r.task)) {
        ++load[*s];
      }
    }
  }
  dispatcher_detail::oldestFirst(waiting);
  std::vector<Task> admitted;
  std::vector<HeldAtStation> held;
  for (auto& t : waiting) {
    const auto stations = byPhase ? phaseStationsOf(t, TaskState::Assigned) : stationsOf(t);
    // A robot's own charge task is never held back: its battery does not wait for the queue.
    const auto full = t.robot.empty() ? std::find_if(stations.begin(), stations.end(),
                                                     [&](const std::string* s) {
                                                       const std::size_t cap = capacityOf(*s);
                                                       return cap > 0 && load[*s] >= cap;
                                                     })
                                      : stations.end();
    if (full == stations.end()) {
      for (const std::string* s : stations) {
        ++load[*s];
      }
      admitted.push_back(std::move(t));
    } else {
      // The line's own places in the reason (not the governor's scaled slots): what an operator
      // sees on the site, and a reason that does not change, with a store write, at every step.
      const auto own = cfg_.stationCapacities.find(**full);
      held.push_back({t.id, **full, own != cfg_.stationCapacities.end() ? own->second : capacityOf(**full)});
    }
  }
  waiting = std::move(admitted);
  return held;
}

std::size_t Dispatcher::capacityOf(const std::string& station) const {
  const auto it = cfg_.stationCapacities.find(station);
  if (it == cfg_.stationCapacities.end()) {
    return cfg_.stationCapacity;
  }
  return static_cast<std::size_t>(std::floor(lineScale_ * static_cast<double>(it->second) + 1e-9));
}

void Dispatcher::setLineScale(double k) {
  lineScale_ = std::isfinite(k) ? std::max(1.0, k) : 1.0;
}

void Dispatcher::noteAdmissionWaits(const std::vector<HeldAtStation>& held, std::int64_t nowNs,
                                    DispatchResult& out) {
  for (const auto& h : held) {
    const auto it = open_.find(h.taskId);
    if (it == open_.end() || !isWaiting(it->second.state) || it->second.paused) {
      continue;
    }
    auto& r = it->second;
    const bool late = r.task.deadlineNs > 0 && nowNs > r.task.deadlineNs;
    const std::string waiting = late ? "past its deadline and still waiting" : "waiting";
    const std::string why =
        h.station.empty()
            ? waiting + " for a robot (every idle one has an older or more urgent task)"
            : waiting + std::string(dispatcher_detail::kPlaceInLine) + h.station + "'s line (it holds " +
                  std::to_string(h.capacity) +
                  (h.byArrival ? ", all taken when a robot could get there)" : ", all taken by other tasks)");
    if (why == r.reason) {
      continue;  // said already: no store write, no event
    }
    auto res = store_.setWaitReason(h.taskId, why.substr(0, 255), nowNs);
    if (!res) {
      out.errors.push_back(res.error());
      continue;
    }
    r.reason = res->reason;
    r.updatedNs = res->updatedNs;
    out.events.push_back({h.taskId, r.state, "", r.reason, nowNs, "", currentEta(r, nowNs)});
  }
}

}  // namespace fleet
