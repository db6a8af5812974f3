#include "fleet/fleet/dispatcher.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "dispatcher_detail.hpp"
#include "station_lines.hpp"

namespace fleet {

using dispatcher_detail::stationsOf;

void Dispatcher::allocate(std::int64_t nowNs, DispatchResult& out) {
  std::vector<Task> waiting;
  bool choosing = false;
  for (const auto& [id, r] : open_) {
    if (isWaiting(r.state) && !r.paused && closedStationOf(r.task) == nullptr) {
      waiting.push_back(r.task);
      choosing = choosing || needsStation(r.task);
    }
  }
  if (!choosing) {
    assignWaiting(std::move(waiting), nullptr, nowNs, out);
    return;
  }
  std::set<std::string, std::less<>> targeted;
  for (const auto& [id, r] : open_) {
    if (isActive(r.state)) {
      for (const std::string* s : stationsOf(r.task)) {
        targeted.insert(*s);
      }
    }
  }
  const auto robots = registry_.all();
  StationChooser chooser(stations_, std::move(targeted), robots, cfg_.standReach);
  assignWaiting(std::move(waiting), &chooser, nowNs, out);
  noteStationWaits(chooser, nowNs, out);
}

void Dispatcher::assignWaiting(std::vector<Task> waiting, StationChooser* chooser, std::int64_t nowNs,
                               DispatchResult& out) {
  auto idle = registry_.idleRobots();
  std::erase_if(idle, [&](const RobotInfo& r) {
    const auto it = failStreak_.find(r.id);
    return robotHeld(r.id) || (it != failStreak_.end() && it->second.holdUntilNs > nowNs);
  });
  heldInLines_ = 0;
  if (waiting.empty() || idle.empty()) {
    return;
  }
  if (cfg_.stationLoad == StationLoad::Arrival && cfg_.stationTimes.known()) {
    noteAdmissionWaits(admitByArrival(waiting, idle), nowNs, out);
    if (waiting.empty()) {
      return;
    }
  } else if (cfg_.stationCapacity > 0 || !cfg_.stationCapacities.empty()) {
    const auto held = admitByStationCapacity(waiting);
    // Only those a wider line could admit: a fixed capacity (a parking place) is not scaled.
    heldInLines_ =
        static_cast<std::size_t>(std::count_if(held.begin(), held.end(), [&](const HeldAtStation& h) {
          return cfg_.stationCapacities.count(h.station) > 0;
        }));
    noteAdmissionWaits(held, nowNs, out);
    if (waiting.empty()) {
      return;
    }
  }
  if (waiting.size() > cfg_.maxCandidates) {
    auto key = [](const Task& t) {
      return std::tuple(t.robot.empty(), -t.priority, t.deadlineNs > 0 ? t.deadlineNs : INT64_MAX,
                        t.createdNs);
    };
    const auto keep = static_cast<std::ptrdiff_t>(cfg_.maxCandidates);
    std::partial_sort(waiting.begin(), waiting.begin() + keep, waiting.end(),
                      [&](const Task& a, const Task& b) { return key(a) < key(b); });
    waiting.resize(cfg_.maxCandidates);
  }
  const auto small = static_cast<double>(std::min(waiting.size(), idle.size()));
  const auto big = static_cast<double>(std::max(waiting.size(), idle.size()));
  const Allocator& alloc = small * small * big > cfg_.hungarianMaxWork
                               ? static_cast<const Allocator&>(greedy_)
                               : static_cast<const Allocator&>(hungarian_);
  TravelModel travel = travel_;
  if (chooser != nullptr) {
    // A task without a station costs what the trip to the station the robot would get costs;
    // with no free station it can reach, the robot cannot take it.
    travel = [this, chooser](const Task& t) -> RobotTravel {
      if (!needsStation(t)) {
        return travel_(t);
      }
      auto options = std::make_shared<const StationChooser::Options>(chooser->options(t, travel_));
      return [options, chooser](const RobotInfo& r) { return chooser->best(*options, r).travelS; };
    };
  }
  if (cfg_.stationTimes.known()) {
    // Expected queue wait (docs/algorithms.md, "Assignment: expected queue wait"): a transport task
    // costs a robot its travel plus its wait in the task's two lines, so of two tasks as near the
    // one whose stations are free goes first, and a robot that will get there after a line has
    // cleared pays nothing for it. The lines as booked now (robots with a task), each robot's
    // arrival at a pickup computed once.
    auto lines = std::make_shared<StationLines>(bookLines());
    auto arrivals = std::make_shared<std::unordered_map<std::string, double>>();
    travel = [this, lines, arrivals, base = std::move(travel)](const Task& t) -> RobotTravel {
      RobotTravel inner = base(t);
      if (t.kind != TaskKind::Transport) {
        return inner;
      }
      return [this, lines, arrivals, inner, &t](const RobotInfo& r) {
        const double c = inner(r);
        if (!std::isfinite(c)) {
          return c;
        }
        auto [it, fresh] = arrivals->try_emplace(r.id + '\n' + t.pickup, 0.0);
        if (fresh) {
          it->second = cfg_.stationTimes.toStation(r.pose.position(), t.pickup);
        }
        return c + lines->expectedWait(t, it->second);
      };
    };
  }
  if (!failedBy_.empty() && idle.size() > 1) {
    // A retry goes to another robot: whatever held the last one (boxed in, a bad pose estimate)
    // is likely to hold it again. With a single idle robot it may take the task back.
    travel = [this, base = std::move(travel)](const Task& t) -> RobotTravel {
      RobotTravel inner = base(t);
      const auto it = failedBy_.find(t.id);
      if (it == failedBy_.end()) {
        return inner;
      }
      return [inner, who = it->second](const RobotInfo& r) { return r.id == who ? kInfeasible : inner(r); };
    };
  }
  const auto assignments = alloc.assign(waiting, idle, travel, nowNs);
  // The stations of the assigned tasks that need one. Two such tasks may have been costed against
  // the same station: the robot nearest to its best one chooses first, and each choice is taken at
  // once. A task left without a station stays in the queue.
  std::vector<std::string> chosen(assignments.size());
  std::vector<bool> dropped(assignments.size(), false);
  if (chooser != nullptr) {
    std::vector<StationChooser::Options> options(assignments.size());
    std::vector<std::tuple<bool, double, std::size_t>> order;
    for (std::size_t k = 0; k < assignments.size(); ++k) {
      const Task& t = waiting[assignments[k].task];
      if (needsStation(t)) {
        options[k] = chooser->options(t, travel_);
        const auto pick = chooser->best(options[k], idle[assignments[k].robot]);
        order.emplace_back(pick.blocked, pick.travelS, k);
      }
    }
    std::sort(order.begin(), order.end());
    for (const auto& [blocked, travelS, k] : order) {
      const auto pick = chooser->best(options[k], idle[assignments[k].robot]);
      if (pick.station == nullptr) {
        dropped[k] = true;
        continue;
      }
      chosen[k] = pick.station->name;
      chooser->take(pick.station->name);
    }
  }
  std::vector<TransitionRequest> reqs;
  reqs.reserve(assignments.size());
  for (std::size_t k = 0; k < assignments.size(); ++k) {
    if (dropped[k]) {
      continue;
    }
    const Task& t = waiting[assignments[k].task];
    std::string why = "allocated";
    if (!chosen[k].empty()) {
      why += " to the nearest free " + std::string(toString(targetKind(t.kind))) + " station " + chosen[k];
    }
    reqs.push_back(
        {t.id, TaskState::Assigned, idle[assignments[k].robot].id, std::move(why), nowNs, chosen[k]});
  }
  auto results = store_.transitionBatch(reqs);
  for (std::size_t k = 0; k < results.size(); ++k) {
    if (!results[k]) {
      out.errors.push_back(results[k].error());
      continue;
    }
    registry_.setTask(reqs[k].robotId, reqs[k].taskId);
    out.assignments.push_back({reqs[k].robotId, results[k]->task, results[k]->revision});
    applied(*results[k], out);
  }
}

void Dispatcher::noteStationWaits(const StationChooser& chooser, std::int64_t nowNs, DispatchResult& out) {
  static constexpr std::string_view kWaiting = "waiting for a free ";
  std::map<StationKind, std::size_t> freeOf;
  for (auto& [id, r] : open_) {
    if (!isWaiting(r.state) || r.paused || !needsStation(r.task)) {
      continue;
    }
    const StationKind kind = targetKind(r.task.kind);
    auto [free, fresh] = freeOf.try_emplace(kind, 0);
    if (fresh) {
      free->second = chooser.freeOfKind(kind);
    }
    const std::string what(toString(kind));
    std::string why;
    if (free->second == 0) {
      const std::size_t n = chooser.countOfKind(kind);
      why = std::string(kWaiting) + what +
            " station: " + (n == 1 ? std::string("the only one is") : "all " + std::to_string(n) + " are") +
            " taken by other tasks";
    } else if (r.reason.starts_with(kWaiting)) {
      why = "a " + what + " station is free again; waiting for a robot";
    }
    if (why.empty() || why == r.reason) {
      continue;
    }
    auto res = store_.setWaitReason(id, why, nowNs);
    if (!res) {
      out.errors.push_back(res.error());
      continue;
    }
    r.reason = res->reason;
    r.updatedNs = res->updatedNs;
    out.events.push_back({id, r.state, "", r.reason, nowNs, "", currentEta(r, nowNs)});
  }
}

}  // namespace fleet
