// Admission by predicted arrival (docs/algorithms.md, "Admission by predicted arrival"): a waiting
// task is admitted when its pickup's line has a place for the time the nearest idle robot could get
// there, and its drop-off's line one for the time it would have loaded and driven on. Robots with
// a task are booked in the lines they are bound for at their own predicted arrival, from where they
// stand now, so a robot held up is booked later, not lost. The line's arithmetic is
// fleet/core/station_slots.hpp; the times are the roadmap's free-flow ones (StationTimes).

#include <algorithm>
#include <limits>
#include <string>
#include <unordered_map>
#include <vector>

#include "fleet/core/clock.hpp"
#include "fleet/core/station_slots.hpp"
#include "fleet/fleet/dispatcher.hpp"

#include "dispatcher_detail.hpp"
#include "station_lines.hpp"

namespace fleet {

namespace {
constexpr double kNever = std::numeric_limits<double>::infinity();
}  // namespace

StationLines::Line& StationLines::line(const std::string& s) {
  auto [it, fresh] = lines_.try_emplace(s);
  if (fresh) {
    it->second.move = times_.dockMove(s);
    it->second.slots = capacity_(s);
  }
  return it->second;
}

StationLines Dispatcher::bookLines() const {
  const StationTimes& times = cfg_.stationTimes;
  StationLines lines(times, [this](const std::string& s) { return capacityOf(s); });
  // Robots with a transport task not yet loaded: booked at their pickup first; their drop-off
  // arrival follows from when the pickup's line will have served them.
  struct Loading {
    const Task* task;
    double arrival;
  };
  std::vector<Loading> loading;
  for (const auto& [id, r] : open_) {
    if (!isActive(r.state)) {
      continue;
    }
    const RobotInfo* robot = registry_.find(r.robotId);
    if (r.task.kind != TaskKind::Transport || robot == nullptr) {
      for (const std::string* s : taskStops(r.task)) {  // other tasks: every stop, from now on
        lines.line(*s).arrivals.push_back(0.0);
      }
      continue;
    }
    const Vec2 at = robot->pose.position();
    if (r.state == TaskState::Delivering || r.state == TaskState::Unloading) {
      lines.line(r.task.dropoff).arrivals.push_back(times.toStation(at, r.task.dropoff));
    } else {
      const double a = times.toStation(at, r.task.pickup);
      lines.line(r.task.pickup).arrivals.push_back(a);
      loading.push_back({&r.task, a});
    }
  }
  for (const auto& [t, a] : loading) {
    auto& p = lines.line(t->pickup);
    std::vector<double> others = p.arrivals;
    if (const auto it = std::find(others.begin(), others.end(), a); it != others.end()) {
      others.erase(it);
    }
    const double leave = offerSlot(others, a, p.move + nsToSec(t->loadNs), 0).leave;
    lines.line(t->dropoff).arrivals.push_back(leave + times.between(t->pickup, t->dropoff));
  }
  return lines;
}

std::vector<Dispatcher::HeldAtStation> Dispatcher::admitByArrival(std::vector<Task>& waiting,
                                                                  const std::vector<RobotInfo>& idle) const {
  const StationTimes& times = cfg_.stationTimes;
  StationLines lines = bookLines();
  const auto line = [&](const std::string& s) -> StationLines::Line& { return lines.line(s); };

  // The nearest idle robot's arrival at each pickup, once per station.
  std::unordered_map<std::string, double> nearest;
  const auto soonest = [&](const std::string& s) {
    auto [it, fresh] = nearest.try_emplace(s, kNever);
    if (fresh) {
      for (const RobotInfo& r : idle) {
        it->second = std::min(it->second, times.toStation(r.pose.position(), s));
      }
    }
    return it->second;
  };
  dispatcher_detail::oldestFirst(waiting);
  std::vector<Task> admitted;
  std::vector<HeldAtStation> held;
  for (auto& t : waiting) {
    if (admitted.size() >= idle.size()) {
      // No robot for it this dispatch: it waits for one, not for a place. A reason it was given
      // when a place was what it lacked would stay until it is looked at again: taken back (a
      // HeldAtStation without a station). Others are left alone (no store write).
      const auto it = open_.find(t.id);
      if (it != open_.end() && it->second.reason.find(dispatcher_detail::kPlaceInLine) != std::string::npos) {
        held.push_back({t.id, "", 0, false});
      }
      continue;
    }
    if (!t.robot.empty()) {  // a robot's own charge task is never held back
      admitted.push_back(std::move(t));
      continue;
    }
    if (t.kind != TaskKind::Transport) {
      // Other kinds hold every stop from now on, as they are booked once active.
      const auto stops = taskStops(t);
      const auto full = std::find_if(stops.begin(), stops.end(), [&](const std::string* s) {
        const auto& l = line(*s);
        return !offerSlot(l.arrivals, 0.0, l.move, l.slots).admitted;
      });
      if (full != stops.end()) {
        held.push_back({t.id, **full, line(**full).slots});
        continue;
      }
      for (const std::string* s : stops) {
        line(*s).arrivals.push_back(0.0);
      }
      admitted.push_back(std::move(t));
      continue;
    }
    auto& p = line(t.pickup);
    const double a = soonest(t.pickup);
    const SlotOffer atPickup = offerSlot(p.arrivals, a, p.move + nsToSec(t.loadNs), p.slots);
    if (!atPickup.admitted) {
      held.push_back({t.id, t.pickup, p.slots, true});
      continue;
    }
    auto& d = line(t.dropoff);
    const double ad = atPickup.leave + times.between(t.pickup, t.dropoff);
    if (!offerSlot(d.arrivals, ad, d.move + nsToSec(t.unloadNs), d.slots).admitted) {
      held.push_back({t.id, t.dropoff, d.slots, true});
      continue;
    }
    p.arrivals.push_back(a);
    d.arrivals.push_back(ad);
    admitted.push_back(std::move(t));
  }
  waiting = std::move(admitted);
  return held;
}

}  // namespace fleet
