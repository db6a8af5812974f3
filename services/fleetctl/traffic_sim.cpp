#include "traffic_sim.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <map>
#include <nlohmann/json.hpp>
#include <sstream>
#include <utility>
#include <vector>

#include "fleet/core/config.hpp"
#include "fleet/fleet/site_stations.hpp"
#include "fleet/traffic/roadmap.hpp"
#include "fleet/traffic/virtual_fleet.hpp"
#include "round3.hpp"
#include "run_fleet_bound.hpp"
#include "traffic_sim_view.hpp"

namespace fleet::ctl {

namespace {

/// The fleet bound of a virtual-fleet run: its drawn tasks in order, its robots' starts, the
/// roadmap's stations (dock, approach, first queue node and exit as it built them), disc and cruise, the
/// virtual fleet's dwell at pickup and drop-off.
nlohmann::json virtualFleetBound(const site::Site& site, const traffic::Roadmap& roadmap,
                                 const traffic::VirtualFleetResult& r, double dwell) {
  const auto& g = roadmap.graph;
  FleetBoundInput in;
  std::map<traffic::NodeId, std::string> names;
  for (const auto& s : roadmap.stations)
    names[s.dock] = s.name;
  in.stations = boundStations(roadmap);
  for (const auto& t : r.tasks)
    in.tasks.push_back(ListTask::transport(names[t.pickup], names[t.dropoff], dwell, dwell));
  for (const auto v : r.starts)
    in.starts.push_back(g.position(v));
  in.radius = roadmap.options.radius;
  in.cruise = roadmap.options.cruiseSpeed;
  const auto b = fleetBound(site.drivable(), in);
  if (!b)
    return {{"error", b.error().code + ": " + b.error().message}};
  return fleetBoundJson(*b, r.tasksPerHour, in.cruise, in.radius);
}

using WaitCauseSeconds = std::array<double, traffic::kWaitCauses.size()>;

/// "  waiting on robots, on what: ..." (wait_cause.hpp), shares of the fleet's waiting, most first.
std::string waitCausesLine(const WaitCauseSeconds& seconds) {
  static const std::map<traffic::WaitCause, const char*> kSaid = {
      {traffic::WaitCause::SameWay, "one driving the same way"},
      {traffic::WaitCause::HeadOn, "one driving head-on"},
      {traffic::WaitCause::Across, "one driving across"},
      {traffic::WaitCause::Standing, "one standing"},
      {traffic::WaitCause::Dwelling, "one dwelling"},
      {traffic::WaitCause::NoneNamed, "none named (the plan)"}};
  double total = 0.0;
  std::vector<std::pair<double, traffic::WaitCause>> v;
  for (const auto c : traffic::kWaitCauses) {
    total += seconds[static_cast<std::size_t>(c)];
    v.emplace_back(seconds[static_cast<std::size_t>(c)], c);
  }
  std::stable_sort(v.begin(), v.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  std::ostringstream os;
  os << "  waiting on robots, on what:";
  for (const auto& [sec, c] : v) {
    if (total > 0.0 && sec > 0.0)
      os << " " << kSaid.at(c) << " " << std::fixed << std::setprecision(0) << 100.0 * sec / total << " %;";
  }
  return os.str();
}

/// "  busiest queues (10 s each, ▁ 0 … █ 4): D-3 ▁▂▅█…; D-2 …": the two stations with the longest
/// mean queue, their queue over the run on one scale; empty when no station had a queue.
std::string busiestQueuesLine(const traffic::VirtualFleetResult& r) {
  std::vector<const traffic::VirtualFleetResult::StationLedger*> by;
  for (const auto& st : r.stations) {
    if (st.queueMean > 0.0 && !st.queueSeries.empty())
      by.push_back(&st);
  }
  if (by.empty())
    return "";
  std::stable_sort(by.begin(), by.end(),
                   [](const auto* a, const auto* b) { return a->queueMean > b->queueMean; });
  by.resize(std::min<std::size_t>(by.size(), 2));
  double top = 0.0;
  for (const auto* st : by)
    top = std::max(top, *std::max_element(st->queueSeries.begin(), st->queueSeries.end()));
  static const char* const kBars[] = {"\u2581", "\u2582", "\u2583", "\u2584",
                                      "\u2585", "\u2586", "\u2587", "\u2588"};
  std::ostringstream os;
  os << "  busiest queues (" << std::fixed << std::setprecision(0) << by.front()->seriesEvery << " s each, "
     << kBars[0] << " 0 \u2026 " << kBars[7] << " " << std::setprecision(1) << top << "):";
  for (const auto* st : by) {
    os << " " << st->name << " ";
    for (const double q : st->queueSeries) {
      const auto i = top > 0.0 ? static_cast<int>(std::lround(7.0 * q / top)) : 0;
      os << kBars[std::clamp(i, 0, 7)];
    }
    os << ";";
  }
  return os.str();
}

/// The fleet against lone robots as they drive here (docs/algorithms.md, "Fleet bound": against a
/// lone robot as it drives): one virtual robot runs the fleet's drawn list in order, chained, with
/// the same jitter, people and turns; robots × its rate is what the fleet would do if robots never
/// met. Its share of the fleet bound's ideal motion says what the robot model costs a lone robot.
nlohmann::json loneAsItDrives(traffic::Roadmap& roadmap, const traffic::VirtualFleetOptions& fleet,
                              const traffic::VirtualFleetResult& r, const nlohmann::json& bound) {
  if (r.tasks.empty())
    return {{"error", "the fleet drew no task"}};
  traffic::VirtualFleetOptions v = fleet;
  v.robots = 1;
  v.list = r.tasks;
  v.recordEvery = 0.0;
  // Three times the list's ideal-motion time (a lone robot takes 1.5 times it on the shipped sites)
  // and ten minutes: a robot that stalls costs a bounded run, not hours of simulated time.
  v.duration = 3.0 * bound.value("lone_chain_s", 3600.0 * static_cast<double>(r.tasks.size())) + 600.0;
  traffic::VirtualFleetResult lone;
  try {
    lone = traffic::runVirtualFleet(roadmap, v);
  } catch (const std::invalid_argument& e) {
    return {{"error", e.what()}};
  }
  if (lone.tasksDone < r.tasks.size()) {
    return {{"error", "the lone robot did " + std::to_string(lone.tasksDone) + " of the list's " +
                          std::to_string(r.tasks.size()) + " tasks in " + std::to_string(v.duration) + " s"}};
  }
  const double perH = lone.tasksPerHour;
  const double robotsPerH = perH * static_cast<double>(r.robots);
  const double ideal = bound.value("lone_rate_per_h", 0.0);
  return {{"tasks", r.tasks.size()},
          {"lone_s", round3(lone.duration)},
          {"lone_rate_per_h", round3(perH)},
          {"of_ideal_motion", ideal > 0.0 ? round3(perH / ideal) : 0.0},
          {"robots_rate_per_h", round3(robotsPerH)},
          {"fraction", robotsPerH > 0.0 ? round3(r.tasksPerHour / robotsPerH) : 0.0}};
}

std::string loneAsItDrivesLine(const nlohmann::json& l) {
  if (l.contains("error"))
    return "  against lone robots as they drive: " + l["error"].get<std::string>();
  char buf[240];
  std::snprintf(
      buf, sizeof buf,
      "  against lone robots as they drive: %.0f %% of robots x a lone robot's %.1f/h on this list as it "
      "drives here (%.0f %% of its ideal motion)",
      100.0 * l.value("fraction", 0.0), l.value("lone_rate_per_h", 0.0),
      100.0 * l.value("of_ideal_motion", 0.0));
  return buf;
}

std::vector<double> rounded(std::vector<double> v) {
  for (double& x : v)
    x = round3(x);
  return v;
}

/// Several seeds end with their means (text output): tasks done (mean ± sd), the shares of the
/// fleet bound and of lone robots as they drive, the robot-time ledger and the wait split, each
/// over all the seeds' robot time.
class SeedsSummary {
 public:
  void add(const traffic::VirtualFleetResult& r, const nlohmann::json& bound, const nlohmann::json& lone) {
    tasks_.push_back(static_cast<double>(r.tasksDone));
    perH_ += r.tasksPerHour;
    ofBound_ += bound.value("fraction_of_bound", 0.0);
    ofLone_ += lone.value("fraction", 0.0);
    loneErrors_ += lone.contains("error") ? 1 : 0;
    for (const auto& l : r.robotTime)
      ledger_.add(l);
    for (std::size_t i = 0; i < causes_.size(); ++i)
      causes_[i] += r.waitCauses[i];
  }
  [[nodiscard]] std::string line() const {
    const auto n = static_cast<double>(tasks_.size());
    double mean = 0.0, var = 0.0;
    for (const double t : tasks_)
      mean += t / n;
    for (const double t : tasks_)
      var += (t - mean) * (t - mean) / n;
    std::ostringstream os;
    os << std::fixed << std::setprecision(1) << "over " << tasks_.size() << " seeds: " << mean << " ± "
       << std::sqrt(var) << " tasks (" << std::setprecision(0) << perH_ / n << "/h), " << 100.0 * ofBound_ / n
       << " % of the fleet bound, ";
    if (loneErrors_ == 0)
      os << 100.0 * ofLone_ / n << " % of lone robots as they drive\n";
    else
      os << "against lone robots as they drive: " << loneErrors_ << " seeds without a lone run\n";
    os << "  robot time:";
    for (const auto c : kLedgerActivities)
      os << " " << toString(c) << " " << 100.0 * ledger_.share(c) << " %";
    os << "\n" << waitCausesLine(causes_);
    return os.str();
  }

 private:
  std::vector<double> tasks_;
  double perH_ = 0.0, ofBound_ = 0.0, ofLone_ = 0.0;
  int loneErrors_ = 0;
  ActivityLedger ledger_;
  WaitCauseSeconds causes_{};
};

nlohmann::json robotTimeJson(const traffic::VirtualFleetResult& r) {
  ActivityLedger fleet;
  nlohmann::json per = nlohmann::json::array();
  for (const auto& l : r.robotTime) {
    fleet.add(l);
    nlohmann::json one = nlohmann::json::object();
    for (const auto c : kLedgerActivities)
      one[toString(c)] = std::round(l.share(c) * 1000.0) / 1000.0;
    per.push_back(one);
  }
  nlohmann::json all = nlohmann::json::object();
  for (const auto c : kLedgerActivities)
    all[toString(c)] = std::round(fleet.share(c) * 1000.0) / 1000.0;
  return {{"fleet", all}, {"per_robot", per}};
}

std::string robotTimeLine(const nlohmann::json& rt) {
  std::string line = "  robot time:";
  char buf[80];
  for (const auto c : kLedgerActivities) {
    std::snprintf(buf, sizeof buf, " %s %.0f %%", toString(c), 100.0 * rt["fleet"].value(toString(c), 0.0));
    line += buf;
  }
  return line;
}

// Driving per task against free flow (docs/algorithms.md, "Driving per task"): what the tasks drove,
// done and under way (per task: over the tasks they add up to), what the same tasks take with nobody
// in the way, and the share of the driving that brought the robot no nearer its goal.
nlohmann::json drivingPerTaskJson(const traffic::VirtualFleetResult& r) {
  const double n = r.taskShare > 0.0 ? r.taskShare : 1.0;
  return {{"driven_s", round3(r.taskDriven / n)},
          {"free_flow_s", round3(r.taskFreeFlow / n)},
          {"stretch", r.taskFreeFlow > 0.0 ? round3(r.taskDriven / r.taskFreeFlow) : 0.0},
          {"not_nearer_share", r.taskDriven > 0.0 ? round3(r.taskDrivenAway / r.taskDriven) : 0.0}};
}

std::string drivingPerTaskLine(const nlohmann::json& d) {
  char buf[200];
  std::snprintf(buf, sizeof buf,
                "driving per task: %.1f s, %.2f x its free flow (%.1f s), %.0f %% of it no nearer the goal",
                d.value("driven_s", 0.0), d.value("stretch", 0.0), d.value("free_flow_s", 0.0),
                100.0 * d.value("not_nearer_share", 0.0));
  return buf;
}

}  // namespace

int runTrafficSim(const TrafficSimOptions& o) {
  const auto core = traffic::plannerCoreFrom(o.core);
  if (!core) {
    std::cerr << "fleetctl traffic-sim: --core must be pibt or sipp, not '" << o.core << "'\n";
    return 2;
  }
  if (!std::isfinite(o.turnScale) || o.turnScale < 0.0) {
    std::cerr << "fleetctl traffic-sim: --turn-scale must be a number from 0 to 10\n";
    return 2;
  }
  const auto site = fleet::loadSiteFile(o.site);
  if (!site) {
    std::cerr << "fleetctl traffic-sim: " << site.error().message << "\n";
    return 2;
  }
  int first = 0;
  int last = 0;
  char dash = 0;
  const int n = std::sscanf(o.seeds.c_str(), "%d%c%d", &first, &dash, &last);
  if (n == 1) {
    last = first;
  }
  if ((n != 1 && (n != 3 || dash != '-')) || first < 0 || last < first) {
    std::cerr << "fleetctl traffic-sim: --seeds " << o.seeds << ": give a seed or a range like 1-8\n";
    return 2;
  }
  // A page that cannot be written is bad input: say so before a run that may take minutes.
  if (!o.html.empty() && !std::ofstream(o.html)) {
    std::cerr << "fleetctl traffic-sim: cannot write " << o.html << "\n";
    return 2;
  }
  traffic::RoadmapOptions ro;
  ro.spacing = o.spacing;
  if (o.queueLength >= 0)
    ro.queueLength = o.queueLength;
  if (o.stopGap >= 0.0)
    ro.stopGap = o.stopGap;
  if (o.guidance >= 0.0)
    ro.guidance = o.guidance;
  auto roadmap = traffic::buildRoadmap(*site, ro);
  for (const auto& name : o.stations) {
    const auto* st = roadmap.station(name);
    if (st == nullptr || (st->kind != site::StationKind::Pickup && st->kind != site::StationKind::Dropoff)) {
      std::cerr << "fleetctl traffic-sim: --stations: '" << name << "' is no pickup or drop-off of " << o.site
                << "\n";
      return 2;
    }
  }
  int rc = 0;
  nlohmann::json all = nlohmann::json::array();
  SeedsSummary summary;
  for (int seed = first; seed <= last; ++seed) {
    traffic::VirtualFleetOptions v;
    v.robots = static_cast<std::size_t>(o.robots);
    v.duration = o.duration;
    v.seed = static_cast<std::uint64_t>(seed);
    v.stopChance = o.stopChance;
    v.turnScale = o.turnScale;
    v.traffic.core = *core;
    v.stationLines = o.stationLines != 0;
    v.admission = static_cast<traffic::Admission>(o.admission);
    v.stationSlots = static_cast<std::size_t>(o.stationSlots);
    v.stations = o.stations;
    if (o.maxLag > 0)
      v.traffic.maxLag = o.maxLag;
    if (o.letPass >= 0)
      v.traffic.letPassBehind = o.letPass;
    if (o.straight >= 0) {
      v.traffic.pibt.preferStraight = o.straight != 0;
      v.traffic.pibt.tieTolerance = o.straight != 0 ? 1e-3F : 0.0F;
    }
    if (o.detourAfter >= 0)
      v.traffic.pibt.detourAfter = o.detourAfter;
    if (o.detourPenalty >= 0.0)
      v.traffic.pibt.detourPenalty = static_cast<float>(o.detourPenalty);
    if (o.occupiedCost >= 0.0)
      v.traffic.pibt.occupiedCost = static_cast<float>(o.occupiedCost);
    const bool record = !o.html.empty() && seed == first;
    if (record)
      v.recordEvery = 0.5;
    traffic::VirtualFleetResult r;
    try {
      r = traffic::runVirtualFleet(roadmap, v);
    } catch (const std::invalid_argument& e) {
      std::cerr << "fleetctl traffic-sim: " << e.what() << "\n";
      return 2;
    }
    if (r.contacts > 0 || r.holdViolations > 0)
      rc = 1;
    if (record) {
      std::ofstream out(o.html);
      out << trafficSimHtml(*site, roadmap, r,
                            "traffic-sim " + site->name + ", " + std::to_string(o.robots) + " robots, seed " +
                                std::to_string(seed));
      if (!out) {
        std::cerr << "fleetctl traffic-sim: cannot write " << o.html << "\n";
        return 2;
      }
    }
    const nlohmann::json bound = virtualFleetBound(*site, roadmap, r, v.dwell);
    const nlohmann::json lone = loneAsItDrives(roadmap, v, r, bound);
    const nlohmann::json robotTime = robotTimeJson(r);
    summary.add(r, bound, lone);
    nlohmann::json stations = nlohmann::json::array();
    for (const auto& st : r.stations) {
      stations.push_back({{"name", st.name},
                          {"visits", st.visits},
                          {"dock_cycles", st.cycles},
                          {"dock_cycle_p50_s", st.cycleP50},
                          {"dock_cycle_p90_s", st.cycleP90},
                          {"utilisation", st.utilisation},
                          {"queue_mean", st.queueMean},
                          {"queue_max", st.queueMax},
                          {"queue_every_s", st.seriesEvery},
                          {"queue_series", rounded(st.queueSeries)}});
    }
    nlohmann::json causes = nlohmann::json::object();
    for (const auto c : traffic::kWaitCauses)
      causes[traffic::toString(c)] = r.waitCauses[static_cast<std::size_t>(c)];
    const nlohmann::json driving = drivingPerTaskJson(r);
    nlohmann::json waits = nlohmann::json::array();
    for (const auto& w : r.waits)
      waits.push_back({{"place", w.place}, {"robot_s", w.seconds}});
    if (o.json) {
      all.push_back({{"seed", seed},
                     {"waits", waits},
                     {"wait_causes", causes},
                     {"fleet_bound", bound},
                     {"lone_as_it_drives", lone},
                     {"robot_time", robotTime},
                     {"driving_per_task", driving},
                     {"stations", stations},
                     {"robots", r.robots},
                     {"duration_s", r.duration},
                     {"tasks_done", r.tasksDone},
                     {"tasks_per_hour", r.tasksPerHour},
                     {"mean_task_s", r.meanTaskTime},
                     {"min_separation_m", r.minSeparation},
                     {"contacts", r.contacts},
                     {"hold_violations", r.holdViolations},
                     {"line_leaves", r.lineLeaves},
                     {"longest_wait_s", r.longestWait},
                     {"replans", r.replans},
                     {"evasions", r.evasions},
                     {"detours", r.detours},
                     {"escalations", r.escalations},
                     {"untangles", r.untangles},
                     {"passes", r.passes},
                     {"core", traffic::toString(*core)},
                     {"yields", r.yields},
                     {"refuges", r.refuges},
                     {"refused_moves", r.refusedMoves},
                     {"searches",
                      {{"count", r.search.searches},
                       {"failed", r.search.failures},
                       {"expanded", r.search.expanded},
                       {"goal_tables", r.search.heuristics}}},
                     {"line_scale", r.lineScale},
                     {"update_p99_ms", r.updateP99Ms},
                     {"density", r.density},
                     {"guidance",
                      {{"weight", roadmap.options.guidance},
                       {"contraflow_before", roadmap.guidance.contraflowBefore},
                       {"contraflow_after", roadmap.guidance.contraflowAfter},
                       {"route_time_ratio", roadmap.guidance.lengthRatio}}},
                     {"time_driving", r.driving},
                     {"time_dwelling", r.dwelling},
                     {"time_waiting_on_others", r.waitingOnOthers},
                     {"time_planned_to_stand", r.standingPlanned},
                     {"longest_wait_at", r.longestWaitAt},
                     {"stalls", r.stalls}});
    } else {
      std::cout << "seed " << seed << ": " << traffic::formatResult(r) << "\n";
      std::cout << "  " << fleetBoundLine(bound) << "\n"
                << loneAsItDrivesLine(lone) << "\n"
                << robotTimeLine(robotTime) << "\n";
      std::cout << "  " << drivingPerTaskLine(driving) << "\n";
      std::cout << "  stations:";
      for (const auto& st : r.stations) {
        std::cout << " " << st.name << " " << st.visits << " visits, " << std::fixed << std::setprecision(0)
                  << 100.0 * st.utilisation << " % docked, queue " << std::setprecision(1) << st.queueMean
                  << " / " << st.queueMax;
        if (st.cycles > 0)
          std::cout << ", dock cycle p50 " << std::fixed << std::setprecision(1) << st.cycleP50 << " / p90 "
                    << st.cycleP90 << " s (" << st.cycles << ")";
        std::cout << ";";
      }
      std::cout << "\n";
      double waited = 0.0;
      for (const auto& w : r.waits)
        waited += w.seconds;
      if (waited > 0.0) {
        std::cout << "  waiting on robots, where:";
        for (std::size_t i = 0; i < r.waits.size() && i < 8; ++i)
          std::cout << " " << r.waits[i].place << " " << std::setprecision(0)
                    << 100.0 * r.waits[i].seconds / waited << " %;";
        std::cout << "\n" << waitCausesLine(r.waitCauses) << "\n";
      }
      if (const std::string q = busiestQueuesLine(r); !q.empty())
        std::cout << q << "\n";
      if (!r.longestWaitAt.empty())
        std::cout << "  longest wait " << std::setprecision(1) << r.longestWait << " s: " << r.longestWaitAt
                  << "\n";
      for (const auto& s : r.stalls)
        std::cout << "  stalled: " << s << "\n";
    }
  }
  if (o.json)
    std::cout << all.dump(1) << "\n";
  else if (last > first)
    std::cout << summary.line() << "\n";
  return rc;
}

}  // namespace fleet::ctl
