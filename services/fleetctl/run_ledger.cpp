#include "run_ledger.hpp"

#include "round3.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

#include "fleet/core/percentiles.hpp"

namespace fleet::ctl {

namespace {

/// s a docking may take beyond the roadmap's time for the last leg (the timed releases' aim).
constexpr double kDockingSlackS = 2.0;

}  // namespace

RunLedger::RunLedger(std::vector<std::string> robots, std::vector<LedgerStation> stations,
                     std::map<std::string, LedgerTask> tasks, double dockTolerance, double seriesEveryS)
    : robots_(std::move(robots)),
      stations_(std::move(stations)),
      tasks_(std::move(tasks)),
      tolerance_(dockTolerance),
      seriesEvery_(seriesEveryS > 0.0 ? seriesEveryS : 10.0),
      ledgers_(robots_.size()),
      state_(robots_.size()),
      acc_(stations_.size()) {}

int RunLedger::stationAt(Vec2 p) const {
  int best = -1;
  double bestD = tolerance_;
  for (std::size_t s = 0; s < stations_.size(); ++s) {
    const double d = (stations_[s].dock - p).norm();
    if (d <= bestD) {
      best = static_cast<int>(s);
      bestD = d;
    }
  }
  return best;
}

int RunLedger::stationIndex(const std::string& name) const {
  for (std::size_t s = 0; s < stations_.size(); ++s) {
    if (stations_[s].name == name) {
      return static_cast<int>(s);
    }
  }
  return -1;
}

void RunLedger::step(double t, const std::vector<RobotSample>& robots) {
  if (robots.size() != robots_.size() || !std::isfinite(t) || (last_ >= 0.0 && t <= last_)) {
    ++skipped_;
    return;
  }
  // The time since the last step goes to the state the robots and stations had then.
  if (last_ >= 0.0) {
    const double dt = t - last_;
    std::vector<std::size_t> queue(stations_.size(), 0);
    std::vector<bool> occupied(stations_.size(), false);
    for (std::size_t r = 0; r < robots_.size(); ++r) {
      const RobotAcc& a = state_[r];
      ledgers_[r].add(a.activity, dt);
      if (a.docked >= 0) {
        occupied[static_cast<std::size_t>(a.docked)] = true;
      }
      if (a.goal >= 0 && a.goal != a.docked) {
        ++queue[static_cast<std::size_t>(a.goal)];
      }
    }
    for (std::size_t s = 0; s < stations_.size(); ++s) {
      acc_[s].dockedS += occupied[s] ? dt : 0.0;
      acc_[s].queueIntegral += static_cast<double>(queue[s]) * dt;
      acc_[s].queueMax = std::max(acc_[s].queueMax, queue[s]);
    }
    for (; nextSeries_ <= t - first_; nextSeries_ += seriesEvery_) {
      for (std::size_t s = 0; s < stations_.size(); ++s) {
        acc_[s].series.push_back(queue[s]);
      }
    }
  } else {
    first_ = t;
  }
  last_ = t;
  // The new state: activities, docks (arrivals and departures), goals.
  std::vector<int> dockedNow(robots_.size());
  for (std::size_t r = 0; r < robots_.size(); ++r) {
    const RobotSample& x = robots[r];
    RobotAcc& a = state_[r];
    RobotActivity said = RobotActivity::Unset;
    if (!x.activity.empty()) {
      parseRobotActivity(x.activity, said);
    }
    if (said != RobotActivity::Unset) {
      a.activity = said;
      ++saidSteps_;
    } else {
      a.activity = x.charging ? RobotActivity::Charging : activityFromMode(x.mode, !x.task.empty());
      ++derivedSteps_;
    }
    dockedNow[r] = stationAt(x.position);
    for (std::size_t s = 0; s < stations_.size(); ++s) {
      if (stations_[s].hasEntry && (stations_[s].entry - x.position).norm() <= tolerance_) {
        a.atEntry = static_cast<int>(s);
        a.entryT = t;
      }
    }
    if (x.task != a.task) {
      a.task = x.task;
      a.pickedUp = false;
    }
    const auto task = tasks_.find(a.task);
    const int pickup = task == tasks_.end() ? -1 : stationIndex(task->second.pickup);
    const int dropoff = task == tasks_.end() ? -1 : stationIndex(task->second.dropoff);
    if (a.docked >= 0 && a.docked == pickup && dockedNow[r] != pickup) {
      a.pickedUp = true;  // it left its pickup: on to the drop-off
    }
    a.goal = task == tasks_.end() ? -1 : (a.pickedUp ? dropoff : pickup);
  }
  // Queues after the goals are known, for the departures below.
  std::vector<std::size_t> queue(stations_.size(), 0);
  std::vector<std::size_t> inLine(stations_.size(), 0);  // of those, standing in the station's line
  for (std::size_t r = 0; r < robots_.size(); ++r) {
    if (state_[r].goal >= 0 && state_[r].goal != dockedNow[r]) {
      const auto g = static_cast<std::size_t>(state_[r].goal);
      ++queue[g];
      const double reach = stations_[g].lineReach;
      if (reach <= 0.0 || (robots[r].position - stations_[g].dock).norm() <= reach) {
        ++inLine[g];
      }
    }
  }
  for (std::size_t r = 0; r < robots_.size(); ++r) {
    RobotAcc& a = state_[r];
    if (a.docked == dockedNow[r]) {
      continue;
    }
    if (a.docked >= 0) {  // left
      StationAcc& s = acc_[static_cast<std::size_t>(a.docked)];
      s.occupancy.push_back(t - a.dockedSince);
      s.nextQueued = inLine[static_cast<std::size_t>(a.docked)] > 0;
    }
    if (dockedNow[r] >= 0) {  // arrived
      StationAcc& s = acc_[static_cast<std::size_t>(dockedNow[r])];
      ++s.visits;
      if (a.atEntry == dockedNow[r]) {
        s.docking.push_back(t - a.entryT);
      }
      a.atEntry = -1;
      if (s.lastArrival >= 0.0 && s.nextQueued) {
        s.cycles.push_back(t - s.lastArrival);
      }
      s.nextQueued = false;
      s.lastArrival = t;
      a.dockedSince = t;
    }
    a.docked = dockedNow[r];
  }
}

nlohmann::json RunLedger::robotTimeJson() const {
  nlohmann::json cats = nlohmann::json::array();
  for (const auto c : kLedgerActivities) {
    cats.push_back(toString(c));
  }
  ActivityLedger fleet;
  nlohmann::json per = nlohmann::json::object();
  for (std::size_t r = 0; r < robots_.size(); ++r) {
    fleet.add(ledgers_[r]);
    nlohmann::json sec = nlohmann::json::object(), share = nlohmann::json::object();
    for (const auto c : kLedgerActivities) {
      sec[toString(c)] = round3(ledgers_[r].seconds(c));
      share[toString(c)] = round3(ledgers_[r].share(c));
    }
    per[robots_[r]] = {{"seconds", sec}, {"share", share}, {"total_s", round3(ledgers_[r].total())}};
  }
  nlohmann::json fleetShare = nlohmann::json::object();
  for (const auto c : kLedgerActivities) {
    fleetShare[toString(c)] = round3(fleet.share(c));
  }
  const char* source = saidSteps_ == 0 ? "mode" : (derivedSteps_ == 0 ? "activity" : "activity and mode");
  return {{"categories", cats},
          {"source", source},
          {"note",
           "from RobotState.activity where the agent says it, else derived from its mode and task: idle "
           "without a task = no task, idle with a task, waiting and blocked = waiting on another robot, "
           "moving = driving, loading = dwelling, charging = charging, fault = faulted (held by a person "
           "or by safety, and turning/docking, only when the agent says so)"},
          {"robot_seconds", round3(fleet.total())},
          {"fleet", fleetShare},
          {"per_robot", per},
          {"skipped_steps", skipped_}};
}

nlohmann::json RunLedger::stationsJson() const {
  const double run = last_ > first_ ? last_ - first_ : 0.0;
  std::vector<std::size_t> order;
  for (std::size_t s = 0; s < stations_.size(); ++s) {
    if (acc_[s].visits > 0 || acc_[s].queueMax > 0) {
      order.push_back(s);
    }
  }
  std::stable_sort(order.begin(), order.end(),
                   [&](std::size_t a, std::size_t b) { return acc_[a].dockedS > acc_[b].dockedS; });
  nlohmann::json out = nlohmann::json::array();
  for (const std::size_t s : order) {
    const StationAcc& a = acc_[s];
    const Percentiles c = percentiles(a.cycles);
    const Percentiles o = percentiles(a.occupancy);
    out.push_back({{"name", stations_[s].name},
                   {"visits", a.visits},
                   {"utilisation", run > 0.0 ? round3(a.dockedS / run) : 0.0},
                   {"docked_s", round3(a.dockedS)},
                   {"queue_mean", run > 0.0 ? round3(a.queueIntegral / run) : 0.0},
                   {"queue_max", a.queueMax},
                   {"queue_every_s", seriesEvery_},
                   {"queue_series", a.series},
                   {"cycles", c.count},
                   {"cycle_p50_s", round3(c.p50)},
                   {"cycle_p90_s", round3(c.p90)},
                   {"occupancy_p50_s", round3(o.p50)},
                   {"occupancy_p90_s", round3(o.p90)}});
    if (stations_[s].hasEntry) {
      const Percentiles d = percentiles(a.docking);
      const double model = stations_[s].dockModelS;
      const auto over = std::count_if(a.docking.begin(), a.docking.end(),
                                      [&](double x) { return x > model + kDockingSlackS; });
      out.back().update(
          {{"dock_model_s", round3(model)},
           {"dockings", d.count},
           {"docking_p50_s", round3(d.p50)},
           {"docking_p90_s", round3(d.p90)},
           {"docking_max_s",
            round3(a.docking.empty() ? 0.0 : *std::max_element(a.docking.begin(), a.docking.end()))},
           {"dockings_over_model", over}});
    }
  }
  return out;
}

std::vector<std::string> ledgerLines(const nlohmann::json& rt, const nlohmann::json& stations) {
  std::vector<std::string> out;
  if (rt.is_object() && rt.contains("fleet")) {
    std::string line = "robot time (fleet, from " + rt.value("source", std::string("?")) + "):";
    char buf[96];
    for (const auto& c : rt["categories"]) {
      const std::string name = c.get<std::string>();
      std::snprintf(buf, sizeof buf, " %s %.0f %%", name.c_str(), 100.0 * rt["fleet"].value(name, 0.0));
      line += buf;
    }
    out.push_back(line);
  }
  if (stations.is_array() && !stations.empty()) {
    const auto& s = stations.front();
    char buf[320];
    std::snprintf(buf, sizeof buf,
                  "stations: busiest %s utilisation %.0f %%, %d visits, queue mean %.2f max %d, dock cycle "
                  "p50 %.1f s p90 %.1f s (%d cycles with the next robot in line); %zu stations visited",
                  s.value("name", std::string("?")).c_str(), 100.0 * s.value("utilisation", 0.0),
                  s.value("visits", 0), s.value("queue_mean", 0.0), s.value("queue_max", 0),
                  s.value("cycle_p50_s", 0.0), s.value("cycle_p90_s", 0.0), s.value("cycles", 0),
                  stations.size());
    out.push_back(buf);
    // Docking against the roadmap's time for the last leg, over every station that has an entry.
    std::vector<std::string> over;
    int dockings = 0;
    int late = 0;
    double worst = 0.0;
    for (const auto& st : stations) {
      if (!st.contains("dockings")) {
        continue;
      }
      dockings += st.value("dockings", 0);
      late += st.value("dockings_over_model", 0);
      worst = std::max(worst, st.value("docking_max_s", 0.0) - st.value("dock_model_s", 0.0));
    }
    if (dockings > 0) {
      std::snprintf(buf, sizeof buf,
                    "docking: %d of %d dockings within the roadmap's time for the last leg + %.0f s; the "
                    "latest %.1f s over it",
                    dockings - late, dockings, kDockingSlackS, worst);
      out.push_back(buf);
    }
  }
  return out;
}

}  // namespace fleet::ctl
